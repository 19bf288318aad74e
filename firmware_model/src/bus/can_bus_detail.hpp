// What the files of CanBus share (can_bus.cpp: arbitration, roles, frames that succeed;
// can_bus_nodes.cpp: what it keeps of its nodes, the member list among it; can_bus_errors.cpp:
// dominant holds and error phases; can_bus_states.cpp: error states and bus-off recovery).
#pragma once

#include "canemu/firmware_model/bus/can_bus.hpp"

namespace canemu::model::detail {

// Suspend transmission: the extra bits an error-passive transmitter waits after intermission.
inline constexpr uint32_t kSuspendBits = 8;

// A duration measured by a node whose oscillator runs `ppm` fast takes proportionally less time.
inline SimDuration with_ppm(SimDuration d, int32_t ppm) {
  if (ppm == 0) {
    return d;
  }
  const int64_t den = 1'000'000 + ppm;
  return SimDuration((d.ns() * 1'000'000 + den / 2) / den);
}

// The cause of a counter change; its time, counters and state are filled in when reported.
inline CounterSample because(CounterCause cause, ErrorRole role = ErrorRole::transmitter,
                             CanErrorType error = CanErrorType::bit) {
  CounterSample s;
  s.cause = cause;
  s.role = role;
  s.error = error;
  return s;
}

}  // namespace canemu::model::detail
