#include "canemu/firmware_model/sim_scheduler.hpp"

#include <algorithm>

namespace canemu::model {

EventId SimScheduler::schedule_at(SimTime at, Action action) {
  return queue_.push(std::max(at, now_), std::move(action));
}

std::size_t SimScheduler::run_until(SimTime limit) {
  limit = std::max(limit, now_);  // time never goes backwards
  std::size_t ran = 0;
  while (true) {
    const auto next = queue_.next_time();
    if (!next || *next > limit) {
      break;
    }
    auto entry = queue_.pop();
    now_ = std::max(now_, entry->time);
    entry->payload(now_);
    ++ran;
  }
  now_ = limit;
  return ran;
}

}  // namespace canemu::model
