#include "canemu/firmware_model/sim/sim_scheduler.hpp"

#include <algorithm>

namespace canemu::model {

EventId SimScheduler::schedule_at(SimTime at, Action action) {
  std::size_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
    actions_[slot] = std::move(action);
  } else {
    slot = actions_.size();
    actions_.push_back(std::move(action));
  }
  return queue_.push(std::max(at, now_), Target{nullptr, slot});
}

bool SimScheduler::cancel(EventId id) {
  const Target* t = queue_.find(id);
  if (t == nullptr) {
    return false;
  }
  if (t->handler == nullptr) {
    actions_[t->tag] = nullptr;
    free_slots_.push_back(t->tag);
  }
  return queue_.cancel(id);
}

std::size_t SimScheduler::run_until(SimTime limit, std::size_t max_events) {
  limit = std::max(limit, now_);  // time never goes backwards
  std::size_t ran = 0;
  while (ran < max_events) {
    SimTime at;
    Target t;
    if (!queue_.pop_due(limit, at, t)) {
      now_ = limit;
      return ran;
    }
    now_ = std::max(now_, at);
    if (t.handler != nullptr) {
      t.handler->on_event(now_, t.tag);
    } else {
      Action action = std::move(actions_[t.tag]);
      actions_[t.tag] = nullptr;
      free_slots_.push_back(t.tag);
      action(now_);
    }
    ++ran;
  }
  if (!queue_.next_time() || *queue_.next_time() > limit) {
    now_ = limit;  // exactly `max_events` were due
  }
  return ran;
}

}  // namespace canemu::model
