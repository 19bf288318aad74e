#include "canemu/firmware_model/chips/can_fd/can_fd_controller.hpp"

#include <gtest/gtest.h>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"
#include "hosted_station.hpp"
#include "test_controller.hpp"

namespace canemu::model {
namespace {

CanFdConfig fd_config(uint32_t data_bps = 2'000'000) {
  CanFdConfig c;
  c.nominal =
      *ixxat::decode_btp({0, 500000, 14, 2, 1, 0}, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  const uint16_t quanta = static_cast<uint16_t>(80'000'000 / data_bps);
  c.data = *ixxat::decode_btp({0, data_bps, static_cast<uint16_t>(quanta * 3 / 4),
                               static_cast<uint16_t>(quanta - quanta * 3 / 4), 1, 0},
                              ixxat::kFdDataRange, ixxat::Phase::data);
  return c;
}

Frame fd_frame(uint32_t id, std::size_t len, bool brs) {
  std::vector<uint8_t> data(len);
  for (std::size_t i = 0; i < len; ++i) {
    data[i] = static_cast<uint8_t>(i);
  }
  return *Frame::fd_frame(id, data, false, brs);
}

using Bus = testing::BusFixture;

// Puts the controllers on the bus, in this order, and starts them.
void connect_and_start(Bus& b, std::initializer_list<CanFdController*> controllers) {
  for (CanFdController* c : controllers) {
    c->connect(b.bus);
  }
  for (CanFdController* c : controllers) {
    c->start();
  }
}

TEST(CanFdController, ExchangesFdFramesWithBitRateSwitchInTheirExactTime) {
  Bus b;
  CanFdController a(fd_config()), r(fd_config());
  connect_and_start(b, {&a, &r});
  const Frame f = fd_frame(0x555, 12, true);
  ASSERT_TRUE(a.submit(TxFrame{f}));
  b.run_until(1'000'000);
  auto got = r.receive();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->frame, f);
  // The 12-byte frame of the wire-model example: 122,000 ns at 500 kbit/s / 2 Mbit/s.
  EXPECT_EQ(got->at.ns(), 122'000);
  EXPECT_EQ(a.tx_queued(), 0u);
}

TEST(CanFdController, SixtyFourByteFramesAndClassicFramesShareTheBus) {
  Bus b;
  CanFdController a(fd_config(4'000'000)), r(fd_config(4'000'000));
  connect_and_start(b, {&a, &r});
  ASSERT_TRUE(a.submit(TxFrame{fd_frame(0x100, 64, true)}));
  ASSERT_TRUE(a.submit(TxFrame{*Frame::classic(0x101, std::vector<uint8_t>{1, 2})}));
  b.run_until(2'000'000);
  EXPECT_EQ(r.rx_queued(), 2u);
  EXPECT_EQ(r.receive()->frame.length(), 64u);
  EXPECT_FALSE(r.receive()->frame.fd());
}

TEST(CanFdController, ErrorPassiveTransmitterSetsEsi) {
  Bus b;
  CanFdController a(fd_config()), r(fd_config());
  connect_and_start(b, {&a, &r});
  a.confinement().set_counters(140, 0);
  ASSERT_TRUE(a.submit(TxFrame{fd_frame(0x10, 8, true)}));
  b.run_until(1'000'000);
  auto got = r.receive();
  ASSERT_TRUE(got);
  EXPECT_TRUE(got->frame.esi());
}

TEST(CanFdController, ClassicOnlyNodeDestroysFdFramesWithFormErrors) {
  Bus b;
  CanFdController a(fd_config()), r(fd_config());
  Sja1000 classic;
  a.connect(b.bus);
  r.connect(b.bus);
  classic.connect(b.bus);
  a.start();
  r.start();
  classic.write(sja1000::BTR0, 0x00);
  classic.write(sja1000::BTR1, 0x1C);
  classic.write(sja1000::MOD, 0);
  ASSERT_TRUE(a.submit(TxFrame{fd_frame(0x10, 8, false)}));
  b.run_until(300'000);
  EXPECT_GT(a.confinement().tec(), 0);
  EXPECT_EQ(classic.read(sja1000::ECC) >> 6, 1);  // form error
  EXPECT_EQ(r.rx_queued(), 0u);
}

TEST(CanFdController, ReceiveQueueOverrunsWhenNobodyDrainsIt) {
  Bus b;
  CanFdConfig small = fd_config();
  small.rx_capacity = 2;
  CanFdController a(fd_config()), r(small);
  connect_and_start(b, {&a, &r});
  for (uint32_t i = 0; i < 4; ++i) {
    ASSERT_TRUE(a.submit(TxFrame{fd_frame(0x100 + i, 8, true)}));
  }
  b.run_until(2'000'000);
  EXPECT_EQ(r.rx_queued(), 2u);
  EXPECT_EQ(r.rx_overruns(), 2u);
  EXPECT_TRUE(r.overrun_flag());
  EXPECT_EQ(r.receive()->frame.id(), 0x100u);  // the oldest stay
}

TEST(CanFdController, DataRateMismatchBreaksOnlyFramesWithBitRateSwitch) {
  Bus b;
  CanFdController a(fd_config(2'000'000)), r(fd_config(4'000'000));
  connect_and_start(b, {&a, &r});
  ASSERT_TRUE(a.submit(TxFrame{fd_frame(0x10, 8, false)}));
  b.run_until(1'000'000);
  EXPECT_EQ(r.rx_queued(), 1u);
  ASSERT_TRUE(a.submit(TxFrame{fd_frame(0x11, 8, true), /*single_shot=*/true}));
  b.run_until(2'000'000);
  EXPECT_EQ(r.rx_queued(), 1u);
  EXPECT_GT(r.confinement().rec(), 0);
}

TEST(CanFdController, RecoversFromBusOffByItselfByDefault) {
  Bus b;
  CanFdController a(fd_config()), r(fd_config());
  connect_and_start(b, {&a, &r});
  FaultRule rule;
  rule.fault.error = CanErrorType::bit;
  rule.count = 32;
  b.plan.add(rule);
  ASSERT_TRUE(a.submit(TxFrame{fd_frame(0x10, 8, true)}));
  b.run_until(100'000'000);
  EXPECT_EQ(a.state(), ErrorState::active);
  EXPECT_EQ(r.rx_queued(), 1u);
  EXPECT_EQ(b.bus.stats(a.node()).state_changes.size(), 4u);  // warning, passive, bus-off, active
}

TEST(CanFdController, AbortDropsQueuedFramesAndRejectsFdWhenDisabled) {
  Bus b;
  CanFdConfig classic = fd_config();
  classic.fd_enabled = false;
  CanFdController a(classic);
  a.connect(b.bus);
  EXPECT_FALSE(a.submit(TxFrame{fd_frame(0x10, 8, false)}));
  EXPECT_TRUE(a.submit(TxFrame{*Frame::classic(0x10, std::vector<uint8_t>{})}));
  EXPECT_TRUE(a.submit(TxFrame{*Frame::classic(0x11, std::vector<uint8_t>{})}));
  EXPECT_EQ(a.abort_pending(), 2u);
  EXPECT_EQ(a.tx_queued(), 0u);
}

// A report of a frame done or dropped with nothing pending changes nothing and tells nothing.
TEST(CanFdController, ATransmissionReportedWithNothingPendingIsIgnored) {
  CanFdController c(fd_config());
  testing::NodeLog log;
  c.set_listener(&log);
  c.on_tx_dropped(SimTime::from_ns(1000));
  c.on_tx_done(SimTime::from_ns(2000));
  EXPECT_TRUE(log.dropped.empty());
  EXPECT_TRUE(log.sent.empty());
  EXPECT_EQ(c.tx_queued(), 0u);
}

// r sends 0x200 single shot against a's 0x100 and loses at ID.9; the run stops at 20 us, on
// a's frame, before the loss is reported at its end.
struct LostSingleShot {
  Bus b;
  CanFdController a{fd_config()};
  CanFdController r{fd_config()};
  testing::NodeLog log;  // r's
  LostSingleShot() {
    connect_and_start(b, {&a, &r});
    r.set_listener(&log);
    EXPECT_TRUE(a.submit(TxFrame{fd_frame(0x100, 8, true)}));
    EXPECT_TRUE(r.submit(TxFrame{fd_frame(0x200, 8, true), /*single_shot=*/true}));
    b.run_until(20'000);
  }
};

// Aborted before the frame's end: the frame queued after the abort is sent, not dropped.
TEST(CanFdController, AFrameQueuedAfterALosersAbortIsSent) {
  LostSingleShot t;
  EXPECT_EQ(t.r.abort_pending(), 1u);
  ASSERT_TRUE(t.r.submit(TxFrame{fd_frame(0x300, 8, true)}));
  t.b.run_until(2'000'000);
  EXPECT_TRUE(t.log.dropped.empty());
  ASSERT_EQ(t.log.sent.size(), 1u);
  EXPECT_EQ(t.log.sent[0].frame.id(), 0x300u);
}

// Error-passive before the frame's end, the controller offers the frame again with ESI set:
// still the frame that lost, so it is dropped.
TEST(CanFdController, ASingleShotThatLostIsDroppedThoughItsEsiChangedMeanwhile) {
  LostSingleShot t;
  t.r.confinement().set_counters(130, 0);
  t.b.bus.counters_changed(t.r.node());
  ASSERT_EQ(t.r.state(), ErrorState::passive);
  t.b.run_until(2'000'000);
  EXPECT_EQ(t.log.dropped.size(), 1u);
  EXPECT_TRUE(t.log.sent.empty());
  EXPECT_EQ(t.r.tx_queued(), 0u);
}

// The controller's receive error count is an 8-bit field: it stops at 255.
TEST(CanFdController, ReceiveErrorCounterStopsAt255) {
  CanFdController c(fd_config());
  for (int i = 0; i < 2000; ++i) {
    c.confinement().receiver_severe_error();
  }
  EXPECT_EQ(c.confinement().rec(), 255);
  EXPECT_EQ(c.state(), ErrorState::passive);
  c.confinement().receive_succeeded();
  EXPECT_EQ(c.confinement().rec(), 127);
}

}  // namespace
}  // namespace canemu::model
