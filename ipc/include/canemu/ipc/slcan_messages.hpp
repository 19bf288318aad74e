// The messages of the SORCUS SL-CANi personality (part of the control protocol: protocol.hpp
// gathers it all).
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

// ---- SORCUS SL-CANi (the SL64_LIB functions) ----
//
// One request type carries every sl064_* function for one slot of a configured
// "sorcus-sl-cani" device (firmware_model adapters/sorcus/slcan_module.hpp). bib_startup gives
// the client every configured slot no other client holds (`value`: a bit per slot); the other
// operations need a slot the client holds (the EEPROM ones: or one nobody holds), else
// ErrorReply (no_such_channel). The reply's `ret` is the function's return value (0 or 42h) and
// `diagnosis` what sl064_get_diagnosis would read now. Service routine calls and service requests
// come as SlcanEventMsg to the client holding the slot, in the order the model made them.
enum class SlcanOp : uint16_t {
  bib_startup = 1,        // reply: `value` = slots held (bit n = slot n)
  config_module = 2,      // task, func: the error service routine
  config_msg_object = 3,  // value = id, flags, task, func; reply: handle
  clear_configuration = 4,
  start_com = 5,
  stop_com = 6,
  get_diagnosis = 7,         // reply: value
  set_data = 8,              // handle, size, data
  get_data = 9,              // handle, size (wanted); reply: size, data
  send_data = 10,            // handle
  send_data_request = 11,    // handle
  clear_msg = 12,            // handle
  set_acceptance_mask = 13,  // value = mask, flags = usage, task, func; reply: value = mask
  get_id = 14,               // handle, flags (kSlcanGetIdOfCall), value; reply: value
  get_msg_count = 15,        // handle; reply: value
  set_led = 16,              // value
  get_led = 17,              // reply: value
  evaluate_srq = 18,         // reply: ret (0, 1, 2), handle
  enable_int_mask = 19,
  end_of_srq = 20,
  install_routine = 21,  // task, func: the client has a function for them
  remove_routine = 22,   // task, func
  eeprom_read = 23,      // reply: eeprom
  eeprom_write = 24,     // value = word, handle = the new value (persisted before the reply)
};

inline constexpr std::size_t kSlcanEepromWords = 64;

// SlcanRequest.flags of get_id with handle 0: the acceptance mask's routine asks for the frame
// its call was for; `value` is that call's SlcanEventMsg.status (the frame's ID). Without the
// flag, handle 0 reads the last unconfigured frame a call was made for.
inline constexpr uint16_t kSlcanGetIdOfCall = 1;

struct SlcanRequest {
  MsgHeader header;
  uint16_t op = 0;  // SlcanOp
  uint8_t slot = 0;
  uint8_t size = 0;
  uint16_t handle = 0;
  uint16_t flags = 0;
  uint16_t task = 0;
  uint16_t func = 0;
  uint32_t value = 0;
  uint8_t data[8] = {};
};
static_assert(sizeof(SlcanRequest) == 16 + 16 + 8);

struct SlcanReply {
  MsgHeader header;
  uint16_t ret = 0;
  uint16_t diagnosis = 0;
  uint16_t handle = 0;
  uint8_t size = 0;
  uint8_t reserved = 0;
  uint32_t value = 0;
  uint32_t reserved2 = 0;
  int64_t sim_time_ns = 0;
  uint8_t data[8] = {};
  uint16_t eeprom[kSlcanEepromWords] = {};
};
static_assert(sizeof(SlcanReply) == 16 + 16 + 8 + 8 + 128);

// SlcanEventMsg.kind
enum class SlcanEventKind : uint8_t { message = 0, error = 1, service_request = 2 };

struct SlcanEventMsg {
  MsgHeader header;
  uint8_t kind = 0;  // SlcanEventKind
  uint8_t slot = 0;
  uint16_t task = 0;
  uint16_t func = 0;
  uint16_t handle = 0;
  // error: 1 heavily disturbed, 2 bus-off; message with handle 0 (the acceptance mask's
  // routine): the unconfigured frame's identifier, e.g. 0x123 or 0x18DAF110 (29 bits).
  uint32_t status = 0;
  uint16_t word = 0;  // service_request: 80h | slot << 8
  uint16_t reserved = 0;
  int64_t sim_time_ns = 0;
};
static_assert(sizeof(SlcanEventMsg) == 16 + 16 + 8);

}  // namespace canemu::ipc
