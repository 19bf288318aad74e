// Simulated LIN nodes: schedule tables at their exact slot times, switching tables, event-
// triggered frames with collision resolution, sporadic slots, nodes switched off.
#include "canemu/firmware_model/chips/lin/lin_ecu.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace canemu::model::lin {
namespace {

constexpr int64_t kMs = 1'000'000;

Response bytes(std::vector<uint8_t> data) {
  Response r;
  r.size = static_cast<uint8_t>(data.size());
  std::copy(data.begin(), data.end(), r.data.begin());
  return r;
}

ScheduleSlot unconditional(uint8_t id, int64_t ms = 10) {
  ScheduleSlot s;
  s.id = id;
  s.delay = milliseconds(ms);
  return s;
}

// (instant, ID, first data byte) of every whole frame `ecu` saw; errors as (instant, ID, FFh).
std::vector<std::tuple<int64_t, int, int>> frames(const LinEcu& ecu) {
  std::vector<std::tuple<int64_t, int, int>> out;
  for (const Event& e : ecu.seen()) {
    if (e.kind == Event::Kind::frame) {
      out.emplace_back(e.at.ns(), e.id, e.response.data[0]);
    } else if (e.kind == Event::Kind::error) {
      out.emplace_back(e.at.ns(), e.id, 0xFF);
    }
  }
  return out;
}

class LinEcuTest : public ::testing::Test {
 protected:
  void run_to(int64_t ns) { scheduler.run_until(SimTime::from_ns(ns)); }
  int64_t bits(uint64_t n) const { return bits_duration(n, 19200).ns(); }

  SimScheduler scheduler;
  LinBus bus{scheduler, Layout{}};
  LinEcu commander{bus, 19200};
  LinEcu a{bus, 19200};
  LinEcu b{bus, 19200};
};

TEST_F(LinEcuTest, AScheduleRunsAtItsExactSlotTimes) {
  a.set_response(0x10, bytes({0xA1, 0xA2}));
  commander.set_response(0x20, bytes({0xC1}));  // the commander publishes 20h itself
  commander.add_schedule({"normal", {unconditional(0x10), unconditional(0x20, 5)}});
  ASSERT_TRUE(commander.run_schedule("normal"));
  run_to(30 * kMs - 1);
  // Slots start at 0, 10, 15, 25 ms; frames end 64 bits (two bytes) or 54 bits (one) later.
  using F = std::tuple<int64_t, int, int>;
  EXPECT_EQ(frames(b), (std::vector<F>{{bits(64), 0x10, 0xA1},
                                       {10 * kMs + bits(54), 0x20, 0xC1},
                                       {15 * kMs + bits(64), 0x10, 0xA1},
                                       {25 * kMs + bits(54), 0x20, 0xC1}}));
  EXPECT_EQ(commander.counters().headers, 4u);
  EXPECT_EQ(commander.counters().responses, 2u);
  EXPECT_EQ(a.counters().responses, 2u);
  EXPECT_FALSE(commander.run_schedule("missing"));
  EXPECT_EQ(commander.running_schedule(), "normal");
}

TEST_F(LinEcuTest, SwitchingTablesStartsTheNewOneAtOnce) {
  a.set_response(0x10, bytes({1}));
  a.set_response(0x11, bytes({2}));
  commander.add_schedule({"one", {unconditional(0x10)}});
  commander.add_schedule({"two", {unconditional(0x11, 20)}});
  commander.run_schedule("one");
  run_to(15 * kMs);
  commander.run_schedule("two");
  run_to(50 * kMs);
  using F = std::tuple<int64_t, int, int>;
  EXPECT_EQ(frames(b), (std::vector<F>{{bits(54), 0x10, 1},
                                       {10 * kMs + bits(54), 0x10, 1},
                                       {15 * kMs + bits(54), 0x11, 2},
                                       {35 * kMs + bits(54), 0x11, 2}}));
  commander.stop_schedule();
  run_to(100 * kMs);
  EXPECT_EQ(frames(b).size(), 4u);
}

TEST_F(LinEcuTest, EventTriggeredFramesAndTheirCollisions) {
  a.set_response(0x31, bytes({0x00, 0x11}));
  b.set_response(0x32, bytes({0x00, 0x22}));
  a.add_event_triggered(0x30, 0x31);
  b.add_event_triggered(0x30, 0x32);
  ScheduleSlot et;
  et.kind = ScheduleSlot::Kind::event_triggered;
  et.id = 0x30;
  et.frames = {0x31, 0x32};
  commander.add_schedule({"et", {et}});
  commander.run_schedule("et");
  // Both changed (new data): both answer at once and collide in the first byte (their PIDs,
  // B1h and 32h: neither reads back what it sent).
  run_to(10 * kMs - 1);
  EXPECT_EQ(commander.counters().collisions, 1u);
  // Then 31h and 32h are polled one per slot, each answered whole.
  run_to(30 * kMs - 1);
  using F = std::tuple<int64_t, int, int>;
  EXPECT_EQ(frames(commander), (std::vector<F>{{bits(44), 0x30, 0xFF},
                                               {10 * kMs + bits(64), 0x31, 0x00},
                                               {20 * kMs + bits(64), 0x32, 0x00}}));
  // Nothing changed since: the next event-triggered header stays unanswered (no collision).
  run_to(40 * kMs - 1);
  ASSERT_EQ(frames(commander).size(), 4u);
  EXPECT_EQ(std::get<2>(frames(commander)[3]), 0xFF);
  EXPECT_EQ(commander.counters().collisions, 1u);
  // A new value in B: it answers the event-triggered header alone, its PID first.
  b.set_response(0x32, bytes({0x00, 0x23}));
  run_to(50 * kMs - 1);
  ASSERT_EQ(frames(commander).size(), 5u);
  EXPECT_EQ(frames(commander)[4], (F{40 * kMs + bits(64), 0x30, protected_id(0x32)}));
  EXPECT_EQ(commander.seen().back().response.data[1], 0x23);
  // Sent whole: not again.
  run_to(60 * kMs - 1);
  EXPECT_EQ(std::get<2>(frames(commander).at(5)), 0xFF);
}

TEST_F(LinEcuTest, ASporadicSlotSendsAChangedFrameOrNothing) {
  commander.set_response(0x28, bytes({0x28}));
  commander.set_response(0x29, bytes({0x29}));
  ScheduleSlot sp;
  sp.kind = ScheduleSlot::Kind::sporadic;
  sp.frames = {0x28, 0x29};
  commander.add_schedule({"sp", {sp}});
  commander.run_schedule("sp");
  run_to(30 * kMs - 1);
  // Both were new: 28h first, then 29h; then the slot stays silent.
  using F = std::tuple<int64_t, int, int>;
  EXPECT_EQ(frames(a), (std::vector<F>{{bits(54), 0x28, 0x28}, {10 * kMs + bits(54), 0x29, 0x29}}));
  commander.set_response(0x29, bytes({0x2A}));
  run_to(40 * kMs - 1);
  EXPECT_EQ(frames(a).back(), (F{30 * kMs + bits(54), 0x29, 0x2A}));
  EXPECT_EQ(commander.counters().headers, 3u);
}

TEST_F(LinEcuTest, NodesSwitchedOff) {
  a.set_response(0x10, bytes({1}));
  commander.add_schedule({"s", {unconditional(0x10)}});
  commander.run_schedule("s");
  a.set_powered(false);
  run_to(10 * kMs - 1);
  ASSERT_EQ(frames(b).size(), 1u);
  EXPECT_EQ(std::get<2>(frames(b)[0]), 0xFF);  // no response
  EXPECT_EQ(b.seen()[0].error, ErrorKind::no_response);
  a.set_powered(true);
  commander.set_powered(false);
  run_to(100 * kMs);
  EXPECT_EQ(frames(b).size(), 1u);  // no more headers
  commander.set_powered(true);      // goes on with its table at once
  run_to(100 * kMs + bits(54));
  EXPECT_EQ(frames(b).back(), (std::tuple<int64_t, int, int>{100 * kMs + bits(54), 0x10, 1}));
}

}  // namespace
}  // namespace canemu::model::lin
