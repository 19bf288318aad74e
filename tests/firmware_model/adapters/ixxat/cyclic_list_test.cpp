// The cyclic transmit list (cyclic_list.hpp, VCI C++ guide 5.2.5, docs/vci.md): through
// the line on a bus, and the CyclicList on its own with a scripted line.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/cyclic_list.hpp"

namespace canemu::model {
namespace {

using namespace testing;  // line_rig.hpp, hosted_station.hpp

// ---------------------------------------------------------------- cyclic transmit list

CANCYCLICTXMSG2 cyclic(uint32_t id, uint16_t cycle, uint8_t incr = CAN_CTXMSG_INC_NO,
                       uint8_t index = 0, std::vector<uint8_t> data = {0x11, 0x22},
                       bool ext = false) {
  const CANMSG2 frame = msg(id, std::move(data), ext);
  CANCYCLICTXMSG2 m{};
  m.wCycleTime = cycle;
  m.bIncrMode = incr;
  m.bByteIndex = index;
  m.dwMsgId = frame.dwMsgId;
  m.uMsgInfo = frame.uMsgInfo;
  std::memcpy(m.abData, frame.abData, sizeof m.abData);
  return m;
}

// A rig with the line online, the peer started and the bus's frames recorded.
struct ListRig : Rig {
  ListRig() {
    b.bus.on_bus_event = [this](const BusEvent& e) {
      if (e.kind == BusEvent::Kind::frame) {
        frames.push_back(e);
      }
    };
    online(port);
    EXPECT_EQ(line.open_scheduler(), VCI_OK);
  }
  // An entry for `id` every `cycle` ticks, started for `count` frames (0: without end), and the
  // task resumed; its index.
  uint32_t running(uint32_t id, uint16_t cycle, uint16_t count = 0) {
    const uint32_t index = *line.scheduler_add(cyclic(id, cycle));
    EXPECT_EQ(line.scheduler_start(index, count), VCI_OK);
    EXPECT_EQ(line.scheduler_resume(), VCI_OK);
    return index;
  }
  // Start of frame instants of `id`, in list ticks (ms).
  std::vector<int64_t> ticks_of(uint32_t id) const {
    std::vector<int64_t> out;
    for (const BusEvent& e : frames) {
      if (e.frame->id() == id) {
        EXPECT_EQ(e.start.ns() % kMs, 0) << e.start.ns();
        out.push_back(e.start.ns() / kMs);
      }
    }
    return out;
  }
  Port port;
  std::vector<BusEvent> frames;
};

TEST(VciCanLine, CollidingCyclicEntriesShiftToTheNextFreeTickAndKeepTheirRhythm) {
  ListRig r;
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 2));
  const uint32_t b = *r.line.scheduler_add(cyclic(0x200, 3));
  EXPECT_EQ(a, 0u);
  EXPECT_EQ(b, 1u);
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(b, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(20 * kMs + 500 * kUs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 6, 8, 10, 12, 14, 16, 18, 20}));
  // The older entry wins the ties at 6, 12 and 18; the cycle-3 entry goes one tick later.
  EXPECT_EQ(r.ticks_of(0x200), (std::vector<int64_t>{3, 7, 9, 13, 15, 19}));
}

TEST(VciCanLine, TheTaskIsStoppedAfterOpeningAndResumeStartsEveryStartedEntryTogether) {
  ListRig r;
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 4));
  const uint32_t b = *r.line.scheduler_add(cyclic(0x200, 4));
  const uint32_t idle = *r.line.scheduler_add(cyclic(0x300, 2));
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_DONE);  // added, not started
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(b, 0), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(10 * kMs);
  EXPECT_TRUE(r.frames.empty());
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  r.b.run_until(19 * kMs);  // frames are recorded at their start of frame
  // Both due in tick 4 after the resume at 10 ms: the older goes, the other in the next tick.
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{14, 18}));
  EXPECT_EQ(r.ticks_of(0x200), (std::vector<int64_t>{15, 19}));  // due 18, a goes then
  EXPECT_TRUE(r.ticks_of(0x300).empty());
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[idle], CAN_CTXMSG_STAT_DONE);
}

TEST(VciCanLine, AnEntryStartedWhileTheTaskRunsCountsItsCycleFromThatMoment) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(5 * kMs + 300 * kUs);
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 3));
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  r.b.run_until(15 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{8, 11, 14}));
}

TEST(VciCanLine, StartMessageWithACountSendsExactlyThatManyFrames) {
  ListRig r;
  const uint32_t a = r.running(0x100, 2, 3);
  r.b.run_until(5 * kMs + 500 * kUs);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(20 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 6}));
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_DONE);
  // Started again, it sends again; stopped, it stops.
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  r.b.run_until(25 * kMs);
  ASSERT_EQ(r.line.scheduler_stop(a), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_DONE);
  r.b.run_until(40 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 6, 22, 24}));
}

TEST(VciCanLine, IncrementsApplyAfterEachFrameAndWrap) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(cyclic(0x7FE, 4, CAN_CTXMSG_INC_ID)), 3),
            VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(
                *r.line.scheduler_add(cyclic(0x1FFFFFFF, 4, CAN_CTXMSG_INC_ID, 0, {1}, true)), 2),
            VCI_OK);
  ASSERT_EQ(
      r.line.scheduler_start(
          *r.line.scheduler_add(cyclic(0x300, 4, CAN_CTXMSG_INC_8, 1, {0xAA, 0xFE, 0x00})), 3),
      VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(cyclic(0x400, 4, CAN_CTXMSG_INC_16, 1,
                                                                {0xAA, 0xFE, 0xFF, 0x07})),
                                   3),
            VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(30 * kMs);
  std::vector<uint32_t> ids;
  std::vector<std::vector<uint8_t>> data8, data16;
  std::vector<uint32_t> ext_ids;
  for (const BusEvent& e : r.frames) {
    const auto d = e.frame->data();
    if (e.frame->extended()) {
      ext_ids.push_back(e.frame->id());
    } else if (e.frame->id() == 0x300) {
      data8.emplace_back(d.begin(), d.end());
    } else if (e.frame->id() == 0x400) {
      data16.emplace_back(d.begin(), d.end());
    } else {
      ids.push_back(e.frame->id());
    }
  }
  EXPECT_EQ(ids, (std::vector<uint32_t>{0x7FE, 0x7FF, 0x000}));  // wraps at 2048
  EXPECT_EQ(ext_ids, (std::vector<uint32_t>{0x1FFFFFFF, 0x0}));  // wraps at 2^29
  using Bytes = std::vector<std::vector<uint8_t>>;
  EXPECT_EQ(data8, (Bytes{{0xAA, 0xFE, 0x00}, {0xAA, 0xFF, 0x00}, {0xAA, 0x00, 0x00}}));
  // Little-endian 16 bits at byte 1: 0xFFFE, 0xFFFF, then 0 (byte 3 is not touched).
  EXPECT_EQ(data16,
            (Bytes{{0xAA, 0xFE, 0xFF, 0x07}, {0xAA, 0xFF, 0xFF, 0x07}, {0xAA, 0x00, 0x00, 0x07}}));
}

TEST(VciCanLine, SixteenBitIncrementsCarryIntoTheHighByte) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_start(
                *r.line.scheduler_add(cyclic(0x400, 1, CAN_CTXMSG_INC_16, 0, {0xFF, 0x00})), 2),
            VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(r.frames.size(), 2u);
  EXPECT_EQ(r.frames[1].frame->data()[0], 0x00);
  EXPECT_EQ(r.frames[1].frame->data()[1], 0x01);
}

TEST(VciCanLine, AddMessageChecksCycleTypeIncrementAndRoom) {
  ListRig r;
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 0)).error(), VCI_E_INVALIDARG);
  ixxat::Clocks small;
  small.cms_max_ticks = 24;
  Rig limited(small);
  ASSERT_EQ(limited.line.open_scheduler(), VCI_OK);
  EXPECT_EQ(limited.line.scheduler_add(cyclic(0x100, 25)).error(), VCI_E_INVALIDARG);
  EXPECT_TRUE(limited.line.scheduler_add(cyclic(0x100, 24)).has_value());
  CANCYCLICTXMSG2 info_msg = cyclic(0x100, 5);
  info_msg.uMsgInfo.Bits.type = CAN_MSGTYPE_INFO;
  EXPECT_EQ(r.line.scheduler_add(info_msg).error(), VCI_E_INVALIDARG);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x800, 5)).error(), VCI_E_INVALIDARG);  // not 11-bit
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 5, 4)).error(), VCI_E_INVALIDARG);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 5, CAN_CTXMSG_INC_8, 2)).error(),
            VCI_E_INVALIDARG);  // 2 bytes: index 0..1
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 5, CAN_CTXMSG_INC_16, 1)).error(),
            VCI_E_INVALIDARG);  // index 0 only
  for (uint32_t k = 0; k < CAN_MAX_CTX_MSGS; ++k) {
    EXPECT_EQ(r.line.scheduler_add(cyclic(0x100 + k, 16, CAN_CTXMSG_INC_16, 0)).value(), k);
  }
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x120, 16)).error(), VCI_E_OUTOFMEMORY);
  ASSERT_EQ(r.line.scheduler_remove(7), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[7], CAN_CTXMSG_STAT_EMPTY);
  EXPECT_EQ(r.line.scheduler_remove(7), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_start(7, 0), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_stop(7), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_start(16, 0), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x120, 16)).value(), 7u);  // the free index again
}

// One frame per tick: the entries' shares 1/wCycleTime add up to at most 1 (VCI guide 5.2.5).
// Every entry in the list counts, started or not; one that would take the total above 1 is
// refused as a full list is, VCI_E_OUTOFMEMORY.
TEST(VciCanLine, AddMessageRefusesAnEntryThatTakesTheTicksAboveOneFramePerTick) {
  ListRig r;
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 2));
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x101, 3)).value(), 1u);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x102, 6)).value(), 2u);  // 1/2 + 1/3 + 1/6 = 1
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x103, 65535)).error(), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x103, 1)).error(), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[3], CAN_CTXMSG_STAT_EMPTY);
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_stop(a), VCI_OK);  // a stopped entry keeps its share
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x103, 65535)).error(), VCI_E_OUTOFMEMORY);
  ASSERT_EQ(r.line.scheduler_remove(2), VCI_OK);  // 1/6 free again
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x103, 7)).value(), 2u);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x104, 42)).value(), 3u);  // 1/2 + 1/3 + 1/7 + 1/42 = 1
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x105, 65535)).error(), VCI_E_OUTOFMEMORY);
  ASSERT_EQ(r.line.scheduler_reset(), VCI_OK);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 1)).value(), 0u);  // one entry takes every tick
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x101, 65535)).error(), VCI_E_OUTOFMEMORY);
}

TEST(VciCanLine, SuspendStopsTheListResumeRestartsItAndResetEmptiesIt) {
  ListRig r;
  const uint32_t a = r.running(0x100, 2);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(r.line.scheduler_suspend(), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(11 * kMs);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(15 * kMs + 500 * kUs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 13, 15}));
  ASSERT_EQ(r.line.scheduler_reset(), VCI_OK);
  const CANSCHEDULERSTATUS s = r.line.scheduler_status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  for (uint8_t stat : s.abMsgStat) {
    EXPECT_EQ(stat, CAN_CTXMSG_STAT_EMPTY);
  }
  r.b.run_until(30 * kMs);
  EXPECT_EQ(r.frames.size(), 4u);
}

TEST(VciCanLine, TheListIsExclusiveAndKeepsItsEntriesWhenReopened) {
  ListRig r;
  EXPECT_EQ(r.line.open_scheduler(), VCI_E_ACCESSDENIED);
  const uint32_t a = r.running(0x100, 2);
  r.b.run_until(3 * kMs);
  r.line.close_scheduler();
  EXPECT_FALSE(r.line.scheduler_open());
  ASSERT_EQ(r.line.open_scheduler(), VCI_OK);  // the task is off again, the entry kept
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(10 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2}));
}

TEST(VciCanLine, TheListKeepsItsRhythmButSendsNothingWhileTheLineIsOffline) {
  ListRig r;
  r.running(0x100, 2);
  r.b.run_until(3 * kMs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  r.b.run_until(7 * kMs);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(11 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 8, 10}));
}

TEST(VciCanLine, CyclicFramesWithSrrAreEchoedWithSrrToV1ChannelsAndV2ChannelsWithSrra) {
  ListRig r;
  Port v2, srra;
  r.channel(v2, true, {0, CAN_FILTER_PASS});
  r.channel(srra, true, {0, CAN_FILTER_PASS | CAN_FILTER_SRRA});
  CANCYCLICTXMSG2 m = cyclic(0x123, 1);
  m.uMsgInfo.Bits.srr = 1;
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(m), 1), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(3 * kMs);
  ASSERT_EQ(r.port.data().size(), 1u);
  EXPECT_EQ(r.port.data()[0].dwTime, 1124u);  // sent at 1 ms, 62 bits
  EXPECT_EQ(r.port.data()[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_TRUE(v2.data().empty());
  ASSERT_EQ(srra.data().size(), 1u);
  EXPECT_EQ(srra.data()[0].uMsgInfo.Bits.srr, 1u);  // the line's own frame, no channel's
  EXPECT_EQ(r.peer.log.received.size(), 1u);
}

TEST(VciCanLine, CyclicFramesShareTheControllerWithTheChannels) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(cyclic(0x100, 1)), 2), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(1 * kMs - 10 * kBit);
  r.send(r.port, msg(0x300, {1, 2, 3, 4, 5, 6, 7, 8}));  // still on the wire at 1 ms
  r.b.run_until(5 * kMs);
  ASSERT_EQ(r.frames.size(), 3u);
  EXPECT_EQ(r.frames[0].frame->id(), 0x300u);
  EXPECT_EQ(r.frames[1].frame->id(), 0x100u);
  EXPECT_EQ(r.frames[1].start.ns(), r.frames[0].end.ns() + 3 * kBit);
  EXPECT_EQ(r.frames[2].start.ns(), 2 * kMs);
}

// ---------------------------------------------------------------- the list on its own

// A line the test switches on and off; it records when the list had a frame for it.
struct ScriptedLine final : ixxat::CyclicList::Line {
  explicit ScriptedLine(SimScheduler& s) : sched(s) {}
  bool online() const override { return on; }
  void frame_due() override { due_at.push_back(sched.now().ns() / kUs); }
  SimScheduler& sched;
  bool on = true;
  std::vector<int64_t> due_at;  // in microseconds
};

struct ListAlone {
  explicit ListAlone(const ixxat::Clocks& c = {}) : clocks(c) {}
  void run_until_us(int64_t us) { sched.run_until(SimTime::from_ns(us * kUs)); }
  ixxat::Clocks clocks;
  SimScheduler sched;
  ScriptedLine line{sched};
  ixxat::CyclicList list{sched, clocks, line};
};

TEST(CyclicList, AFrameTheLineHasNotTakenHoldsTheListBackAndTheEntryKeepsItsRhythm) {
  ListAlone l;
  ASSERT_EQ(l.list.start(*l.list.add(cyclic(0x100, 2)), 0), VCI_OK);
  ASSERT_EQ(l.list.resume(), VCI_OK);
  l.run_until_us(2000);
  EXPECT_EQ(l.line.due_at, (std::vector<int64_t>{2000}));
  const auto first = l.list.take();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->dwMsgId, 0x100u);
  EXPECT_EQ(first->uMsgInfo.Bits.dlc, 2u);
  EXPECT_EQ(first->abData[1], 0x22);
  EXPECT_FALSE(l.list.take().has_value());  // taken once
  // The 4 ms frame is not taken until 6 ms: ticks 5 and 6 pick nothing, tick 7 the entry due
  // at 6, tick 8 the next.
  l.run_until_us(6000);
  EXPECT_EQ(l.line.due_at, (std::vector<int64_t>{2000, 4000}));
  ASSERT_TRUE(l.list.take().has_value());
  l.run_until_us(7000);
  ASSERT_TRUE(l.list.take().has_value());
  l.run_until_us(8000);
  EXPECT_EQ(l.line.due_at, (std::vector<int64_t>{2000, 4000, 7000, 8000}));
}

TEST(CyclicList, WhileTheLineIsOfflineTheTicksPassWithoutFrames) {
  ListAlone l;
  l.line.on = false;
  ASSERT_EQ(l.list.start(*l.list.add(cyclic(0x100, 2)), 0), VCI_OK);
  ASSERT_EQ(l.list.resume(), VCI_OK);
  l.run_until_us(5000);
  EXPECT_TRUE(l.line.due_at.empty());
  EXPECT_FALSE(l.list.take().has_value());
  l.line.on = true;
  l.run_until_us(6000);
  EXPECT_EQ(l.line.due_at, (std::vector<int64_t>{6000}));
}

TEST(CyclicList, TicksCountTheListClockFromTheResume) {
  ixxat::Clocks half_ms;
  half_ms.cms_divisor = 500;  // 1 MHz / 500: a tick every 500 us
  ListAlone l(half_ms);
  l.run_until_us(1234);
  ASSERT_EQ(l.list.start(*l.list.add(cyclic(0x100, 3)), 2), VCI_OK);
  ASSERT_EQ(l.list.resume(), VCI_OK);
  for (int64_t us = 2000; us <= 6000; us += 500) {
    l.run_until_us(us);
    l.list.take();
  }
  EXPECT_EQ(l.line.due_at, (std::vector<int64_t>{2734, 4234}));
  EXPECT_EQ(l.list.status().abMsgStat[0], CAN_CTXMSG_STAT_DONE);  // both repetitions sent
}

TEST(CyclicList, IdentifierIncrementsWrapAndApplyAfterEachFrame) {
  ListAlone l;
  ASSERT_EQ(l.list.start(*l.list.add(cyclic(0x7FF, 1, CAN_CTXMSG_INC_ID)), 0), VCI_OK);
  ASSERT_EQ(l.list.resume(), VCI_OK);
  std::vector<uint32_t> ids;
  for (int64_t us = 1000; us <= 3000; us += 1000) {
    l.run_until_us(us);
    ids.push_back(l.list.take()->dwMsgId);
  }
  EXPECT_EQ(ids, (std::vector<uint32_t>{0x7FF, 0x000, 0x001}));
}

// The admission sum is exact: nine entries of cycle 9 fill the ticks exactly (a sum in doubles
// comes out above 1), and so do 2, 3, 7, 43 and 1806; with 1807 instead of 1806 the sum falls
// 1/3263442 short of 1, less than any further entry's share.
TEST(CyclicList, TheAdmissionSumIsExact) {
  ListAlone l;
  for (uint32_t k = 0; k < 9; ++k) {
    EXPECT_EQ(l.list.add(cyclic(0x100 + k, 9)).value(), k);
  }
  EXPECT_EQ(l.list.add(cyclic(0x110, 65535)).error(), VCI_E_OUTOFMEMORY);
  l.list.reset();
  for (const uint16_t c : std::initializer_list<uint16_t>{2, 3, 7, 43}) {
    ASSERT_TRUE(l.list.add(cyclic(0x100, c)).has_value()) << c;
  }
  EXPECT_EQ(l.list.add(cyclic(0x100, 1806)).value(), 4u);
  EXPECT_EQ(l.list.add(cyclic(0x100, 65535)).error(), VCI_E_OUTOFMEMORY);
  ASSERT_EQ(l.list.remove(4), VCI_OK);
  EXPECT_EQ(l.list.add(cyclic(0x100, 1807)).value(), 4u);
  EXPECT_EQ(l.list.add(cyclic(0x100, 65535)).error(), VCI_E_OUTOFMEMORY);
}

TEST(CyclicList, ClearDropsTheWaitingFrameAndEveryEntry) {
  ListAlone l;
  ASSERT_EQ(l.list.start(*l.list.add(cyclic(0x100, 1)), 0), VCI_OK);
  ASSERT_EQ(l.list.resume(), VCI_OK);
  l.run_until_us(1000);
  l.list.clear();
  EXPECT_FALSE(l.list.take().has_value());
  EXPECT_FALSE(l.list.running());
  EXPECT_EQ(l.list.status().abMsgStat[0], CAN_CTXMSG_STAT_EMPTY);
  l.run_until_us(5000);
  EXPECT_EQ(l.line.due_at, (std::vector<int64_t>{1000}));
  EXPECT_EQ(l.sched.pending(), 0u);  // no tick left scheduled
}

}  // namespace
}  // namespace canemu::model
