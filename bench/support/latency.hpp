// Helpers for latency benchmarks: a monotonic clock in ns, percentiles, sleeping with fine
// timer slack, and latency samples shared between a parent and a forked child.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <benchmark/benchmark.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <time.h>
#include "canemu/ipc/clock.hpp"

namespace canemu::bench {

// Latency benchmarks take this many samples, each after this long an idle bus (a frame at
// 1 Mbit/s is over long before the next).
inline constexpr std::size_t kLatencySamples = 2000;
inline constexpr int64_t kLatencyGapNs = 500'000;

inline int64_t now_ns() {
  return ipc::monotonic_ns();
}

// Sleeps `ns` with 1 ns timer slack (the default 50 us slack would dominate short sleeps).
inline void sleep_ns(int64_t ns) {
  ::prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  ::clock_nanosleep(CLOCK_MONOTONIC, 0, &ts, nullptr);
}

inline double percentile(std::vector<int64_t> samples, double p) {
  if (samples.empty()) {
    return 0;
  }
  std::sort(samples.begin(), samples.end());
  const auto at = static_cast<std::size_t>(p * static_cast<double>(samples.size() - 1) + 0.5);
  return static_cast<double>(samples[at]);
}

// Reports p50 and p99 of `samples` (ns) as counters named `<name>_p50_us` and `<name>_p99_us`.
inline void report(benchmark::State& state, const char* name, const std::vector<int64_t>& s) {
  state.counters[std::string(name) + "_p50_us"] = percentile(s, 0.50) / 1000.0;
  state.counters[std::string(name) + "_p99_us"] = percentile(s, 0.99) / 1000.0;
}

// `n` samples in memory shared with forked children.
class SharedSamples {
 public:
  explicit SharedSamples(std::size_t n) : n_(n) {
    void* p = ::mmap(nullptr, n * sizeof(int64_t), PROT_READ | PROT_WRITE,
                     MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    data_ = p == MAP_FAILED ? nullptr : static_cast<int64_t*>(p);
  }
  ~SharedSamples() {
    if (data_ != nullptr) {
      ::munmap(data_, n_ * sizeof(int64_t));
    }
  }
  SharedSamples(const SharedSamples&) = delete;
  SharedSamples& operator=(const SharedSamples&) = delete;
  bool valid() const { return data_ != nullptr; }
  int64_t& operator[](std::size_t i) { return data_[i]; }
  std::vector<int64_t> vector() const { return {data_, data_ + n_}; }

 private:
  std::size_t n_;
  int64_t* data_ = nullptr;
};

}  // namespace canemu::bench
