// The messages of the IXXAT VCI personality (part of the control protocol: protocol.hpp gathers it
// all).
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

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
  // LIN (an IXXAT adapter's LIN controller, firmware_model adapters/ixxat/lin_line.hpp):
  // `controller` is its bus number, after the adapter's CAN controllers.
  lin_control_open = 70,
  lin_monitor_open = 71,  // flags: kVciExclusive
  // On any LIN handle, or (handle 0) on device + controller: LINCAPABILITIES at kVciCapsOffset,
  // LINLINESTATUS at kVciLineOffset.
  lin_info = 72,
  lin_init = 73,  // args: bOpMode, wBitrate (LININITLINE)
  lin_reset = 74,
  lin_start = 75,
  lin_stop = 76,
  lin_write = 77,  // args[0]: 1 send, 0 response table; payload: LINMSG
  // args[0]: receive FIFO capacity (1..65535); reply as channel_init (values: rx capacity, 0,
  // element size 16; kChannelFdCount descriptors, the transmit ring unused).
  lin_monitor_init = 78,
  lin_monitor_activate = 79,
  lin_monitor_deactivate = 80,
  // values: initialized, activated, rx_overrun; payload: VciChannelCounters (received, lost).
  lin_monitor_status = 81,
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

}  // namespace canemu::ipc
