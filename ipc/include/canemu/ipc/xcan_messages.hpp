// The messages of the SORCUS X-CAN-2i personality (part of the control protocol: protocol.hpp
// gathers it all).
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

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

}  // namespace canemu::ipc
