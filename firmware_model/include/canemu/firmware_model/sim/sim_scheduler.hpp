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
#include <memory>
#include <optional>
#include <type_traits>
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

  // For a handler running in run_until() whose follow-up is due at `at`: if that follow-up is
  // what would run next (`at` within the run's limit, no other event due at or before it, the
  // run's bound on events not reached), moves now() on to `at`, counts it as an event run (and
  // tells the run's `before`) and returns true; the handler then runs it at once itself instead
  // of scheduling it (a bus at full load goes from frame to frame without the queue). Otherwise,
  // and outside run_until(), false: the handler schedules it as usual.
  bool run_inline(SimTime at) {
    if (window_.left == 0 || at > window_.limit || at < now_ || queue_.any_due_by(at)) {
      return false;
    }
    --window_.left;
    now_ = at;
    if (window_.note != nullptr) {
      window_.note(window_.before, at);
    }
    return true;
  }

  std::optional<SimTime> next_event_time() { return queue_.next_time(); }
  std::size_t pending() const { return queue_.size(); }

  // Runs every event due at or before `limit`, then sets now() to `limit` (never backwards).
  // Returns the number of events run.
  std::size_t run_until(SimTime limit) { return run_until(limit, SIZE_MAX); }
  // The same, but at most `max_events`: when that many ran and more are due, now() stays at the
  // last one's instant (the rest run at the next call). So a caller can bound its work per turn.
  std::size_t run_until(SimTime limit, std::size_t max_events) {
    return run_until(limit, max_events, NoBefore{});
  }
  // The same, calling `before(at)` with each event's instant just before it runs (canemud
  // measures how late it runs them).
  template <class Before>
  std::size_t run_until(SimTime limit, std::size_t max_events, Before&& before) {
    limit = std::max(limit, now_);  // time never goes backwards
    const Window outer = window_;   // a run_until() from a handler leaves the caller's as it was
    window_.limit = limit;
    if constexpr (std::is_same_v<std::decay_t<Before>, NoBefore>) {
      window_.note = nullptr;
    } else {
      window_.before = const_cast<void*>(static_cast<const void*>(std::addressof(before)));
      window_.note = [](void* f, SimTime at) { (*static_cast<std::decay_t<Before>*>(f))(at); };
    }
    std::size_t ran = 0;
    while (ran < max_events) {
      SimTime at;
      Target t;
      if (!queue_.take_due(limit, at, t)) {
        now_ = limit;
        window_ = outer;
        return ran;
      }
      now_ = std::max(now_, at);
      before(at);
      // What the handler may run at once (run_inline) counts against `max_events`.
      const std::size_t left = max_events - ran - 1;
      window_.left = left;
      if (t.handler != nullptr) {
        t.handler->on_event(now_, t.tag);
      } else {
        run_action(t.tag);
      }
      ran += 1 + (left - window_.left);
    }
    window_ = outer;
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

  // run_until() without a `before`.
  struct NoBefore {
    void operator()(SimTime) const {}
  };
  // The run_until() under way, for run_inline(): its limit, the events it may still run, and
  // its `before` (note(before, at); note is nullptr for none). `left` is 0 outside a run.
  struct Window {
    SimTime limit;
    std::size_t left = 0;
    void* before = nullptr;
    void (*note)(void*, SimTime) = nullptr;
  };
  Window window_;

  EventQueue<Target> queue_;
  std::vector<Action> actions_;
  std::vector<std::size_t> free_slots_;
  SimTime now_;
};

}  // namespace canemu::model
