// How punctually canemud runs the simulation in real and scaled time, measured by canemud
// itself (docs/daemon.md, "Pacing"):
// - events: every simulated event against its instant mapped to CLOCK_MONOTONIC (lateness
//   includes the batching of `simulation.batch_us` by design);
// - wake-ups: each timer wake-up of the loop, after its spin, against the deadline it aimed for;
// - the timer itself: how late the timerfd fired against the instant it was armed for, which
//   sets how early the loop arms it (the spin, at most `simulation.spin_us`).
// Each as p50 / p99 / max since start and over the last complete second.
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::daemon {

// Counts of non-negative durations in ns in log-linear buckets: exact below 32 ns, then 16
// buckets per power of two (a bucket is at most 1/16 of its lower bound wide, about 6 %).
class LatenessHistogram {
 public:
  static constexpr std::size_t kBuckets = 960;  // up to 2^63 ns

  static std::size_t bucket_of(int64_t ns) {
    const auto v = static_cast<uint64_t>(ns);
    if (v < 32) {
      return static_cast<std::size_t>(v);
    }
    // The top five bits (16..31) of v and the position of its highest bit.
    const int msb = 63 - std::countl_zero(v);
    return static_cast<std::size_t>(msb - 4) * 16 + static_cast<std::size_t>(v >> (msb - 4));
  }
  // The largest value bucket `i` holds (what a quantile reports: never below the truth).
  static int64_t upper_bound_of(std::size_t i);

  void add(int64_t ns) {
    if (ns < 0) {
      ns = 0;
    }
    ++counts_[bucket_of(ns)];
    ++count_;
    if (ns > max_) {
      max_ = ns;
    }
  }
  uint64_t count() const { return count_; }
  int64_t max() const { return max_; }
  // The smallest bucket bound at or below which at least `q` (0..1) of the values are; the
  // max when that bound is beyond it; 0 without values.
  int64_t quantile(double q) const;
  ipc::WirePacingFigures figures() const;
  void clear();
  // Adds what `other` counted.
  void merge(const LatenessHistogram& other);

 private:
  std::array<uint64_t, kBuckets> counts_{};
  uint64_t count_ = 0;
  int64_t max_ = 0;
};

// One figure since start and over the last complete interval. A value goes into the current
// interval only; an interval that ends is added to what came before it.
class LatenessRecord {
 public:
  void add(int64_t ns) { current_.add(ns); }
  // Ends the current interval: its figures become the last interval's.
  void rotate() {
    last_ = current_.figures();
    before_.merge(current_);
    current_.clear();
  }
  ipc::WirePacingFigures since_start() const {
    LatenessHistogram all = before_;
    all.merge(current_);
    return all.figures();
  }
  ipc::WirePacingFigures last_interval() const { return last_; }
  // The current interval's quantile (the spin estimate reads it before rotating).
  const LatenessHistogram& current() const { return current_; }

 private:
  LatenessHistogram before_;  // the intervals that ended
  LatenessHistogram current_;
  ipc::WirePacingFigures last_{};
};

class Pacing {
 public:
  static constexpr int64_t kIntervalNs = 1'000'000'000;
  // Timer firings an interval needs before the spin follows them.
  static constexpr uint64_t kSpinMinSamples = 50;

  // `max_spin_ns`: `simulation.spin_us`; the spin starts there.
  explicit Pacing(int64_t max_spin_ns = 0) { set_max_spin(max_spin_ns); }
  void set_max_spin(int64_t ns);

  void event_late(int64_t ns) { events_.add(ns); }
  void wakeup_late(int64_t ns) { wakeups_.add(ns); }
  void timer_late(int64_t ns) { timer_.add(ns); }

  // Rotates the intervals once `mono_ns` is an interval past the last rotation; the spin then
  // becomes the timer's p99 of the interval that ended, at most the configured maximum.
  void tick(int64_t mono_ns);
  // How early to arm the timer before a deadline.
  int64_t spin_ns() const { return spin_ns_; }
  int64_t max_spin_ns() const { return max_spin_ns_; }

  void fill(ipc::WirePacing& out) const;

 private:
  LatenessRecord events_;
  LatenessRecord wakeups_;
  LatenessRecord timer_;
  int64_t max_spin_ns_ = 0;
  int64_t spin_ns_ = 0;
  int64_t interval_start_ns_ = -1;
};

}  // namespace canemu::daemon
