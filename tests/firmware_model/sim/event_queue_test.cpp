#include "canemu/firmware_model/sim/event_queue.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::model {
namespace {

TEST(SimTime, DurationsConvertExactly) {
  EXPECT_EQ(microseconds(3).ns(), 3'000);
  EXPECT_EQ(milliseconds(2).ns(), 2'000'000);
  EXPECT_EQ(seconds(1).ns(), 1'000'000'000);
  const SimTime t = SimTime::from_ns(100) + microseconds(1);
  EXPECT_EQ(t.ns(), 1'100);
  EXPECT_EQ((t - SimTime::from_ns(100)).ns(), 1'000);
}

TEST(EventQueue, PopsInTimeOrder) {
  EventQueue<int> q;
  q.push(SimTime::from_ns(30), 3);
  q.push(SimTime::from_ns(10), 1);
  q.push(SimTime::from_ns(20), 2);
  std::vector<int> got;
  while (auto e = q.pop()) {
    got.push_back(e->payload);
  }
  EXPECT_EQ(got, (std::vector<int>{1, 2, 3}));
}

TEST(EventQueue, EqualTimesComeOutInInsertionOrder) {
  EventQueue<int> q;
  for (int i = 0; i < 100; ++i) {
    q.push(SimTime::from_ns(5), i);
  }
  for (int i = 0; i < 100; ++i) {
    auto e = q.pop();
    ASSERT_TRUE(e);
    EXPECT_EQ(e->payload, i);
  }
  EXPECT_TRUE(q.empty());
}

TEST(EventQueue, CancelledEventsNeverComeOut) {
  EventQueue<std::string> q;
  q.push(SimTime::from_ns(1), "a");
  const EventId b = q.push(SimTime::from_ns(2), "b");
  q.push(SimTime::from_ns(3), "c");
  EXPECT_TRUE(q.cancel(b));
  EXPECT_FALSE(q.cancel(b));
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(q.pop()->payload, "a");
  EXPECT_EQ(q.next_time(), SimTime::from_ns(3));
  EXPECT_EQ(q.pop()->payload, "c");
  EXPECT_FALSE(q.pop());
  EXPECT_FALSE(q.cancel(12345));
}

TEST(EventQueue, CancellingTheEarliestExposesTheNext) {
  EventQueue<int> q;
  const EventId first = q.push(SimTime::from_ns(1), 1);
  q.push(SimTime::from_ns(9), 2);
  q.cancel(first);
  EXPECT_EQ(q.next_time(), SimTime::from_ns(9));
}

TEST(EventQueue, ATakenEventIsGoneForEveryOtherCall) {
  EventQueue<int> q;
  const EventId a = q.push(SimTime::from_ns(1), 1);
  q.push(SimTime::from_ns(2), 2);
  q.push(SimTime::from_ns(3), 3);
  SimTime at;
  int payload = 0;
  EXPECT_FALSE(q.take_due(SimTime::from_ns(0), at, payload));
  ASSERT_TRUE(q.take_due(SimTime::from_ns(10), at, payload));
  EXPECT_EQ(at, SimTime::from_ns(1));
  EXPECT_EQ(payload, 1);
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(q.find(a), nullptr);
  EXPECT_FALSE(q.cancel(a));
  EXPECT_EQ(q.next_time(), SimTime::from_ns(2));
  EXPECT_EQ(q.pop()->payload, 2);
  EXPECT_EQ(q.pop()->payload, 3);
  EXPECT_TRUE(q.empty());
}

// Events taken one by one, each followed by a push (which takes the taken entry's place) at the
// same instant, soon, after everything or in between, and now and then a pending event
// cancelled: they come out as from a sorted list of (time, order pushed).
TEST(EventQueue, PushesAfterATakeKeepTheOrderOfASortedList) {
  EventQueue<int> q;
  std::set<std::pair<int64_t, int>> model;  // (time, push number)
  std::map<int, EventId> ids;               // push number -> the queue's id
  int pushed = 0;
  auto push = [&](int64_t t) {
    ids[pushed] = q.push(SimTime::from_ns(t), pushed);
    model.insert({t, pushed});
    ++pushed;
  };
  std::mt19937 rng(41);
  for (int i = 0; i < 130; ++i) {
    push(static_cast<int64_t>(rng() % 1000));
  }
  for (int step = 0; step < 5000; ++step) {
    SimTime at;
    int payload = -1;
    ASSERT_TRUE(q.take_due(SimTime::from_ns(INT64_MAX), at, payload));
    ASSERT_FALSE(model.empty());
    ASSERT_EQ(std::make_pair(at.ns(), payload), *model.begin()) << step;
    model.erase(model.begin());
    const int64_t now = at.ns();
    switch (rng() % 4) {
      case 0:
        push(now);  // at the same instant: after every other event of it
        break;
      case 1:
        push(now + 3);  // soon: near the top
        break;
      case 2:
        push(now + 1000);  // after everything
        break;
      default:
        push(now + static_cast<int64_t>(rng() % 500));
        break;
    }
    if (rng() % 8 == 0 && model.size() > 1) {
      auto victim = std::next(model.begin(), static_cast<long>(rng() % model.size()));
      ASSERT_TRUE(q.cancel(ids[victim->second])) << step;
      model.erase(victim);
    }
    ASSERT_EQ(q.size(), model.size()) << step;
  }
}

TEST(SteppedClock, AdvancesOnlyForwardAndOnlyWhenTold) {
  SteppedClock clock;
  EXPECT_EQ(clock.now().ns(), 0);
  clock.advance(milliseconds(10));
  EXPECT_EQ(clock.now().ns(), 10'000'000);
  clock.advance_to(SimTime::from_ns(5));
  EXPECT_EQ(clock.now().ns(), 10'000'000);
  clock.advance(SimDuration(-5));
  EXPECT_EQ(clock.now().ns(), 10'000'000);
}

TEST(SimScheduler, RunsDueEventsInOrderAndStopsAtTheLimit) {
  SimScheduler s;
  std::vector<std::pair<int, int64_t>> trace;
  s.schedule_at(SimTime::from_ns(300), [&](SimTime t) { trace.emplace_back(3, t.ns()); });
  s.schedule_at(SimTime::from_ns(100), [&](SimTime t) { trace.emplace_back(1, t.ns()); });
  s.schedule_at(SimTime::from_ns(100), [&](SimTime t) { trace.emplace_back(2, t.ns()); });
  EXPECT_EQ(s.run_until(SimTime::from_ns(200)), 2u);
  EXPECT_EQ(s.now().ns(), 200);
  EXPECT_EQ(s.next_event_time(), SimTime::from_ns(300));
  EXPECT_EQ(s.run_until(SimTime::from_ns(300)), 1u);
  EXPECT_EQ(trace, (std::vector<std::pair<int, int64_t>>{{1, 100}, {2, 100}, {3, 300}}));
}

// A bounded turn stops after `max_events`; time stays at the last event run while more are due,
// and reaches the limit once none is.
TEST(SimScheduler, ABoundedRunStopsAfterItsEventsAndTimeWaitsForTheRest) {
  SimScheduler s;
  std::vector<int64_t> ran;
  for (int64_t at : {10, 20, 30, 40, 40}) {
    s.schedule_at(SimTime::from_ns(at), [&](SimTime t) { ran.push_back(t.ns()); });
  }
  EXPECT_EQ(s.run_until(SimTime::from_ns(100), 2), 2u);
  EXPECT_EQ(s.now().ns(), 20);
  EXPECT_EQ(s.run_until(SimTime::from_ns(100), 2), 2u);
  EXPECT_EQ(s.now().ns(), 40);  // the second event at 40 is still due
  EXPECT_EQ(s.run_until(SimTime::from_ns(100), 2), 1u);
  EXPECT_EQ(s.now().ns(), 100);
  EXPECT_EQ(ran, (std::vector<int64_t>{10, 20, 30, 40, 40}));
  // Exactly as many due as allowed: the limit is reached.
  s.schedule_at(SimTime::from_ns(150), [&](SimTime t) { ran.push_back(t.ns()); });
  s.schedule_at(SimTime::from_ns(900), [&](SimTime t) { ran.push_back(t.ns()); });
  EXPECT_EQ(s.run_until(SimTime::from_ns(200), 1), 1u);
  EXPECT_EQ(s.now().ns(), 200);
  EXPECT_EQ(s.run_until(SimTime::from_ns(300), 0), 0u);
  EXPECT_EQ(s.now().ns(), 300);  // nothing due: even a turn of no events reaches the limit
}

TEST(SimScheduler, EventsScheduledWhileRunningRunInTheSameCallWhenDue) {
  SimScheduler s;
  std::vector<int64_t> times;
  std::function<void(SimTime)> tick = [&](SimTime t) {
    times.push_back(t.ns());
    if (times.size() < 5) {
      s.schedule_after(nanoseconds(10), tick);
    }
  };
  s.schedule_at(SimTime::from_ns(0), tick);
  s.run_until(SimTime::from_ns(25));
  EXPECT_EQ(times, (std::vector<int64_t>{0, 10, 20}));
  s.run_until(SimTime::from_ns(1000));
  EXPECT_EQ(times, (std::vector<int64_t>{0, 10, 20, 30, 40}));
  EXPECT_EQ(s.pending(), 0u);
}

TEST(SimScheduler, AnEventInThePastRunsAtNowAndTimeNeverGoesBack) {
  SimScheduler s;
  s.run_until(SimTime::from_ns(500));
  int64_t ran_at = -1;
  s.schedule_at(SimTime::from_ns(100), [&](SimTime t) { ran_at = t.ns(); });
  s.run_until(SimTime::from_ns(400));
  EXPECT_EQ(ran_at, 500);
  EXPECT_EQ(s.now().ns(), 500);
}

TEST(SimScheduler, SameInputsGiveTheSameTrace) {
  auto run = [] {
    SimScheduler s;
    std::vector<int> order;
    for (int i = 0; i < 50; ++i) {
      s.schedule_at(SimTime::from_ns((i * 7) % 13), [&order, i](SimTime) { order.push_back(i); });
    }
    s.run_until(SimTime::from_ns(100));
    return order;
  };
  EXPECT_EQ(run(), run());
}

// A handler that follows itself up every `period` ns, `left` times: at once when run_inline()
// allows it, else through the queue. It notes each run's instant and whether it ran inline.
class FollowingUp final : public EventHandler {
 public:
  FollowingUp(SimScheduler& s, int64_t period, int left) : s_(s), period_(period), left_(left) {}
  void on_event(SimTime now, uint64_t) override {
    for (;;) {
      runs.push_back({now.ns(), inline_});
      if (--left_ == 0) {
        return;
      }
      const SimTime next = now + SimDuration(period_);
      inline_ = s_.run_inline(next);
      if (!inline_) {
        s_.schedule_at(next, *this, 0);
        return;
      }
      EXPECT_EQ(s_.now(), next);
      now = next;
    }
  }
  struct Run {
    int64_t at;
    bool was_inline;
    bool operator==(const Run&) const = default;
  };
  std::vector<Run> runs;

 private:
  SimScheduler& s_;
  int64_t period_;
  int left_;
  bool inline_ = false;
};

TEST(SimScheduler, AFollowUpRunsInlineOnlyWhenNothingElseIsDueByItsInstant) {
  SimScheduler s;
  FollowingUp h(s, 10, 5);
  std::vector<int64_t> other;
  s.schedule_at(SimTime::from_ns(0), h, 0);
  // An event due exactly at the third run's instant, queued before it: it runs first.
  s.schedule_at(SimTime::from_ns(20), [&](SimTime t) { other.push_back(t.ns()); });
  std::vector<int64_t> before;
  const std::size_t ran =
      s.run_until(SimTime::from_ns(1000), SIZE_MAX, [&](SimTime at) { before.push_back(at.ns()); });
  using Run = FollowingUp::Run;
  EXPECT_EQ(h.runs,
            (std::vector<Run>{{0, false}, {10, true}, {20, false}, {30, true}, {40, true}}));
  EXPECT_EQ(other, (std::vector<int64_t>{20}));
  // Every event counts, the inline ones too, and `before` hears of each in order.
  EXPECT_EQ(ran, 6u);
  EXPECT_EQ(before, (std::vector<int64_t>{0, 10, 20, 20, 30, 40}));
  EXPECT_EQ(s.now().ns(), 1000);
}

TEST(SimScheduler, AFollowUpPastTheLimitOrTheBoundWaitsForTheNextRun) {
  SimScheduler s;
  FollowingUp h(s, 10, 6);
  s.schedule_at(SimTime::from_ns(0), h, 0);
  // The limit: 0, 10 and 20 run, 30 lies beyond it.
  EXPECT_EQ(s.run_until(SimTime::from_ns(25)), 3u);
  EXPECT_EQ(s.now().ns(), 25);
  EXPECT_EQ(s.pending(), 1u);
  // The bound: two events, the second inline; time stays at the last one run.
  EXPECT_EQ(s.run_until(SimTime::from_ns(1000), 2), 2u);
  EXPECT_EQ(s.now().ns(), 40);
  EXPECT_EQ(s.run_until(SimTime::from_ns(1000)), 1u);
  using Run = FollowingUp::Run;
  EXPECT_EQ(h.runs, (std::vector<Run>{
                        {0, false}, {10, true}, {20, true}, {30, false}, {40, true}, {50, false}}));
  // Outside a run nothing runs inline.
  EXPECT_FALSE(s.run_inline(SimTime::from_ns(1000)));
}

}  // namespace
}  // namespace canemu::model
