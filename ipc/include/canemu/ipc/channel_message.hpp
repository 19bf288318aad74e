// One element of a channel's rings: a CAN frame or an event, with its exact simulated instant.
// The receive ring carries frames and (when asked for) transmit confirmations, bus errors and
// state changes; the transmit ring carries frames to send. Fixed layout, part of the ABI.
#pragma once

#include <cstdint>

namespace canemu::ipc {

enum class ChannelMessageKind : uint8_t {
  frame = 0,       // a frame (received, or to send)
  tx_done = 1,     // an own frame went out (kChannelReportTx)
  tx_dropped = 2,  // an own frame was given up (single shot after an error or lost arbitration,
                   // or a tx ring element that is not a valid frame)
  bus_error = 3,   // an error the node detected (kChannelReportErrors)
  state = 4,       // the node's error state changed (kChannelReportErrors)
};

// ChannelMessage.flags
inline constexpr uint8_t kMsgExtended = 0x01;
inline constexpr uint8_t kMsgRemote = 0x02;
inline constexpr uint8_t kMsgFd = 0x04;
inline constexpr uint8_t kMsgBrs = 0x08;
inline constexpr uint8_t kMsgEsi = 0x10;
inline constexpr uint8_t kMsgOwn = 0x20;            // received: the node's own frame
inline constexpr uint8_t kMsgSingleShot = 0x40;     // to send: no retransmission
inline constexpr uint8_t kMsgSelfReception = 0x80;  // to send: receive it too when it succeeds

struct ChannelMessage {
  int64_t timestamp_ns = 0;  // simulated time: end of EOF for frames, the error bit for errors
  uint32_t id = 0;
  uint8_t kind = 0;  // ChannelMessageKind
  uint8_t flags = 0;
  uint8_t dlc = 0;  // 0..15; the data bytes follow from it (classic 9..15 mean 8; none if remote)
  uint8_t error_type = 0;  // bus_error: model CanErrorType (bit, stuff, form, crc, ack)
  uint8_t error_role = 0;  // bus_error: model ErrorRole (0 transmitter, 1 receiver)
  uint8_t state = 0;       // bus_error and state: WireErrorState after the event
  uint16_t tec = 0;        // bus_error and state: counters after the event
  uint16_t rec = 0;
  uint16_t error_bit = 0;      // bus_error: frame bit (SOF = 0, stuff bits counted)
  uint32_t lost_before = 0;    // messages lost just before this one because the ring was full
  uint8_t error_location = 0;  // bus_error: where, as SJA1000 ECC segment / CAN_ERR_PROT_LOC_*
  uint8_t reserved[3] = {};
  uint8_t data[64] = {};
};
static_assert(sizeof(ChannelMessage) == 96);

}  // namespace canemu::ipc
