#include "canemu/daemon/base/reject_log.hpp"

#include <time.h>

#include "canemu/daemon/base/log.hpp"

namespace canemu::daemon {

namespace {

int64_t monotonic_ms() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1000 + ts.tv_nsec / 1'000'000;
}

}  // namespace

void reject_log_line(const std::string& source, const std::string& detail, int64_t& window_start_ms,
                     int& logged, uint64_t& unlogged, int burst, int64_t window_ms) {
  const int64_t now = monotonic_ms();
  if (now - window_start_ms >= window_ms) {
    window_start_ms = now;
    logged = 0;
  }
  if (logged >= burst) {
    ++unlogged;
    return;
  }
  ++logged;
  if (unlogged > 0) {
    log::warning("{}: {} ({} more since the last line, not logged: at most {} lines in {} s)",
                 source, detail, unlogged, burst, window_ms / 1000);
    unlogged = 0;
    return;
  }
  log::warning("{}: {}", source, detail);
}

}  // namespace canemu::daemon
