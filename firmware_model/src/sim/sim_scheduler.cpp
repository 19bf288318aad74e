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

void SimScheduler::run_action(std::size_t slot) {
  Action action = std::move(actions_[slot]);
  actions_[slot] = nullptr;
  free_slots_.push_back(slot);
  action(now_);
}

}  // namespace canemu::model
