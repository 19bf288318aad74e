// What each leg of a message between daemons costs (bench/README.md, "DDS hop"): measured only
// when the environment sets CANEMU_NET_LEGS (to anything but "" or "0"), and written to the log
// once, as the daemon stops. Off, it costs a branch per message. Private to the files of buses
// across hosts; only in builds with Cyclone DDS.
#pragma once

#include <time.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <fmt/format.h>

namespace canemu::daemon::net_detail {

enum class Leg : uint8_t {
  request_write,     // dds_write of a request: serialising it and sending it
  request_delivery,  // a request: from its write's start (the sender's) to the listener here
  request_turn,      // a request: from the listener's call to the loop taking it
  event_wait,        // the owner: from a frame's end (its instant) to the start of its write
  event_write,       // dds_write of an event sample
  event_delivery,    // an event: from its write's start (the owner's) to the listener here
  event_turn,        // an event: from the listener's call to the loop taking it
  count
};

class LinkLegs {
 public:
  LinkLegs() {
    const char* v = std::getenv("CANEMU_NET_LEGS");
    on_ = v != nullptr && *v != '\0' && std::string(v) != "0";
  }
  bool on() const { return on_; }

  // Cyclone's receive thread, as the listener rings the loop: the first call since the loop took.
  void rung() {
    int64_t none = 0;
    first_ring_.compare_exchange_strong(none, dds_time(), std::memory_order_relaxed);
  }
  // The loop takes: when the first listener call since the last take was (0: none), and now.
  struct Take {
    int64_t rung = 0;
    int64_t now = 0;
    bool timed = false;  // the first request or event of this take has been timed
  };
  Take take() {
    Take t;
    t.rung = first_ring_.exchange(0, std::memory_order_relaxed);
    t.now = dds_time();
    return t;
  }
  // The first request or event sample of a take: its delivery and the loop's turn.
  void taken(Take& t, int64_t written, bool event) {
    if (t.timed || t.rung == 0 || written > t.rung) {
      return;  // not the sample that rang, or its ring not seen
    }
    t.timed = true;
    add(event ? Leg::event_delivery : Leg::request_delivery, t.rung - written);
    add(event ? Leg::event_turn : Leg::request_turn, t.now - t.rung);
  }
  // Real time: the monotonic clock minus simulated time, the smallest seen (the loop's
  // present when it has just caught up): a frame's end instant on the monotonic clock.
  void observe(int64_t sim_now_ns) { origin_ = std::min(origin_, mono() - sim_now_ns); }
  int64_t since_instant(int64_t sim_ns) const { return mono() - origin_ - sim_ns; }

  void add(Leg leg, int64_t ns) {
    auto& v = samples_[static_cast<std::size_t>(leg)];
    if (v.size() < kMaxSamples) {
      v.push_back(ns);
    }
  }
  static int64_t mono() {
    timespec ts{};
    ::clock_gettime(CLOCK_MONOTONIC, &ts);
    return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
  }

  // "link legs (us, p50/p99/samples): request_write=5.1/12.0/2020, ..."
  std::string summary() {
    static constexpr const char* kNames[] = {"request_write", "request_delivery", "request_turn",
                                             "event_wait",    "event_write",      "event_delivery",
                                             "event_turn"};
    std::string out = "link legs (us, p50/p99/samples):";
    for (std::size_t i = 0; i < samples_.size(); ++i) {
      auto& v = samples_[i];
      std::sort(v.begin(), v.end());
      const auto at = [&](double p) {
        return v.empty() ? 0.0
                         : static_cast<double>(
                               v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))]) /
                               1000.0;
      };
      out += fmt::format("{} {}={:.1f}/{:.1f}/{}", i == 0 ? "" : ",", kNames[i], at(0.5), at(0.99),
                         v.size());
    }
    return out;
  }

 private:
  static constexpr std::size_t kMaxSamples = 1 << 20;
  bool on_ = false;
  std::atomic<int64_t> first_ring_{0};
  int64_t origin_ = std::numeric_limits<int64_t>::max();
  std::array<std::vector<int64_t>, static_cast<std::size_t>(Leg::count)> samples_;
};

}  // namespace canemu::daemon::net_detail
