// How long the event loop lets events gather before it wakes for them, in real and scaled time
// (docs/daemon.md, "Time"). A wake-up costs the same whatever it finds (the timer, the kernel's
// switch, a look at every ring), so when events come densely (many busy buses) the window
// widens from `simulation.batch_us` towards `simulation.batch_max_us`, doubling every wake-up,
// as a network card moderates its interrupts; as soon as they come sparsely again it is back to
// batch_us, so a lone frame keeps its latency. Every event still runs at its exact simulated
// instant; what widens is how late a client may see it.
#pragma once

#include <algorithm>
#include <cstdint>

namespace canemu::daemon {

class BatchWindow {
 public:
  // Events a second from which the loop counts as busy: 8 in every 50 us (about ten 1 Mbit/s
  // buses at full load, two events a frame); it is quiet again below half of that.
  static constexpr int64_t kBusyEventsPerSecond = 160'000;

  // `base_us` and `max_us` as configured; no widening when max_us <= base_us. The same values
  // again change nothing (the loop passes them on every turn, reloads included).
  void configure(uint32_t base_us, uint32_t max_us) {
    const int64_t base_ns = int64_t{base_us} * 1000;
    const int64_t max_ns = std::max(base_ns, int64_t{max_us} * 1000);
    if (base_ns == base_ns_ && max_ns == max_ns_) {
      return;
    }
    base_ns_ = base_ns;
    max_ns_ = max_ns;
    window_ns_ = base_ns_;
  }

  // A wake-up at `wake_ns` (CLOCK_MONOTONIC) that ran `events` events, gathered since the one
  // before; returns the window to wait after it.
  int64_t woke(uint64_t events, int64_t wake_ns) {
    const int64_t span = wake_ns - last_wake_ns_;
    last_wake_ns_ = wake_ns;
    if (max_ns_ == base_ns_ || span <= 0) {
      return window_ns_ = base_ns_;
    }
    // events / span >= kBusyEventsPerSecond / 1e9, without a division.
    const auto busy = static_cast<double>(events) * 1e9;
    const auto rate_needed = static_cast<double>(kBusyEventsPerSecond) * static_cast<double>(span);
    if (busy >= rate_needed) {
      window_ns_ = std::min(max_ns_, std::max<int64_t>(2 * window_ns_, kFirstWidenedNs));
    } else if (2 * busy < rate_needed) {
      window_ns_ = base_ns_;
    }
    return window_ns_;
  }
  int64_t window_ns() const { return window_ns_; }
  // Wider than batch_us: events come densely.
  bool widened() const { return window_ns_ > base_ns_; }

 private:
  static constexpr int64_t kFirstWidenedNs = 100'000;  // where widening starts from batch_us 0

  int64_t base_ns_ = 50'000;
  int64_t max_ns_ = 50'000;
  int64_t window_ns_ = 50'000;
  int64_t last_wake_ns_ = 0;
};

}  // namespace canemu::daemon
