// The time bases of an emulated IXXAT adapter (CANCAPABILITIES, VCI C++ guide 8.3.1-8.3.2) and
// the conversion between their ticks and simulated time. Every counter is a clock of `clock_hz`
// divided by its divisor: time stamps (tsc), the cyclic list (cms), transmit delays (dtx).
#pragma once

#include <cstdint>

#include "canemu/firmware_model/bus/bit_timing.hpp"

namespace canemu::model::ixxat {

struct Clocks {
  uint32_t clock_hz = 1'000'000;  // dwClockFreq; also the v2 time stamp, list and delay clocks
  uint32_t tsc_divisor = 1;       // time stamps count microseconds
  uint32_t cms_divisor = 1000;    // the cyclic list's tick: 1 ms
  uint32_t cms_max_ticks = 0xFFFF;
  uint32_t dtx_divisor = 1;  // transmit delays count microseconds
  uint32_t dtx_max_ticks = 0xFFFF;
};

// Nanoseconds from a counter's zero to its tick `count`, rounded up: the first instant at which
// the counter shows `count`. 128 bits: tick counts times clock rates overflow 64.
int64_t ticks_to_ns(uint128 count, uint32_t divisor, uint32_t clock_hz);
// The counter's value `ns` after its zero (0 before it).
uint64_t ns_to_ticks(int64_t ns, uint32_t divisor, uint32_t clock_hz);

}  // namespace canemu::model::ixxat
