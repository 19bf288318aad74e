// The control protocol between canemud and its clients: fixed-layout messages over an AF_UNIX
// SOCK_SEQPACKET socket, one message per packet, every one starting with MsgHeader.
//
// Layouts are part of the ABI: sizes are checked with static_assert, integers are the host's
// (both ends are on one machine), strings are NUL-padded fixed arrays. A client says Hello
// first; the daemon answers HelloReply or ErrorReply. Every other request gets its reply type or
// ErrorReply with the same request_id.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>

#include "canemu/ipc/channel_message.hpp"

namespace canemu::ipc {

inline constexpr uint32_t kMagic = 0x454E4143;  // "CANE" in memory on little-endian machines
inline constexpr uint16_t kProtocolVersion = 2;
inline constexpr std::size_t kMaxMessageSize = 16384;
inline constexpr std::size_t kNameSize = 32;
// A fault scenario's name: up to 63 bytes and the terminating zero.
inline constexpr std::size_t kScenarioNameSize = 64;
inline constexpr std::size_t kMaxStatusBuses = 16;
inline constexpr std::size_t kMaxStatusNodes = 128;
inline constexpr std::size_t kMaxDevices = 64;
inline constexpr std::size_t kMaxDeviceControllers = 4;
inline constexpr std::size_t kMaxClients = 64;
// Descriptors that come with an OpenChannelReply, in this order.
inline constexpr std::size_t kChannelFdCount = 5;
// Descriptors that come with a VCI FIFO (VciOp::fifo_create / fifo_access), in this order: the
// ring's memory, the reader's eventfd, the writer's eventfd.
inline constexpr std::size_t kFifoFdCount = 3;

enum class MsgType : uint16_t {
  hello = 1,
  hello_reply = 2,
  error_reply = 3,
  status_request = 10,
  status_reply = 11,
  time_step_request = 20,
  time_step_reply = 21,
  open_channel_request = 30,
  open_channel_reply = 31,
  close_channel_request = 32,
  close_channel_reply = 33,
  channel_status_request = 34,
  channel_status_reply = 35,
  device_list_request = 40,
  device_list_reply = 41,
  client_list_request = 42,
  client_list_reply = 43,
  subscribe_request = 50,
  subscribe_reply = 51,
  notification = 52,  // unsolicited, request_id 0
  fault_load_request = 60,
  fault_load_reply = 61,
  fault_list_request = 62,
  fault_list_reply = 63,
  fault_clear_request = 64,
  fault_clear_reply = 65,
  vci_request = 70,
  vci_reply = 71,
  xcan_request = 80,
  xcan_reply = 81,
  xcan_callback = 82,  // unsolicited, request_id 0
};

// Why a request failed. Values are stable: clients show them by name.
enum class ErrorCode : uint32_t {
  none = 0,
  bad_magic = 1,
  bad_version = 2,
  bad_size = 3,
  unknown_type = 4,
  not_hello = 5,    // a request before the handshake
  not_stepped = 6,  // time step outside stepped mode
  bad_argument = 7,
  permission_denied = 8,
  no_such_bus = 9,
  no_such_channel = 10,
  name_in_use = 11,
  bad_bit_timing = 12,
  no_resources = 13,
  bad_scenario = 14,
};
std::string_view to_string(ErrorCode code);

struct MsgHeader {
  uint32_t magic = kMagic;
  uint16_t version = kProtocolVersion;
  uint16_t type = 0;
  uint32_t size = 0;        // of the whole message, header included
  uint32_t request_id = 0;  // echoed in the reply
};
static_assert(sizeof(MsgHeader) == 16);

struct Hello {
  MsgHeader header;
  uint32_t client_pid = 0;
  char client_name[kNameSize] = {};
};
static_assert(sizeof(Hello) == 52);

struct HelloReply {
  MsgHeader header;
  uint32_t server_pid = 0;
  uint16_t server_version = kProtocolVersion;
  uint16_t reserved = 0;
};
static_assert(sizeof(HelloReply) == 24);

struct ErrorReply {
  MsgHeader header;
  uint32_t code = 0;  // ErrorCode
  char message[96] = {};
};
static_assert(sizeof(ErrorReply) == 116);

struct StatusRequest {
  MsgHeader header;
};

enum class WireTimeMode : uint8_t { realtime = 0, scaled = 1, stepped = 2 };
enum class WireBusKind : uint8_t { can = 0, can_fd = 1, lin = 2 };

// Names as configuration files and `canemu status` write them; "?" for a value that is none.
constexpr std::string_view to_string(WireTimeMode mode) {
  switch (mode) {
    case WireTimeMode::realtime:
      return "realtime";
    case WireTimeMode::scaled:
      return "scaled";
    case WireTimeMode::stepped:
      return "stepped";
  }
  return "?";
}
constexpr std::string_view to_string(WireBusKind kind) {
  switch (kind) {
    case WireBusKind::can:
      return "can";
    case WireBusKind::can_fd:
      return "can-fd";
    case WireBusKind::lin:
      return "lin";
  }
  return "?";
}
enum class WireErrorState : uint8_t { active = 0, warning = 1, passive = 2, bus_off = 3 };

struct StatusBus {
  char name[kNameSize] = {};
  uint8_t kind = 0;       // WireBusKind
  uint8_t low_speed = 0;  // 1: ISO 11898-3 low-speed transceivers
  uint8_t reserved[2] = {};
  uint32_t bitrate = 0;
  uint32_t data_bitrate = 0;
  uint32_t load_permille = 0;  // over the last second
  uint64_t frames = 0;
  uint64_t error_frames = 0;
};
static_assert(sizeof(StatusBus) == 64);

struct StatusNode {
  char name[kNameSize] = {};  // "device:N"
  uint16_t bus = 0;           // index into the reply's buses
  uint8_t state = 0;          // WireErrorState
  uint8_t reserved = 0;
  uint16_t tec = 0;
  uint16_t rec = 0;
  uint64_t frames_sent = 0;
  uint64_t frames_received = 0;
  uint64_t errors = 0;
};
static_assert(sizeof(StatusNode) == 64);

struct StatusReply {
  MsgHeader header;
  int64_t sim_time_ns = 0;
  double time_scale = 1.0;
  uint8_t time_mode = 0;  // WireTimeMode
  uint8_t reserved = 0;
  uint16_t bus_count = 0;
  uint16_t node_count = 0;
  uint16_t client_count = 0;
  StatusBus buses[kMaxStatusBuses];
  StatusNode nodes[kMaxStatusNodes];
};
static_assert(sizeof(StatusReply) == 16 + 24 + 64 * kMaxStatusBuses + 64 * kMaxStatusNodes);
static_assert(sizeof(StatusReply) <= kMaxMessageSize);

struct TimeStepRequest {
  MsgHeader header;
  int64_t step_ns = 0;  // > 0
};
static_assert(sizeof(TimeStepRequest) == 24);

struct TimeStepReply {
  MsgHeader header;
  int64_t sim_time_ns = 0;  // after the step
  uint64_t events_run = 0;
};
static_assert(sizeof(TimeStepReply) == 32);

// ---- channels (the data plane) ----

// OpenChannelRequest.flags
inline constexpr uint16_t kChannelListenOnly = 0x0001;    // never drives the bus (no ACK)
inline constexpr uint16_t kChannelReportTx = 0x0002;      // tx_done / tx_dropped messages
inline constexpr uint16_t kChannelReportErrors = 0x0004;  // error and state messages

// Asks for an ephemeral device: one node on the bus `bus` (an SJA1000 on a classic CAN bus, the
// CAN FD controller on a CAN FD bus), alive while this client is connected (or until
// CloseChannelRequest). The reply carries kChannelFdCount descriptors:
// rx ring memory, tx ring memory, the rx reader's eventfd (the client waits on it), the tx
// writer's eventfd (the client waits on it for room), the tx reader's eventfd (the daemon's
// doorbell, written by the client's ring writer).
struct OpenChannelRequest {
  MsgHeader header;
  char bus[kNameSize] = {};
  char device[kNameSize] = {};  // name of the ephemeral device; empty: the daemon picks one
  uint32_t bitrate = 0;         // 0: the bus's rate
  uint16_t sample_point = 0;    // per mille; 0: the bus's
  uint16_t flags = 0;
  uint32_t rx_capacity = 0;   // elements; 0: 1024
  uint32_t tx_capacity = 0;   // elements; 0: 256
  uint32_t restart_ms = 0;    // restart after bus-off after this long; 0: stay bus-off
  uint32_t data_bitrate = 0;  // CAN FD buses: data-phase bit/s; 0: the bus's
};
static_assert(sizeof(OpenChannelRequest) == 16 + 64 + 24);

struct OpenChannelReply {
  MsgHeader header;
  uint32_t channel = 0;
  uint32_t rx_capacity = 0;
  uint32_t tx_capacity = 0;
  uint32_t element_size = 0;
  char device[kNameSize] = {};
  uint32_t bitrate = 0;
  uint16_t sample_point = 0;
  uint8_t btr0 = 0;  // SJA1000 nodes: the register values
  uint8_t btr1 = 0;
  uint32_t data_bitrate = 0;  // CAN FD nodes: the data-phase rate
  uint8_t fd_capable = 0;
  uint8_t reserved[3] = {};
};
static_assert(sizeof(OpenChannelReply) == 16 + 16 + 32 + 16);

struct CloseChannelRequest {
  MsgHeader header;
  uint32_t channel = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(CloseChannelRequest) == 24);

struct CloseChannelReply {
  MsgHeader header;
  uint32_t channel = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(CloseChannelReply) == 24);

struct ChannelStatusRequest {
  MsgHeader header;
  uint32_t channel = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(ChannelStatusRequest) == 24);

struct ChannelStatusReply {
  MsgHeader header;
  uint32_t channel = 0;
  uint8_t state = 0;  // WireErrorState
  uint8_t transmitting = 0;
  uint16_t reserved = 0;
  uint16_t tec = 0;
  uint16_t rec = 0;
  uint32_t rx_fill = 0;
  uint64_t frames_sent = 0;
  uint64_t frames_received = 0;
  uint64_t rx_lost = 0;      // messages the rx ring had no room for
  uint64_t tx_rejected = 0;  // tx ring elements that were not valid frames
  uint64_t errors = 0;
  int64_t sim_time_ns = 0;
};
static_assert(sizeof(ChannelStatusReply) == 16 + 16 + 48);

// ---- devices, clients, notifications ----

enum class WireDeviceModel : uint8_t {
  ixxat_usb_to_can = 0,
  ixxat_usb_to_can_fd = 1,
  ephemeral = 2,
  sorcus_x_can_2i = 3
};

// A device model's name: the `model` key of a configuration's [[device]], and what
// `canemu status` shows; "?" for a value that is none of them.
constexpr std::string_view to_string(WireDeviceModel model) {
  switch (model) {
    case WireDeviceModel::ixxat_usb_to_can:
      return "ixxat-usb-to-can";
    case WireDeviceModel::ixxat_usb_to_can_fd:
      return "ixxat-usb-to-can-fd";
    case WireDeviceModel::ephemeral:
      return "ephemeral";
    case WireDeviceModel::sorcus_x_can_2i:
      return "sorcus-x-can-2i";
  }
  return "?";
}

struct DeviceEntry {
  char name[kNameSize] = {};
  uint8_t model = 0;  // WireDeviceModel
  uint8_t controller_count = 0;
  uint8_t ephemeral = 0;
  uint8_t reserved = 0;
  uint32_t owner_pid = 0;                             // ephemeral devices: the client's pid
  char buses[kMaxDeviceControllers][kNameSize] = {};  // bus of each controller
  uint64_t vci_id = 0;        // VCI devices: VciObjectId, unique while the daemon runs
  char hardware_id[16] = {};  // VCI devices: "HW" and a serial number, stable across runs
  uint8_t controller_fd[kMaxDeviceControllers] = {};  // 1: a CAN FD controller
  uint32_t reserved2 = 0;
  int64_t epoch_ns = 0;  // VCI devices: simulated time of power-on (their time stamps' zero)
};
static_assert(sizeof(DeviceEntry) == 40 + 32 * kMaxDeviceControllers + 40);

struct DeviceListRequest {
  MsgHeader header;
};

struct DeviceListReply {
  MsgHeader header;
  uint32_t generation = 0;  // changes whenever a device comes or goes
  uint16_t count = 0;
  uint16_t total = 0;  // devices that exist (count is capped at kMaxDevices)
  DeviceEntry devices[kMaxDevices];
};
static_assert(sizeof(DeviceListReply) <= kMaxMessageSize);

struct ClientEntry {
  char name[kNameSize] = {};
  uint32_t pid = 0;
  uint32_t uid = 0;
  uint32_t channels = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(ClientEntry) == 48);

struct ClientListRequest {
  MsgHeader header;
};

struct ClientListReply {
  MsgHeader header;
  uint16_t count = 0;
  uint16_t total = 0;
  uint32_t reserved = 0;
  ClientEntry clients[kMaxClients];
};
static_assert(sizeof(ClientListReply) <= kMaxMessageSize);

// SubscribeRequest.events
inline constexpr uint32_t kEventDevices = 0x0001;  // devices added or removed

struct SubscribeRequest {
  MsgHeader header;
  uint32_t events = 0;  // replaces the earlier subscription
  uint32_t reserved = 0;
};
static_assert(sizeof(SubscribeRequest) == 24);

struct SubscribeReply {
  MsgHeader header;
  uint32_t events = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(SubscribeReply) == 24);

enum class NotificationKind : uint32_t { device_added = 1, device_removed = 2 };

// ---- fault scenarios (docs/faults.md) ----

inline constexpr std::size_t kMaxScenarioText = 12288;
inline constexpr std::size_t kMaxFaults = 64;

// A scenario's text (not a path: the daemon never reads files on a client's behalf), applied
// from the simulated time the request is handled.
struct FaultLoadRequest {
  MsgHeader header;
  char source[64] = {};  // shown in errors, e.g. the client's file name
  uint32_t length = 0;   // bytes of `text` used
  uint32_t reserved = 0;
  char text[kMaxScenarioText] = {};
};
static_assert(sizeof(FaultLoadRequest) == 16 + 72 + kMaxScenarioText);

struct FaultLoadReply {
  MsgHeader header;
  uint32_t applied = 0;  // 1: applied; 0: rejected, see `errors`
  uint32_t faults = 0;
  char name[kScenarioNameSize] = {};
  char errors[4096] = {};  // one problem per line, with the line of the scenario text
};
static_assert(sizeof(FaultLoadReply) == 16 + 8 + kScenarioNameSize + 4096);

enum class WireFaultState : uint8_t { pending = 0, active = 1, done = 2, cleared = 3 };

// A fault's state as `canemu fault list` shows it; "?" for a value that is none.
constexpr std::string_view to_string(WireFaultState state) {
  switch (state) {
    case WireFaultState::pending:
      return "pending";
    case WireFaultState::active:
      return "active";
    case WireFaultState::done:
      return "done";
    case WireFaultState::cleared:
      return "cleared";
  }
  return "?";
}

struct FaultEntry {
  char scenario[kScenarioNameSize] = {};
  char effect[24] = {};
  char target[kNameSize] = {};  // bus or node
  uint32_t line = 0;
  uint8_t state = 0;  // WireFaultState
  uint8_t has_until = 0;
  uint16_t reserved = 0;
  int64_t at_ns = 0;
  int64_t until_ns = 0;
  uint64_t seen = 0;
  uint64_t hits = 0;
};
static_assert(sizeof(FaultEntry) == kScenarioNameSize + 24 + 32 + 8 + 32);

struct FaultListRequest {
  MsgHeader header;
};

struct FaultListReply {
  MsgHeader header;
  uint16_t count = 0;
  uint16_t total = 0;
  uint32_t reserved = 0;
  FaultEntry faults[kMaxFaults];
};
static_assert(sizeof(FaultListReply) <= kMaxMessageSize);

struct FaultClearRequest {
  MsgHeader header;
  char scenario[kScenarioNameSize] = {};  // empty: every scenario
};
static_assert(sizeof(FaultClearRequest) == 16 + kScenarioNameSize);

struct FaultClearReply {
  MsgHeader header;
  uint32_t cleared = 0;  // scenarios
  uint32_t reserved = 0;
};
static_assert(sizeof(FaultClearReply) == 24);

struct Notification {
  MsgHeader header;
  uint32_t kind = 0;        // NotificationKind
  uint32_t generation = 0;  // of the device list after the change
  char device[kNameSize] = {};
};
static_assert(sizeof(Notification) == 16 + 8 + 32);

// ---- VCI (the IXXAT personality) ----
//
// One request type carries every call of the VCI APIs that reaches the adapter firmware
// (firmware_model adapters/ixxat/can_line.hpp): opening the control unit, a channel or the cyclic
// list of a configured device's controller gives a handle (per connection); later calls name it.
// The reply's hresult is the VCI result (VCI_OK or a VCI_E_* code); protocol-level problems
// (a malformed request) get ErrorReply instead.
enum class VciOp : uint16_t {
  // On a controller (device + controller); the reply's handle is the new object.
  control_open = 1,
  channel_open = 2,  // flags: kVciV2, kVciExclusive
  scheduler_open = 3,
  // On any handle of a controller, or (handle 0) on device + controller: capabilities and line
  // status (the kVci*Offset structs in the payload).
  line_info = 4,
  // Control unit.
  control_init = 10,  // payload: CANINITLINE2 layout; flags kVciV2 (else only the BTR/opmode)
  control_reset = 11,
  control_start = 12,
  control_stop = 13,
  control_filter = 14,    // args: kind, select, mode, code, mask; values[0]: mode
  controller_state = 15,  // values: error state (WireErrorState), tec, rec, line state
  // Bit-rate detection: payload CANBTRTABLE (or, kVciV2, CANBTPTABLE); args: timeout ms per
  // entry, v2 operating mode, v2 extended mode. Starts it (VCI_OK) or refuses; the result
  // comes from control_detect_result: VCI_E_PENDING while it runs, then VCI_OK with the index
  // in values[0], or VCI_E_TIMEOUT.
  control_detect = 16,
  control_detect_result = 17,
  // Channels.
  channel_init = 20,  // args: rx, tx capacity, ext list size, filter mode; reply: 5 descriptors
  channel_activate = 21,
  channel_deactivate = 22,
  channel_status = 23,  // values: initialized, activated, rx_overrun; payload: VciChannelCounters
  channel_filter = 24,  // as control_filter
  // Cyclic transmit list.
  scheduler_resume = 30,
  scheduler_suspend = 31,
  scheduler_reset = 32,
  scheduler_add = 33,     // payload: CANCYCLICTXMSG2 layout; values[0]: index
  scheduler_remove = 34,  // args[0]: index
  scheduler_start = 35,   // args[0]: index, args[1]: count
  scheduler_stop = 36,    // args[0]: index
  scheduler_status = 37,  // payload: task state then 16 entry states
  // Closing any handle.
  close = 40,
  // An ephemeral VCI adapter (one controller) on the bus named in the payload's first 32
  // bytes, named `device` (empty: the daemon picks), alive while this connection is or until
  // device_remove; the reply has its VciObjectId in values[0] (low) and values[1] (high) and
  // its name in the payload.
  device_create = 50,
  device_remove = 51,  // `device`: one this connection created
  // Stand-alone FIFOs (VciCreateFifo / VciAccessFifo), shared by processes through canemud.
  // fifo_create: args capacity, element size; fifo_access: args id (low, high). Both reply
  // with the id in values[0..1], capacity and element size in values[2..3], and 3 descriptors:
  // the ring, the reader's eventfd, the writer's eventfd. The FIFO lives while a connection
  // holds it. fifo_side: args id (low, high), side (0 reader, 1 writer), 1 take / 0 give back;
  // VCI_E_ACCESSDENIED when another holder has that side.
  fifo_create = 60,
  fifo_access = 61,
  fifo_side = 62,
};

// VciRequest.flags
inline constexpr uint16_t kVciV2 = 0x0001;
inline constexpr uint16_t kVciExclusive = 0x0002;

inline constexpr std::size_t kVciPayloadSize = 192;
inline constexpr std::size_t kVciRequestPayloadSize = 2056;  // a CANBTPTABLE fits

struct VciRequest {
  MsgHeader header;
  uint16_t op = 0;  // VciOp
  uint16_t flags = 0;
  uint32_t handle = 0;
  char device[kNameSize] = {};  // the open operations
  uint32_t controller = 0;
  uint32_t args[7] = {};
  uint8_t payload[kVciRequestPayloadSize] = {};
};
static_assert(sizeof(VciRequest) == 16 + 8 + 32 + 32 + kVciRequestPayloadSize);

struct VciReply {
  MsgHeader header;
  int32_t hresult = 0;
  uint32_t handle = 0;
  uint32_t values[6] = {};
  uint8_t payload[kVciPayloadSize] = {};
};
static_assert(sizeof(VciReply) == 16 + 8 + 24 + kVciPayloadSize);

// The payload of a line_info reply: the vendor structs' bytes, each at its own offset.
inline constexpr std::size_t kVciCapsOffset = 0;     // CANCAPABILITIES (32 bytes)
inline constexpr std::size_t kVciCaps2Offset = 32;   // CANCAPABILITIES2 (108)
inline constexpr std::size_t kVciLineOffset = 140;   // CANLINESTATUS (8)
inline constexpr std::size_t kVciLine2Offset = 148;  // CANLINESTATUS2 (40)
static_assert(kVciLine2Offset + 40 <= kVciPayloadSize);

// The payload of a channel_status reply.
struct VciChannelCounters {
  uint64_t received = 0;
  uint64_t lost = 0;
  uint64_t sent = 0;
  uint64_t rejected = 0;
  uint64_t dropped = 0;
  uint64_t not_shown = 0;
};
static_assert(sizeof(VciChannelCounters) <= kVciPayloadSize);

// ---- SORCUS X-CAN-2i (the MDD's generic channel services) ----
//
// One request type carries every generic channel service of the X-CAN-2i module device driver
// (firmware_model adapters/sorcus/xcan_module.hpp) on a configured "sorcus-x-can-2i" device:
// xcan_open gives a channel handle (per connection), later services name it. The reply's
// `error` is the MDD's result (ERR_OK or an ERR_* of sorcus/xcan_types.h); a malformed request
// gets ErrorReply instead. A blocking service (a send with XCAN_NO_INT, an active receive read)
// is answered when the model completes it, in simulated time: replies can come in another
// order than their requests. Callbacks come as XcanCallbackMsg on the same socket, in the order
// the model made them.
enum class XcanOp : uint16_t {
  module_check = 1,  // `device`: is it an X-CAN-2i? (max_load_mdd)
  open = 2,          // `device`, `cps` (CPS_XCAN bytes); flags: kXcanCallback
  close = 3,
  write_block = 4,  // `size` bytes of `data`
  read_block = 5,   // reply: `size` bytes of `data`
  write_ulong = 6,  // `value`
  read_ulong = 7,   // reply: `value`
  control = 8,      // `value`: CMD_*
  info = 9,         // `value`: INFO_*; reply: `value`
  clear_error = 10,
};

// XcanRequest.flags (open): the client gave a callback function.
inline constexpr uint16_t kXcanCallback = 0x0001;
inline constexpr std::size_t kXcanDataSize = 16;  // an XCAN_BITPARAMS or XCAN_MESSAGE fits
inline constexpr std::size_t kXcanCpsSize = 16;   // sizeof(CPS_XCAN)

struct XcanRequest {
  MsgHeader header;
  uint16_t op = 0;  // XcanOp
  uint16_t flags = 0;
  uint32_t channel = 0;
  char device[kNameSize] = {};
  uint8_t cps[kXcanCpsSize] = {};
  uint32_t value = 0;
  uint16_t size = 0;
  uint16_t reserved = 0;
  uint8_t data[kXcanDataSize] = {};
};
static_assert(sizeof(XcanRequest) == 16 + 8 + 32 + 16 + 8 + 16);

struct XcanReply {
  MsgHeader header;
  uint32_t error = 0;  // ERR_OK or ERR_*
  uint32_t channel = 0;
  uint32_t value = 0;
  uint16_t size = 0;
  uint16_t reserved = 0;
  int64_t sim_time_ns = 0;  // when the service ended
  uint8_t data[kXcanDataSize] = {};
};
static_assert(sizeof(XcanReply) == 16 + 16 + 8 + 16);

// XcanCallbackMsg.arg: what the callback function gets (the digest's §1.7 table).
enum class XcanCallbackArg : uint8_t { none = 0, data = 1, status = 2, message = 3 };

struct XcanCallbackMsg {
  MsgHeader header;
  uint32_t channel = 0;
  uint8_t arg = 0;   // XcanCallbackArg
  uint8_t sync = 0;  // the channel has _CP_SYNC_CALLBACK
  uint8_t size = 0;  // data: valid bytes
  uint8_t reserved = 0;
  uint32_t status = 0;  // status: the bus state word
  uint32_t reserved2 = 0;
  int64_t sim_time_ns = 0;
  uint8_t data[kXcanDataSize] = {};  // data bytes, or the XCAN_MESSAGE
};
static_assert(sizeof(XcanCallbackMsg) == 16 + 16 + 8 + 16);

// The message type of each struct (and, in protocol.cpp, the size of each type).
template <class T>
inline constexpr MsgType type_of_v = MsgType{};
template <>
inline constexpr MsgType type_of_v<Hello> = MsgType::hello;
template <>
inline constexpr MsgType type_of_v<HelloReply> = MsgType::hello_reply;
template <>
inline constexpr MsgType type_of_v<ErrorReply> = MsgType::error_reply;
template <>
inline constexpr MsgType type_of_v<StatusRequest> = MsgType::status_request;
template <>
inline constexpr MsgType type_of_v<StatusReply> = MsgType::status_reply;
template <>
inline constexpr MsgType type_of_v<TimeStepRequest> = MsgType::time_step_request;
template <>
inline constexpr MsgType type_of_v<TimeStepReply> = MsgType::time_step_reply;
template <>
inline constexpr MsgType type_of_v<OpenChannelRequest> = MsgType::open_channel_request;
template <>
inline constexpr MsgType type_of_v<OpenChannelReply> = MsgType::open_channel_reply;
template <>
inline constexpr MsgType type_of_v<CloseChannelRequest> = MsgType::close_channel_request;
template <>
inline constexpr MsgType type_of_v<CloseChannelReply> = MsgType::close_channel_reply;
template <>
inline constexpr MsgType type_of_v<ChannelStatusRequest> = MsgType::channel_status_request;
template <>
inline constexpr MsgType type_of_v<ChannelStatusReply> = MsgType::channel_status_reply;
template <>
inline constexpr MsgType type_of_v<DeviceListRequest> = MsgType::device_list_request;
template <>
inline constexpr MsgType type_of_v<DeviceListReply> = MsgType::device_list_reply;
template <>
inline constexpr MsgType type_of_v<ClientListRequest> = MsgType::client_list_request;
template <>
inline constexpr MsgType type_of_v<ClientListReply> = MsgType::client_list_reply;
template <>
inline constexpr MsgType type_of_v<SubscribeRequest> = MsgType::subscribe_request;
template <>
inline constexpr MsgType type_of_v<SubscribeReply> = MsgType::subscribe_reply;
template <>
inline constexpr MsgType type_of_v<Notification> = MsgType::notification;
template <>
inline constexpr MsgType type_of_v<FaultLoadRequest> = MsgType::fault_load_request;
template <>
inline constexpr MsgType type_of_v<FaultLoadReply> = MsgType::fault_load_reply;
template <>
inline constexpr MsgType type_of_v<FaultListRequest> = MsgType::fault_list_request;
template <>
inline constexpr MsgType type_of_v<FaultListReply> = MsgType::fault_list_reply;
template <>
inline constexpr MsgType type_of_v<FaultClearRequest> = MsgType::fault_clear_request;
template <>
inline constexpr MsgType type_of_v<FaultClearReply> = MsgType::fault_clear_reply;
template <>
inline constexpr MsgType type_of_v<VciRequest> = MsgType::vci_request;
template <>
inline constexpr MsgType type_of_v<VciReply> = MsgType::vci_reply;
template <>
inline constexpr MsgType type_of_v<XcanRequest> = MsgType::xcan_request;
template <>
inline constexpr MsgType type_of_v<XcanReply> = MsgType::xcan_reply;
template <>
inline constexpr MsgType type_of_v<XcanCallbackMsg> = MsgType::xcan_callback;
template <class T>
constexpr MsgType type_of() {
  static_assert(type_of_v<T> != MsgType{}, "not a protocol message");
  return type_of_v<T>;
}

// A message of type T with its header filled in.
template <class T>
T make_message(uint32_t request_id = 0) {
  static_assert(std::is_trivially_copyable_v<T>);
  T m{};
  m.header.magic = kMagic;
  m.header.version = kProtocolVersion;
  m.header.type = static_cast<uint16_t>(type_of<T>());
  m.header.size = sizeof(T);
  m.header.request_id = request_id;
  return m;
}

// Checks a received packet's header: magic, version, the size it claims against the bytes that
// came and against the size of its type. ErrorCode::none when it may be read as its type.
ErrorCode check_message(const void* data, std::size_t bytes);

template <std::size_t N>
void copy_name(char (&dst)[N], std::string_view src) {
  const std::size_t n = src.size() < N - 1 ? src.size() : N - 1;
  std::memcpy(dst, src.data(), n);
  std::memset(dst + n, 0, N - n);
}

template <std::size_t N>
std::string name_of(const char (&src)[N]) {
  return std::string(src, strnlen(src, N));
}

}  // namespace canemu::ipc
