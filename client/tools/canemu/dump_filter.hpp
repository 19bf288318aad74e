// canemu dump's bus arguments in candump's syntax, <bus>[,filter]*, and the filters as can-utils'
// candump sets them on a CAN_RAW socket and the Linux kernel applies them (af_can.c, raw.c):
//
//   <id>:<mask>   a frame matches when its can_id & mask == id & mask
//   <id>~<mask>   a frame matches when its can_id & mask != id & mask
//   #<mask>       error frames whose classes (CAN_ERR_* bits of can_id) meet the mask
//   j or J        join: a frame must match every filter rather than one of them
//
// Identifiers and masks are hex. can_id is the frame's identifier with CAN_EFF_FLAG (29-bit) and
// CAN_RTR_FLAG (remote) as linux/can.h sets them, so a mask may ask for them: an identifier of 8
// digits gets CAN_EFF_FLAG (candump's rule), and a mask with CAN_EFF_FLAG and an identifier
// without it match 11-bit frames only. The bus `any` stands for every CAN bus.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/ipc/socketcan.hpp"

namespace canemu::cli {

// linux/can.h, linux/can/error.h
inline constexpr uint32_t kInvFilter = 0x20000000;  // CAN_INV_FILTER, in a filter's can_id
inline constexpr uint32_t kErrMask = 0x1FFFFFFF;    // CAN_ERR_MASK: every error class

// One struct can_filter as the kernel keeps it: `id` already masked.
struct CanFilter {
  uint32_t id = 0;
  uint32_t mask = 0;
  bool inverted = false;
  std::string text;  // as given
  bool matches(uint32_t can_id) const { return ((can_id & mask) == id) != inverted; }
};

// One bus argument of canemu dump.
struct BusFilter {
  std::string text;                // the argument as given
  std::string bus;                 // a bus name, or "any"
  bool filtered = false;           // a filter list followed the name
  std::vector<CanFilter> filters;  // none: every frame (candump's 0:0)
  bool join = false;
  // Error frames shown: of these classes. Without a filter list every class (canemu dump's
  // default, --no-errors none); with one, what #<mask> gives (none without it, as in candump).
  uint32_t error_mask = kErrMask;

  // Whether a frame (an error frame by its classes) gets through.
  bool matches(const ipc::socketcan::Frame& f) const;
  // What gets through in words, for canemu dump's first lines: empty without a filter list.
  std::string describe() const;
};

// A bus argument: `can0`, `any`, `can0,123:7FF,400~700,#FFFFFFFF,j`. Nothing, with `error`
// set, when a filter is none of the four forms.
std::optional<BusFilter> parse_bus_filter(std::string_view arg, std::string& error);

// candump -l's file name for the local time `t` (seconds since the epoch):
// candump-YYYY-MM-DD_HHMMSS.log.
std::string candump_log_name(int64_t t);

}  // namespace canemu::cli
