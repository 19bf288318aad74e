// Clock sources and the scheduler that runs a simulation island's events in time order.
//
// Contract: the daemon (or a test) owns a ClockSource and calls SimScheduler::run_until() with
// its current time; the scheduler runs every event due up to that instant, in (time, insertion)
// order, and tells the caller when the next one is due so it can arm a timer. Events may
// schedule further events, including at the current instant (they run in the same call).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "canemu/firmware_model/sim/event_queue.hpp"
#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model {

// Where simulated "now" comes from. The daemon implements realtime and scaled sources over
// CLOCK_MONOTONIC; the model only ships the stepped one.
class ClockSource {
 public:
  virtual ~ClockSource() = default;
  virtual SimTime now() const = 0;
};

// Time that moves only when told to: stepped mode and tests.
class SteppedClock final : public ClockSource {
 public:
  SimTime now() const override { return now_; }
  void advance(SimDuration d) {
    if (d.ns() > 0) {
      now_ += d;
    }
  }
  // Moves to `t` if it is later than now; time never goes backwards.
  void advance_to(SimTime t) {
    if (t > now_) {
      now_ = t;
    }
  }

 private:
  SimTime now_;
};

// A long-lived object that receives events by tag: the cheap way to schedule the events that
// recur all the time (a bus's end of frame), without a std::function per event.
class EventHandler {
 public:
  virtual void on_event(SimTime now, uint64_t tag) = 0;

 protected:
  ~EventHandler() = default;
};

class SimScheduler {
 public:
  using Action = std::function<void(SimTime)>;

  SimTime now() const { return now_; }

  // Schedules `action` at `at`; an instant in the past runs at the next run_until(), at now().
  EventId schedule_at(SimTime at, Action action);
  // Schedules handler.on_event(now, tag) at `at`. The handler must outlive the event.
  EventId schedule_at(SimTime at, EventHandler& handler, uint64_t tag) {
    return queue_.push(std::max(at, now_), Target{&handler, tag});
  }
  EventId schedule_after(SimDuration delay, Action action) {
    return schedule_at(now_ + delay, std::move(action));
  }
  bool cancel(EventId id);

  std::optional<SimTime> next_event_time() { return queue_.next_time(); }
  std::size_t pending() const { return queue_.size(); }

  // Runs every event due at or before `limit`, then sets now() to `limit` (never backwards).
  // Returns the number of events run.
  std::size_t run_until(SimTime limit) { return run_until(limit, SIZE_MAX); }
  // The same, but at most `max_events`: when that many ran and more are due, now() stays at the
  // last one's instant (the rest run at the next call). So a caller can bound its work per turn.
  std::size_t run_until(SimTime limit, std::size_t max_events) {
    return run_until(limit, max_events, [](SimTime) {});
  }
  // The same, calling `before(at)` with each event's instant just before it runs (canemud
  // measures how late it runs them).
  template <class Before>
  std::size_t run_until(SimTime limit, std::size_t max_events, Before&& before) {
    limit = std::max(limit, now_);  // time never goes backwards
    std::size_t ran = 0;
    while (ran < max_events) {
      SimTime at;
      Target t;
      if (!queue_.take_due(limit, at, t)) {
        now_ = limit;
        return ran;
      }
      now_ = std::max(now_, at);
      before(at);
      if (t.handler != nullptr) {
        t.handler->on_event(now_, t.tag);
      } else {
        run_action(t.tag);
      }
      ++ran;
    }
    if (!queue_.next_time() || *queue_.next_time() > limit) {
      now_ = limit;  // exactly `max_events` were due
    }
    return ran;
  }

 private:
  // Heap entries stay small: a handler and a tag, or an index into the slots of std::function
  // actions.
  struct Target {
    EventHandler* handler = nullptr;
    uint64_t tag = 0;  // handler's tag, or the action's slot
  };
  void run_action(std::size_t slot);  // the std::function in `slot`, which it frees

  EventQueue<Target> queue_;
  std::vector<Action> actions_;
  std::vector<std::size_t> free_slots_;
  SimTime now_;
};

}  // namespace canemu::model
