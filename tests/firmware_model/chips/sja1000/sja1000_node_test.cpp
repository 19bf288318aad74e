// The SJA1000 with its host driver: frames pulled from a queue as the transmit buffer frees,
// received frames reported and the FIFO emptied, bus-off restarts, and reuse after stop().
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

#include <gtest/gtest.h>

#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "hosted_station.hpp"

namespace canemu::model {
namespace {

using testing::k123;
using testing::kBit;
using testing::kZero;
using Bus = testing::BusFixture;

using Log = testing::NodeLog;

// An SJA1000 node with its own queue and log, at 500 kbit/s.
struct Station : testing::Station<Sja1000Node> {
  using testing::Station<Sja1000Node>::Station;
  void start(bool listen_only = false, int64_t restart_ns = 0) {
    HostedNodeSettings s;
    s.btr0 = 0x00;
    s.btr1 = 0x1C;
    s.listen_only = listen_only;
    s.restart_delay = SimDuration(restart_ns);
    testing::Station<Sja1000Node>::start(s);
  }
};

// TEC at 248 and one bit error planned on the node's next frame: that frame takes it bus-off.
void one_error_from_bus_off(Bus& b, Station& a) {
  a.node.chip().write(sja1000::MOD, sja1000::MOD_RM);
  a.node.chip().write(sja1000::TXERR, 248);
  a.node.chip().write(sja1000::MOD, 0);
  b.plan.add(testing::errors_from(a.node.node(), CanErrorType::bit, 1));
}

TEST(Sja1000Node, PullsFramesAsTheTransmitBufferFreesAndEmptiesTheReceiveFifo) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  a.queue.assign(8, TxFrame{k123, false, false});
  a.node.kick();
  b.run_until(8 * 65 * kBit);
  // 62 bits each, 3 bits of intermission between: ends at 62, 127, 192, ... bit times.
  ASSERT_EQ(r.log.received.size(), 8u);
  ASSERT_EQ(a.log.sent.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(r.log.received[i].at, (62 + 65 * i) * kBit) << i;
    EXPECT_EQ(a.log.sent[i].at, (62 + 65 * i) * kBit) << i;
    EXPECT_EQ(r.log.received[i].frame, k123);
  }
  // Eight frames of 5 FIFO bytes each would overflow a 64-byte FIFO after 12: the driver keeps
  // it empty.
  EXPECT_EQ(r.node.chip().read(sja1000::RMC), 0);
  EXPECT_EQ(b.bus.stats(r.node.node()).frames_received, 8u);
  // One pull at start (empty), one per loaded frame, one that found the queue empty again.
  EXPECT_EQ(a.pulls, 10);
  EXPECT_FALSE(a.node.transmitting());
}

TEST(Sja1000Node, AFrameQueuedWhileIdleStartsAtTheKick) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  b.run_until(1000 * kBit);
  a.send(kZero);
  EXPECT_TRUE(a.node.transmitting());
  b.run_until(2000 * kBit);
  ASSERT_EQ(r.log.received.size(), 1u);
  EXPECT_EQ(r.log.received[0].at, (1000 + 50) * kBit);
}

TEST(Sja1000Node, SelfReceptionAndSingleShotGoThroughTheChipCommands) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  a.send(k123, false, true);
  b.run_until(100 * kBit);
  ASSERT_EQ(a.log.received.size(), 1u);
  EXPECT_TRUE(a.log.received[0].own);
  EXPECT_EQ(a.log.received[0].at, 62 * kBit);
  // Single shot on a bus where nobody acknowledges: one attempt, then dropped.
  r.node.stop();
  a.send(kZero, true);
  b.run_until(300 * kBit);
  EXPECT_EQ(a.log.sent.size(), 1u);
  ASSERT_EQ(a.log.dropped.size(), 1u);
  ASSERT_FALSE(a.log.errors.empty());
  EXPECT_EQ(a.log.errors[0].type, CanErrorType::ack);
  EXPECT_EQ(a.node.chip().read(sja1000::TXERR), 8);
}

// The driver reads ALC after each loss, so the chip captures and reports every one, not only
// the first.
TEST(Sja1000Node, EveryArbitrationLossIsReported) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  r.send(kZero);
  r.send(kZero);
  a.send(k123);
  b.run_until(300 * kBit);
  // k123 departs from kZero at ID.8, bit 3: in the first frame, and in the second, which starts
  // after the first's 50 bits and the intermission.
  const std::vector<std::pair<int64_t, uint16_t>> lost{{4 * kBit, 3}, {(53 + 4) * kBit, 3}};
  EXPECT_EQ(a.log.lost, lost);
  ASSERT_EQ(a.log.sent.size(), 1u);
  EXPECT_EQ(a.log.sent[0].at, (106 + 62) * kBit);
}

TEST(Sja1000Node, AListenOnlyNodeReceivesButNeverAcknowledges) {
  Bus b;
  Station a(b), l(b);
  a.start();
  l.start(true);
  a.send(kZero);
  b.run_until(30 * 70 * kBit);
  EXPECT_FALSE(l.log.received.empty());
  EXPECT_TRUE(a.log.sent.empty());
  EXPECT_EQ(a.node.chip().confinement().state(), ErrorState::passive);
  EXPECT_EQ(a.node.chip().read(sja1000::TXERR), 128);  // a lone transmitter stays at 128
}

TEST(Sja1000Node, RestartsAfterBusOffOnceTheDelayHasPassed) {
  Bus b;
  Station a(b), r(b);
  a.start(false, 1'000'000);  // 1 ms
  r.start();
  b.run_until(100 * kBit);
  // Bus-off by the host writing 255 to TXERR in reset mode (datasheet 6.4.13).
  a.node.chip().write(sja1000::MOD, sja1000::MOD_RM);
  a.node.chip().write(sja1000::TXERR, 255);
  // Restart at 100 bits + 1 ms, then 128 x 11 recessive bits on the idle bus.
  ASSERT_NO_FATAL_FAILURE(testing::expect_bus_off_until_recovery(b, a.log, 100 * kBit, 1'000'000));
  EXPECT_EQ(a.node.chip().read(sja1000::TXERR), 0);
}

TEST(Sja1000Node, WithoutADelayBusOffLastsUntilRestart) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  a.node.chip().write(sja1000::MOD, sja1000::MOD_RM);
  a.node.chip().write(sja1000::TXERR, 255);
  b.run_until(10'000 * kBit);
  EXPECT_TRUE(a.node.chip().confinement().bus_off());
  a.node.restart();
  b.run_until(10'000 * kBit + 128 * 11 * kBit);
  EXPECT_EQ(a.log.states.back(), std::make_pair((10'000 + 128 * 11) * kBit, ErrorState::active));
}

TEST(Sja1000Node, AStoppedNodeIsReusedWithClearedCountersAndStatistics) {
  Bus b;
  Station a(b), r(b);
  a.start(false, 1'000'000);
  r.start();
  a.send(kZero);
  b.run_until(100 * kBit);
  a.node.chip().write(sja1000::MOD, sja1000::MOD_RM);
  a.node.chip().write(sja1000::TXERR, 255);
  a.node.stop();
  EXPECT_TRUE(a.node.reusable());
  EXPECT_FALSE(a.node.running());
  // Reused by someone else: a fresh node, and the restart scheduled before the stop is void.
  Station& again = a;
  again.log = Log{};
  again.start();
  EXPECT_EQ(again.node.chip().read(sja1000::TXERR), 0);
  EXPECT_EQ(again.node.chip().confinement().state(), ErrorState::active);
  EXPECT_EQ(b.bus.stats(again.node.node()).frames_sent, 0u);
  b.run_until(100 * kBit + 2'000'000);
  EXPECT_TRUE(again.log.states.empty());
  again.send(kZero);
  b.run_until(100 * kBit + 2'000'000 + 50 * kBit);
  ASSERT_EQ(r.log.received.size(), 2u);
  EXPECT_EQ(r.log.received[1].at, 100 * kBit + 2'000'000 + 50 * kBit);
}

// A single-shot frame whose bit error takes the node bus-off: the chip is in reset mode when the
// frame is given up, so the driver must not load the next frame (its registers would land in the
// acceptance filter); it loads it once the node is back.
TEST(Sja1000Node, AFrameQueuedThroughBusOffGoesOutAfterRecovery) {
  Bus b;
  Station a(b), r(b);
  a.start(false, 1'000'000);
  r.start();
  one_error_from_bus_off(b, a);
  a.queue.push_back(TxFrame{kZero, true, false});  // single shot: hit, bus-off, dropped
  a.queue.push_back(TxFrame{k123, false, false});  // waits through bus-off
  a.node.kick();
  b.run_until(200 * kBit);
  ASSERT_EQ(a.log.dropped.size(), 1u);
  EXPECT_TRUE(a.node.chip().confinement().bus_off());
  EXPECT_EQ(a.queue.size(), 1u);  // not taken while the chip is in reset mode
  b.run_until(10'000'000);
  ASSERT_EQ(r.log.received.size(), 1u);
  EXPECT_EQ(r.log.received[0].frame, k123);
  // The acceptance filter still takes everything: a receives r's frame.
  r.send(kZero);
  b.run_until(11'000'000);
  ASSERT_FALSE(a.log.received.empty());
  EXPECT_EQ(a.log.received.back().frame, kZero);
}

// a and r started, and a bus-off through one bit error on kZero, which it holds in its buffer.
void bus_off_holding_a_request(Bus& b, Station& a, Station& r) {
  a.start();
  r.start();
  one_error_from_bus_off(b, a);
  a.send(kZero);
  b.run_until(200 * kBit);
  ASSERT_TRUE(a.node.chip().confinement().bus_off());
}

// A node stopped while bus-off with a request held in its buffer (the SJA1000 keeps it through
// bus-off): the next user gets a clean chip, not the old frame.
TEST(Sja1000Node, AReusedNodeDoesNotSendTheLastUsersFrame) {
  Bus b;
  Station a(b), r(b);
  ASSERT_NO_FATAL_FAILURE(bus_off_holding_a_request(b, a, r));
  EXPECT_EQ(a.node.chip().read(sja1000::SR) & sja1000::SR_TBS, 0);  // the request is held
  a.node.stop();
  a.log = Log{};
  a.start();
  b.run_until(1'000'000);
  EXPECT_TRUE(a.log.sent.empty());
  EXPECT_TRUE(r.log.received.empty());
  a.send(k123);
  b.run_until(2'000'000);
  ASSERT_EQ(r.log.received.size(), 1u);
  EXPECT_EQ(r.log.received[0].frame, k123);
}

// Bus-off sets reset mode and keeps the request for after recovery; the host's own reset
// request (go_offline(): MOD.RM written while the chip is already in reset mode) aborts it: the
// buffer is released (SR.TBS) and, back on the bus after recovery, the chip sends nothing.
TEST(Sja1000Node, GoingOffTheBusInBusOffAbortsTheHeldRequest) {
  Bus b;
  Station a(b), r(b);
  ASSERT_NO_FATAL_FAILURE(bus_off_holding_a_request(b, a, r));
  ASSERT_EQ(a.node.chip().read(sja1000::MOD) & sja1000::MOD_RM, sja1000::MOD_RM);
  EXPECT_EQ(a.node.chip().read(sja1000::SR) & sja1000::SR_TBS, 0);  // held
  EXPECT_NE(a.node.controller().pending_tx(), nullptr);
  a.node.go_offline();
  EXPECT_EQ(a.node.chip().read(sja1000::SR) & sja1000::SR_TBS, sja1000::SR_TBS);  // released
  EXPECT_EQ(a.node.controller().pending_tx(), nullptr);
  EXPECT_FALSE(a.node.transmitting());
  // Back on the bus: recovery (128 x 11 bits from 300 bits), then nothing of the old request.
  b.run_until(300 * kBit);
  a.node.go_online();
  const int64_t recovered = (300 + 128 * 11) * kBit;
  b.run_until(recovered);
  EXPECT_EQ(a.log.states.back(), std::make_pair(recovered, ErrorState::active));
  b.run_until(recovered + 1'000 * kBit);
  EXPECT_TRUE(r.log.received.empty());
  EXPECT_TRUE(a.log.sent.empty());
  // Its next frame goes at once.
  a.send(k123);
  b.run_until(recovered + 1'100 * kBit);
  ASSERT_EQ(r.log.received.size(), 1u);
  EXPECT_EQ(r.log.received[0].frame, k123);
  EXPECT_EQ(r.log.received[0].at, recovered + 1'000 * kBit + 62 * kBit);
}

TEST(Sja1000Node, AStoppedNodeTakesNoPartOnTheBus) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  r.node.stop();
  a.send(kZero);
  b.run_until(200 * kBit);
  EXPECT_TRUE(r.log.received.empty());
  EXPECT_TRUE(a.log.sent.empty());  // nobody acknowledges
  EXPECT_EQ(b.bus.stats(r.node.node()).frames_received, 0u);
}

// A babbling idiot (fault injection): copies of one frame back to back for a window, its own
// traffic waiting, the sink told nothing of the copies.
TEST(Sja1000Node, BabblingFloodsBackToBackWhileItsOwnTrafficWaits) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  ASSERT_TRUE(a.node.babble(k123, SimTime::from_ns(300 * kBit)));
  EXPECT_TRUE(a.node.babbling());
  a.send(kZero);  // waits for the window's end
  b.run_until(1000 * kBit);
  // Copies start at 0, 65, 130, 195, 260 bit times (62 bits and 3 of intermission each); the
  // one loaded at 322 (after the window) is not.
  ASSERT_EQ(r.log.received.size(), 6u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(r.log.received[i].frame, k123) << i;
    EXPECT_EQ(r.log.received[i].at, (62 + 65 * i) * kBit) << i;
  }
  EXPECT_EQ(r.log.received[5].frame, kZero);
  EXPECT_EQ(r.log.received[5].at, (325 + encode(kZero).length) * kBit);
  ASSERT_EQ(a.log.sent.size(), 1u);  // only its own frame reached its sink
  EXPECT_EQ(a.log.sent[0].frame, kZero);
  EXPECT_TRUE(a.log.dropped.empty());
  EXPECT_FALSE(a.node.babbling());
  EXPECT_EQ(b.bus.stats(a.node.node()).frames_sent, 6u);  // the bus counts every copy
}

TEST(Sja1000Node, ALoneBabblersLastCopyIsWithdrawnAtTheWindowsEnd) {
  Bus b;
  Station a(b);
  a.start();
  ASSERT_TRUE(a.node.babble(k123, SimTime::from_ns(5'000'000)));
  b.run_until(4'000'000);
  // Nobody acknowledges: the copy repeats, its errors count on the node's own counters and are
  // reported like any bus error.
  EXPECT_EQ(a.node.controller().confinement().tec(), 128);
  EXPECT_FALSE(a.log.errors.empty());
  b.run_until(6'000'000);
  EXPECT_FALSE(a.node.transmitting());  // withdrawn at 5 ms, nothing of its own waits
  EXPECT_TRUE(a.log.dropped.empty());
  EXPECT_TRUE(a.log.sent.empty());
  a.send(kZero);  // its own traffic goes again (unacknowledged, as before)
  EXPECT_TRUE(a.node.transmitting());
}

TEST(Sja1000Node, OnlyANodeOnTheBusBabbles) {
  Bus b;
  Station a(b);
  EXPECT_FALSE(a.node.babble(k123, SimTime::from_ns(1'000'000)));
  EXPECT_FALSE(a.node.babbling());
  a.start();
  a.node.go_offline();
  EXPECT_FALSE(a.node.babble(k123, SimTime::from_ns(1'000'000)));
}

}  // namespace
}  // namespace canemu::model
