// Transmission through the VCI firmware (VCI C++ guide 5.2.2, docs/vci.md): frames from
// the channels' transmit FIFOs to the controller, delayed, single-shot and high-priority
// transmission, the distributor's turns.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"

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

TEST(VciCanLine, ADelayedFrameIsHandedOverDwTimeTicksAfterThePreviousOne) {
  Rig r;
  Port p;
  std::vector<BusEvent> events;
  r.b.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  r.init();
  const ChannelId ch = r.channel(p);
  r.peer.start();
  CANMSG2 first = msg(0x123);
  first.dwTime = 5000;  // the first frame after the start is not delayed
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 1000;
  p.tx = {first, delayed, msg(0x125)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].start.ns(), 0);
  // 1000 ticks after 0x123 was handed over (not after it ended at 124 us).
  EXPECT_EQ(events[1].start.ns(), 1000 * kUs);
  EXPECT_EQ(events[1].frame->id(), 0x124u);
  EXPECT_EQ(events[2].start.ns(), events[1].end.ns() + 3 * kBit);  // no delay: after the IFS
  EXPECT_EQ(r.counters(ch).sent, 3u);
}

TEST(VciCanLine, ATransmitDelayAboveTheMaximumIsClamped) {
  ixxat::Clocks clocks;
  clocks.dtx_max_ticks = 300;
  Rig r(clocks);
  Port p;
  std::vector<BusEvent> events;
  r.b.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  r.init();
  r.channel(p);
  r.peer.start();
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 60000;
  p.tx = {msg(0x123), delayed};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].start.ns(), 300 * kUs);
}

TEST(VciCanLine, TheFirstFrameAfterARestartIsNotDelayed) {
  Rig r;
  Port p;
  std::vector<BusEvent> events;
  r.b.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  r.online(p);
  r.send(p, msg(0x123));
  r.b.run_until(200 * kUs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 1000;
  p.tx.push_back(delayed);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].start.ns(), 200 * kUs);
}

TEST(VciCanLine, ASingleShotFrameThatLosesArbitrationIsNotRetriedNorEchoed) {
  Rig r;
  Port p;
  r.init();
  const ChannelId ch = r.channel(p);
  r.peer.start();
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

TEST(VciCanLine, AHighPriorityFrameOfAnotherChannelGoesFirst) {
  Rig r;
  Port a, b;
  r.init();
  r.channel(a);
  r.channel(b);
  r.peer.start();
  CANMSG2 h = msg(0x303);
  h.uMsgInfo.Bits.hpm = 1;
  a.tx = {msg(0x301), msg(0x302)};
  b.tx = {h};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(2 * kMs);
  std::vector<uint32_t> order;
  for (const auto& item : r.peer.log.received) {
    order.push_back(item.frame.id());
  }
  EXPECT_EQ(order, (std::vector<uint32_t>{0x303, 0x301, 0x302}));
}

TEST(VciCanLine, AHighPriorityFrameNeverOvertakesFramesAheadOfItInItsFifo) {
  Rig r;
  Port a, b;
  r.init();
  r.channel(a);
  r.channel(b);
  r.peer.start();
  CANMSG2 h = msg(0x302);
  h.uMsgInfo.Bits.hpm = 1;
  a.tx = {msg(0x301), h};
  b.tx = {msg(0x303)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(2 * kMs);
  std::vector<uint32_t> order;
  for (const auto& item : r.peer.log.received) {
    order.push_back(item.frame.id());
  }
  // 0x302 overtakes the other channel's 0x303, not 0x301 before it.
  EXPECT_EQ(order, (std::vector<uint32_t>{0x301, 0x302, 0x303}));
}

TEST(VciCanLine, TheDistributorServesTheChannelsRoundRobin) {
  Rig r;
  Port a, b;
  r.init();
  const ChannelId ca = r.channel(a);
  const ChannelId cb = r.channel(b);
  r.peer.start();
  a.tx = {msg(0x101), msg(0x102), msg(0x103), msg(0x104)};
  b.tx = {msg(0x201), msg(0x202)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  std::vector<uint32_t> order;
  for (const auto& item : r.peer.log.received) {
    order.push_back(item.frame.id());
  }
  EXPECT_EQ(order, (std::vector<uint32_t>{0x101, 0x201, 0x102, 0x202, 0x103, 0x104}));
  EXPECT_EQ(r.counters(ca).sent, 4u);
  EXPECT_EQ(r.counters(cb).sent, 2u);
}

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
