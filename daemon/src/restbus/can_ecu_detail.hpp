// What the two halves of CanEcu share: its schedule and payloads (can_ecu.cpp) and its faults
// (can_ecu_faults.cpp).
#pragma once

#include <algorithm>
#include <cstdint>

#include <fmt/format.h>

#include "canemu/daemon/restbus/can_ecu.hpp"

namespace canemu::daemon::restbus::detail {

// A checksum is computed as each frame goes out: it cannot be set.
inline Result<> settable(const CanMessageConfig& m, const CanSignalConfig& s) {
  if (s.checksum != ChecksumKind::none) {
    return fail(
        Errc::bad_argument,
        fmt::format("{}.{} is a checksum: it is computed as each frame goes out", m.name, s.name));
  }
  return {};
}

// A ramp's value at `now`: on the straight line from its start to its end, `to` from `until` on.
template <typename Ramp>
double ramp_at(const Ramp& r, model::SimTime now) {
  if (now >= r.until) {
    return r.to;
  }
  const double part =
      static_cast<double>((now - r.from).ns()) / static_cast<double>((r.until - r.from).ns());
  return r.start + (r.to - r.start) * std::max(part, 0.0);
}

inline uint64_t mask(uint32_t length) {
  return length >= 64 ? ~uint64_t{0} : (uint64_t{1} << length) - 1;
}

}  // namespace canemu::daemon::restbus::detail
