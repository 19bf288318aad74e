// The bus engine alone on the workload of BabblingBuses: N buses at 1 Mbit/s, on each a node
// sending 000#0102030405060708 back to back and a node receiving it, with no chip model, no
// daemon and no client. What canemud's cost per bus frame is divided by.
#pragma once

#include <algorithm>
#include <deque>
#include <string>
#include <vector>

#include <time.h>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"
#include "saturating.hpp"

namespace canemu::bench {

class EngineBuses {
 public:
  explicit EngineBuses(int buses) {
    const model::BitTiming t1m = *model::sja1000::decode_btr(0x00, 0x14);  // 1 Mbit/s
    const auto frame = *model::Frame::classic(0, std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 8});
    for (int i = 0; i < buses; ++i) {
      model::CanBus& bus = buses_.emplace_back(sched_, "can" + std::to_string(i));
      senders_.emplace_back(frame, t1m);
      senders_.back().bus = &bus;
      senders_.back().id = bus.attach(senders_.back());
      receivers_.emplace_back(t1m);
      bus.attach(receivers_.back());
    }
  }
  EngineBuses(const EngineBuses&) = delete;
  EngineBuses& operator=(const EngineBuses&) = delete;

  // Runs `ns` further in simulated time, in steps of `step_ns` (as canemud's stepped time).
  void run(int64_t ns, int64_t step_ns = 2'000'000) {
    for (const int64_t end = now_ + ns; now_ < end;) {
      now_ = std::min(now_ + step_ns, end);
      sched_.run_until(model::SimTime::from_ns(now_));
    }
  }
  // Frames carried so far, on all buses.
  uint64_t frames() const {
    uint64_t n = 0;
    for (const model::CanBus& bus : buses_) {
      n += bus.frames_on_bus();
    }
    return n;
  }

 private:
  model::SimScheduler sched_;
  std::deque<model::CanBus> buses_;
  std::deque<Saturating> senders_;
  std::deque<Receiving> receivers_;
  int64_t now_ = 0;
};

// This thread's processor time in nanoseconds.
inline int64_t thread_cpu_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace canemu::bench
