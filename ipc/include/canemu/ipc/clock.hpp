// CLOCK_MONOTONIC in nanoseconds: the wall clock of real time, for the daemon's deadlines and
// the clients' timeouts and spins.
#pragma once

#include <cstdint>

#include <time.h>

namespace canemu::ipc {

inline int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace canemu::ipc
