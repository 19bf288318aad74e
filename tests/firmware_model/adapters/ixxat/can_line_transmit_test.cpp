// Transmission through the VCI firmware (VCI C++ guide 5.2.2, docs/vci.md): frames from
// the channels' transmit FIFOs to the controller, delayed, single-shot and high-priority
// transmission, the distributor's turns.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "case_name.hpp"

namespace canemu::model {
namespace {

using namespace testing;  // line_rig.hpp, hosted_station.hpp

// ---------------------------------------------------------------- transmission

TEST(VciCanLine, AFrameFromTheTransmitFifoGoesOutAtOnceAndIsCounted) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.send(p, msg(0x123));
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_TXPEND));
  EXPECT_TRUE(p.tx.empty());
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.peer.log.received[0].at, 62 * kBit);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
  EXPECT_TRUE(p.data().empty());  // no srr: no echo
}

// A rig that keeps what happened on the bus (frames with their start and end).
struct WatchedRig : Rig {
  explicit WatchedRig(const ixxat::Clocks& clocks = {}) : Rig(clocks) {
    b.bus.on_bus_event = [this](const BusEvent& e) { events.push_back(e); };
  }
  std::vector<int64_t> starts() const {
    std::vector<int64_t> out;
    for (const BusEvent& e : events) {
      out.push_back(e.start.ns());
    }
    return out;
  }
  std::vector<BusEvent> events;
};

TEST(VciCanLine, ADelayedFrameIsHandedOverDwTimeTicksAfterThePreviousOne) {
  WatchedRig r;
  Port p;
  CANMSG2 first = msg(0x123);
  first.dwTime = 5000;  // the first frame after the start is not delayed
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 1000;
  const ChannelId ch = r.start_with(p, {first, delayed, msg(0x125)});
  r.b.run_until(5 * kMs);
  ASSERT_EQ(r.events.size(), 3u);
  EXPECT_EQ(r.events[0].start.ns(), 0);
  // 1000 ticks after 0x123 was handed over (not after it ended at 124 us).
  EXPECT_EQ(r.events[1].start.ns(), 1000 * kUs);
  EXPECT_EQ(r.events[1].frame->id(), 0x124u);
  EXPECT_EQ(r.events[2].start.ns(), r.events[1].end.ns() + 3 * kBit);  // no delay: after the IFS
  EXPECT_EQ(r.counters(ch).sent, 3u);
}

TEST(VciCanLine, ATransmitDelayAboveTheMaximumIsClamped) {
  ixxat::Clocks clocks;
  clocks.dtx_max_ticks = 300;
  WatchedRig r(clocks);
  Port p;
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 60000;
  r.start_with(p, {msg(0x123), delayed});
  r.b.run_until(5 * kMs);
  EXPECT_EQ(r.starts(), (std::vector<int64_t>{0, 300 * kUs}));
}

TEST(VciCanLine, TheFirstFrameAfterARestartIsNotDelayed) {
  WatchedRig r;
  Port p;
  r.online(p);
  r.send(p, msg(0x123));
  r.b.run_until(200 * kUs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 1000;
  p.tx.push_back(delayed);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  EXPECT_EQ(r.starts(), (std::vector<int64_t>{0, 200 * kUs}));
}

TEST(VciCanLine, ASingleShotFrameThatLosesArbitrationIsNotRetriedNorEchoed) {
  Rig r;
  Port p;
  const ChannelId ch = r.ready(p);
  r.peer.send(kZero);  // identifier 0 wins
  CANMSG2 m = with_srr(msg(0x123));
  m.uMsgInfo.Bits.ssm = 1;
  p.tx = {m};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(10 * kMs);
  EXPECT_TRUE(r.peer.log.received.empty());
  EXPECT_EQ(r.b.bus.stats(r.node.node()).arbitration_lost, 1u);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
  EXPECT_EQ(r.counters(ch).sent, 0u);
  ASSERT_EQ(p.data().size(), 1u);  // the peer's frame, no echo
  EXPECT_EQ(p.data()[0].dwMsgId, 0u);
  EXPECT_EQ(p.data()[0].dwTime, 100u);  // 50 bits
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
}

TEST(VciCanLine, ASingleShotFrameWithoutAcknowledgeIsGivenUpAfterOneAttempt) {
  Rig r;  // the peer stays off the bus: nobody acknowledges
  Port p;
  r.init();
  const ChannelId ch = r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  CANMSG2 m = msg(0x123);
  m.uMsgInfo.Bits.ssm = 1;
  r.send(p, m);
  r.b.run_until(10 * kMs);
  const auto errors = p.of_type(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].dwTime, 108u);  // ACK slot: bit 53, detected at its end, 54 bits
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_ACK);
  EXPECT_EQ(errors[0].abData[1], CAN_STATUS_TXPEND);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
  EXPECT_EQ(r.counters(ch).sent, 0u);
  EXPECT_EQ(r.line.controller_state().tec, 8);
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
}

// Two channels with frames waiting when the line starts: the order the peer receives them in,
// and what each channel counts as sent.
struct Turns {
  const char* name;
  std::vector<CANMSG2> a;  // the first channel's transmit FIFO
  std::vector<CANMSG2> b;
  int64_t run_ns;
  std::vector<uint32_t> order;
  uint32_t sent_a;
  uint32_t sent_b;
};

class VciCanLineTurns : public ::testing::TestWithParam<Turns> {};

TEST_P(VciCanLineTurns, FramesGoOutInTheDistributorsOrder) {
  const Turns& c = GetParam();
  Rig r;
  Port a, b;
  r.init();
  const ChannelId ca = r.channel(a);
  const ChannelId cb = r.channel(b);
  r.peer.start();
  a.tx.assign(c.a.begin(), c.a.end());
  b.tx.assign(c.b.begin(), c.b.end());
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(c.run_ns);
  std::vector<uint32_t> order;
  for (const auto& item : r.peer.log.received) {
    order.push_back(item.frame.id());
  }
  EXPECT_EQ(order, c.order);
  EXPECT_EQ(r.counters(ca).sent, c.sent_a);
  EXPECT_EQ(r.counters(cb).sent, c.sent_b);
}

CANMSG2 high_priority(CANMSG2 m) {
  m.uMsgInfo.Bits.hpm = 1;
  return m;
}

INSTANTIATE_TEST_SUITE_P(
    VciCanLine, VciCanLineTurns,
    ::testing::Values(Turns{"AHighPriorityFrameOfAnotherChannelGoesFirst",
                            {msg(0x301), msg(0x302)},
                            {high_priority(msg(0x303))},
                            2 * kMs,
                            {0x303, 0x301, 0x302},
                            2,
                            1},
                      // 0x302 overtakes the other channel's 0x303, not 0x301 before it.
                      Turns{"AHighPriorityFrameNeverOvertakesFramesAheadOfItInItsFifo",
                            {msg(0x301), high_priority(msg(0x302))},
                            {msg(0x303)},
                            2 * kMs,
                            {0x301, 0x302, 0x303},
                            2,
                            1},
                      Turns{"TheDistributorServesTheChannelsRoundRobin",
                            {msg(0x101), msg(0x102), msg(0x103), msg(0x104)},
                            {msg(0x201), msg(0x202)},
                            5 * kMs,
                            {0x101, 0x201, 0x102, 0x202, 0x103, 0x104},
                            4,
                            2}),
    test_support::CaseName{});

// A listen-only line never sends: the firmware leaves the messages in the transmit FIFO (none
// reaches the controller: no TXPEND, ever) and skips the cyclic list's entries. It still
// receives; initialized to send again, it sends what waited.
TEST(VciCanLine, AListenOnlyLineLeavesWhatItIsGivenInTheFifoAndNeverShowsTxpend) {
  Rig r;
  Port p;
  r.init(kOpAll | CAN_OPMODE_LISTONLY);
  const ChannelId ch = r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  EXPECT_TRUE(r.node.controller().listen_only());
  for (uint32_t id : {0x100u, 0x101u, 0x102u}) {
    r.send(p, msg(id));
  }
  EXPECT_EQ(p.tx.size(), 3u);  // waiting
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
  EXPECT_EQ(r.counters(ch).rejected, 0u);
  EXPECT_EQ(r.counters(ch).sent, 0u);
  EXPECT_EQ(r.node.controller().pending_tx(), nullptr);
  ASSERT_EQ(r.line.open_scheduler(), VCI_OK);
  CANCYCLICTXMSG2 c{};
  c.wCycleTime = 1;
  c.dwMsgId = 0x200;
  c.uMsgInfo.Bits.type = CAN_MSGTYPE_DATA;
  c.uMsgInfo.Bits.dlc = 1;
  const auto index = r.line.scheduler_add(c);
  ASSERT_TRUE(index.has_value());
  ASSERT_EQ(r.line.scheduler_start(*index, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  Peer acker(r.b);  // acknowledges the peer's frame
  acker.start();
  r.peer.send(k123);
  r.b.run_until(10 * kMs);
  EXPECT_TRUE(r.peer.log.received.empty());  // nothing of the line's on the bus
  EXPECT_EQ(r.b.bus.stats(r.node.node()).frames_sent, 0u);
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
  // The peer's frame is received.
  ASSERT_EQ(p.data().size(), 1u);
  EXPECT_EQ(p.data()[0].dwMsgId, 0x123u);
  EXPECT_EQ(p.data()[0].dwTime, static_cast<uint32_t>(62 * kBit / kUs));
  // Initialized to send again, it sends what waited, in order.
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  ASSERT_EQ(r.line.init_line(v1_init(kOpAll)), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(20 * kMs);
  EXPECT_TRUE(p.tx.empty());
  EXPECT_EQ(r.counters(ch).sent, 3u);
  EXPECT_EQ(r.counters(ch).rejected, 0u);
}

}  // namespace
}  // namespace canemu::model
