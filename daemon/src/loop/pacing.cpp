#include "canemu/daemon/loop/pacing.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace canemu::daemon {

int64_t LatenessHistogram::upper_bound_of(std::size_t i) {
  if (i < 32) {
    return static_cast<int64_t>(i);
  }
  const int msb = static_cast<int>(i / 16) + 3;
  const uint64_t mantissa = i % 16 + 16;
  const uint64_t lower = mantissa << (msb - 4);
  return static_cast<int64_t>(lower + (uint64_t{1} << (msb - 4)) - 1);
}

int64_t LatenessHistogram::quantile(double q) const {
  if (count_ == 0) {
    return 0;
  }
  const auto needed =
      std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(q * static_cast<double>(count_))));
  uint64_t seen = 0;
  for (std::size_t i = 0; i < kBuckets; ++i) {
    seen += counts_[i];
    if (seen >= needed) {
      return std::min(upper_bound_of(i), max_);
    }
  }
  return max_;
}

ipc::WirePacingFigures LatenessHistogram::figures() const {
  ipc::WirePacingFigures f;
  f.count = count_;
  f.p50_ns = quantile(0.5);
  f.p99_ns = quantile(0.99);
  f.max_ns = max_;
  return f;
}

void LatenessHistogram::merge(const LatenessHistogram& other) {
  for (std::size_t i = 0; i < kBuckets; ++i) {
    counts_[i] += other.counts_[i];
  }
  count_ += other.count_;
  max_ = std::max(max_, other.max_);
}

void LatenessHistogram::clear() {
  counts_.fill(0);
  count_ = 0;
  max_ = 0;
}

void Pacing::set_max_spin(int64_t ns) {
  max_spin_ns_ = std::max<int64_t>(0, ns);
  spin_ns_ = max_spin_ns_;  // until an interval has measured the timer
}

void Pacing::tick(int64_t mono_ns) {
  if (interval_start_ns_ < 0) {
    interval_start_ns_ = mono_ns;
    return;
  }
  if (mono_ns - interval_start_ns_ < kIntervalNs) {
    return;
  }
  interval_start_ns_ = mono_ns;
  if (timer_.current().count() >= kSpinMinSamples) {
    spin_ns_ = std::min(max_spin_ns_, timer_.current().quantile(0.99));
  }
  events_.rotate();
  wakeups_.rotate();
  timer_.rotate();
}

void Pacing::fill(ipc::WirePacing& out) const {
  out.events = events_.since_start();
  out.events_last = events_.last_interval();
  out.wakeups = wakeups_.since_start();
  out.wakeups_last = wakeups_.last_interval();
  out.timer = timer_.since_start();
  out.timer_last = timer_.last_interval();
  out.spin_ns = spin_ns_;
  out.max_spin_ns = max_spin_ns_;
}

}  // namespace canemu::daemon
