// The control protocol's core (protocol.hpp gathers it all): the header, message types, error
// codes, names, and the messages of the daemon itself (status, time, channels, devices,
// clients, notifications, faults). Fixed-layout messages over an AF_UNIX SOCK_SEQPACKET
// socket, one message per packet, every one starting with MsgHeader.
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
inline constexpr uint16_t kProtocolVersion = 8;
inline constexpr std::size_t kMaxMessageSize = 16384;
inline constexpr std::size_t kNameSize = 32;
// A fault scenario's name: up to 63 bytes and the terminating zero.
inline constexpr std::size_t kScenarioNameSize = 64;
// Lists longer than one message come in pages: a request names the first entry it wants, the
// reply how many there are in all (StatusRequest, DeviceListRequest, ClientListRequest).
inline constexpr std::size_t kStatusPageBuses = 32;
inline constexpr std::size_t kStatusPageNodes = 192;
inline constexpr std::size_t kDevicePage = 64;
inline constexpr std::size_t kMaxDeviceControllers = 4;
inline constexpr std::size_t kClientPage = 64;
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
  recorder_list_request = 90,
  recorder_list_reply = 91,
  bridge_add_request = 92,
  bridge_add_reply = 93,
  bridge_remove_request = 94,
  bridge_remove_reply = 95,
  bridge_list_request = 96,
  bridge_list_reply = 97,
  bridge_restart_request = 98,
  bridge_restart_reply = 99,
  slcan_request = 100,
  slcan_reply = 101,
  slcan_event = 102,  // unsolicited, request_id 0
  lin_node_request = 110,
  lin_node_reply = 111,
  can_node_request = 112,
  can_node_reply = 113,
  peer_list_request = 120,
  peer_list_reply = 121,
  timeline_request = 160,
  timeline_reply = 161,
  load_history_reply = 162,
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

// One page of the status: buses from first_bus on, nodes from first_node on (0, 0: the first
// page, which is all of it while there are at most kStatusPageBuses buses and kStatusPageNodes
// nodes).
struct StatusRequest {
  MsgHeader header;
  uint16_t first_bus = 0;
  uint16_t first_node = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(StatusRequest) == 24);

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
// A LIN controller's state in StatusNode.lin (it has no error counters).
enum class WireLinState : uint8_t { none = 0, offline = 1, online = 2 };
// Whether a CAN node's controller takes part in bus traffic (StatusNode.mode): `init` while it
// is in reset or initialization mode (an adapter no program has started, a stopped line, an
// SJA1000 in sleep), as the VCI's CAN_STATUS_ININIT says.
enum class WireNodeMode : uint8_t { running = 0, init = 1 };

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
  uint16_t bus = 0;           // index among all buses (not the page's)
  uint8_t state = 0;          // WireErrorState (CAN nodes)
  uint8_t lin = 0;            // WireLinState: 0 for a CAN node
  uint16_t tec = 0;
  uint16_t rec = 0;
  uint8_t mode = 0;  // WireNodeMode (CAN nodes)
  uint8_t reserved[7] = {};
  uint64_t frames_sent = 0;
  uint64_t frames_received = 0;
  uint64_t errors = 0;
};
static_assert(sizeof(StatusNode) == 72);

// How late things ran, in ns (real and scaled time; all zero in stepped time).
struct WirePacingFigures {
  uint64_t count = 0;
  int64_t p50_ns = 0;
  int64_t p99_ns = 0;
  int64_t max_ns = 0;
};
static_assert(sizeof(WirePacingFigures) == 32);

// canemud's own measure of its pacing (docs/daemon.md, "Pacing"): since start and over the
// last complete second.
struct WirePacing {
  WirePacingFigures events;  // every simulated event against its instant
  WirePacingFigures events_last;
  WirePacingFigures wakeups;  // the loop's timer wake-ups, after the spin, against the deadline
  WirePacingFigures wakeups_last;
  WirePacingFigures timer;  // the timerfd's firing against the instant it was armed for
  WirePacingFigures timer_last;
  int64_t spin_ns = 0;      // how early the timer is armed now
  int64_t max_spin_ns = 0;  // simulation.spin_us
};
static_assert(sizeof(WirePacing) == 6 * 32 + 16);

struct StatusReply {
  MsgHeader header;
  int64_t sim_time_ns = 0;
  double time_scale = 1.0;
  uint8_t time_mode = 0;  // WireTimeMode
  uint8_t reserved = 0;
  uint16_t bus_count = 0;   // in this page
  uint16_t node_count = 0;  // in this page
  uint16_t client_count = 0;
  uint16_t first_bus = 0;  // index of buses[0] among all buses (the request's)
  uint16_t first_node = 0;
  uint16_t bus_total = 0;  // buses and nodes that exist
  uint16_t node_total = 0;
  // Changes whenever a node comes or goes (DeviceListReply.generation): pages of different
  // generations do not fit together.
  uint32_t generation = 0;
  uint32_t reserved2 = 0;
  StatusBus buses[kStatusPageBuses];
  StatusNode nodes[kStatusPageNodes];
  uint64_t ring_bytes = 0;  // shared ring memory all clients' channels and FIFOs hold
  // Real and scaled time: how far simulated time is behind the configured mapping (0 while
  // canemud keeps up), and the scale achieved over the last second.
  int64_t lag_ns = 0;
  double achieved_scale = 0.0;
  WirePacing pacing;
};
static_assert(sizeof(StatusReply) ==
              16 + 40 + 64 * kStatusPageBuses + 72 * kStatusPageNodes + 8 + 16 + 208);
static_assert(sizeof(StatusReply) <= kMaxMessageSize);

struct TimeStepRequest {
  MsgHeader header;
  int64_t step_ns = 0;  // > 0
};
static_assert(sizeof(TimeStepRequest) == 24);

inline constexpr std::size_t kStepNoteSize = 160;
struct TimeStepReply {
  MsgHeader header;
  int64_t sim_time_ns = 0;  // after the step
  uint64_t events_run = 0;
  // Across hosts: the followers the step let go ("let go during the step: daemon b (why)"), or
  // empty. The step ran all the same.
  char note[kStepNoteSize] = {};
};
static_assert(sizeof(TimeStepReply) == 32 + kStepNoteSize);

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
  sorcus_x_can_2i = 3,
  sorcus_sl_cani = 4
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
    case WireDeviceModel::sorcus_sl_cani:
      return "sorcus-sl-cani";
  }
  return "?";
}

// DeviceEntry.controller_fd: what each controller is. IXXAT adapters list their CAN
// controllers first, then their LIN controllers.
enum class WireControllerKind : uint8_t { can = 0, can_fd = 1, lin = 2 };

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
  uint8_t controller_fd[kMaxDeviceControllers] = {};  // WireControllerKind
  uint32_t reserved2 = 0;
  int64_t epoch_ns = 0;  // VCI devices: simulated time of power-on (their time stamps' zero)
};
static_assert(sizeof(DeviceEntry) == 40 + 32 * kMaxDeviceControllers + 40);

// One page of the device list: devices from `first` on.
struct DeviceListRequest {
  MsgHeader header;
  uint16_t first = 0;
  uint16_t reserved = 0;
  uint32_t reserved2 = 0;
};
static_assert(sizeof(DeviceListRequest) == 24);

struct DeviceListReply {
  MsgHeader header;
  uint32_t generation = 0;  // changes whenever a device comes or goes
  uint16_t count = 0;       // in this page, at most kDevicePage
  uint16_t total = 0;       // devices that exist
  uint16_t first = 0;       // index of devices[0] among all (the request's)
  uint16_t reserved = 0;
  uint32_t reserved2 = 0;
  DeviceEntry devices[kDevicePage];
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

// One page of the client list: clients from `first` on.
struct ClientListRequest {
  MsgHeader header;
  uint16_t first = 0;
  uint16_t reserved = 0;
  uint32_t reserved2 = 0;
};
static_assert(sizeof(ClientListRequest) == 24);

struct ClientListReply {
  MsgHeader header;
  uint16_t count = 0;  // in this page, at most kClientPage
  uint16_t total = 0;  // clients connected
  uint16_t first = 0;  // index of clients[0] among all (the request's)
  uint16_t reserved = 0;
  ClientEntry clients[kClientPage];
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

struct Notification {
  MsgHeader header;
  uint32_t kind = 0;        // NotificationKind
  uint32_t generation = 0;  // of the device list after the change
  char device[kNameSize] = {};
};
static_assert(sizeof(Notification) == 16 + 8 + 32);

}  // namespace canemu::ipc
