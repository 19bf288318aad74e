// Bit-rate detection (bitrate_detector.hpp, ICanControl::DetectBaud): through the line, and
// the BitrateDetector on its own.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/bitrate_detector.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model {
namespace {

using namespace testing;  // line_rig.hpp, hosted_station.hpp

// Two SJA1000 stations talking at 250 kbit/s: one sends `frames` frames, the other acknowledges.
struct Traffic250k {
  Traffic250k(testing::BusFixture& b, int frames) : sender(b), acker(b) {
    HostedNodeSettings s;
    s.btr0 = 0x01;
    s.btr1 = 0x1C;
    sender.start(s);
    acker.start(s);
    for (int i = 0; i < frames; ++i) {
      sender.queue.push_back(TxFrame{k123, false, false});
    }
    sender.node.kick();
  }
  testing::Station<Sja1000Node> sender;
  testing::Station<Sja1000Node> acker;
};

std::vector<ixxat::LineInit> btr_table(std::vector<std::pair<uint8_t, uint8_t>> pairs) {
  std::vector<ixxat::LineInit> t;
  for (auto [btr0, btr1] : pairs) {
    ixxat::LineInit e = v1_init();
    e.btr0 = btr0;
    e.btr1 = btr1;
    t.push_back(e);
  }
  return t;
}

TEST(VciCanLine, DetectionFindsTheTableEntryThatDecodesTheTraffic) {
  Rig r;
  Traffic250k traffic(r.b, 200);
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  // 500, 250, 125 kbit/s: the first sees errors in the 250 kbit/s frames and gives way at
  // once; the second receives a frame.
  ASSERT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}, {0x01, 0x1C}, {0x03, 0x1C}}),
                                   milliseconds(10)),
            VCI_OK);
  EXPECT_EQ(r.line.detection().hr, VCI_E_PENDING);
  EXPECT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}}), milliseconds(10)), VCI_E_BUSY);
  EXPECT_EQ(r.line.init_line(v1_init()), VCI_E_BUSY);
  r.b.run_until(5 * kMs);  // well under one entry's wait: errors, not silence, moved it on
  EXPECT_EQ(r.line.detection().hr, VCI_OK);
  EXPECT_EQ(r.line.detection().index, 1u);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  // The detector only listened: every frame was acknowledged by the other station.
  const NodeStats& s = r.b.bus.stats(traffic.sender.node.node());
  EXPECT_EQ(s.errors_as_transmitter.total(), 0u);
  EXPECT_EQ(r.b.bus.stats(r.node.node()).frames_sent, 0u);
  // Then the application initializes the line with what was found.
  EXPECT_EQ(r.line.init_line(btr_table({{0x01, 0x1C}})[0]), VCI_OK);
}

TEST(VciCanLine, DetectionOnASilentBusTimesOutAfterEveryEntrysWait) {
  Rig r;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}, {0x01, 0x1C}}), milliseconds(10)),
            VCI_OK);
  r.b.run_until(20 * kMs - 1);
  EXPECT_EQ(r.line.detection().hr, VCI_E_PENDING);
  r.b.run_until(20 * kMs);
  EXPECT_EQ(r.line.detection().hr, VCI_E_TIMEOUT);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
}

TEST(VciCanLine, DetectionIsRefusedOnlineAndEndedByResetLine) {
  Rig r;
  Port port;
  r.online(port);
  EXPECT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}}), milliseconds(10)),
            VCI_E_INVALID_STATE);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  EXPECT_EQ(r.line.start_detection({}, milliseconds(10)), VCI_E_INVALIDARG);
  ASSERT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}}), milliseconds(10)), VCI_OK);
  EXPECT_EQ(r.line.start_line(), VCI_E_BUSY);
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.line.detection().hr, VCI_E_ABORT);
  r.b.run_until(50 * kMs);
  EXPECT_EQ(r.line.detection().hr, VCI_E_ABORT);  // no timer of the cancelled run fires
}

// ---------------------------------------------------------------- CAN_OPMODE_AUTOBAUD

constexpr int64_t k250kBit = 4'000;  // ns

ixxat::LineInit autobaud_init(uint8_t op_mode = kOpAll) {
  ixxat::LineInit init = v1_init(op_mode | CAN_OPMODE_AUTOBAUD);
  init.btr0 = 0xFF;  // ignored
  init.btr1 = 0xFF;
  return init;
}

// r's line opened, initialized with AUTOBAUD and started, with a channel on `p`.
void start_autobaud(Rig& r, Port& p) {
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(autobaud_init()), VCI_OK);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
}

// Back-to-back frames at 250 kbit/s from t = 0. The line tries 1000, 800 and 500 kbit/s on the
// first three (each sees an error in its frame and gives way at once) and decodes the fourth
// with 250 kbit/s: it locks in at the instant the fourth frame is received (the end of its
// EOF: the engine delivers a frame at its end), delivers that frame and every later one with exact
// time stamps, and from then on is an ordinary line at 250 kbit/s: it acknowledges and sends.
TEST(VciCanLine, AutobaudLocksInOnTheFirstFrameThatDecodesAndRunsAtThatRate) {
  Rig r;
  Port p;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(autobaud_init()), VCI_OK);
  CANLINESTATUS s = r.line.line_status();
  EXPECT_EQ(s.bOpMode, kOpAll | CAN_OPMODE_AUTOBAUD);
  EXPECT_EQ(s.bBtReg0, 0u);  // no rate yet
  EXPECT_EQ(s.bBtReg1, 0u);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::online);
  EXPECT_FALSE(r.line.autobaud_rate_known());
  EXPECT_EQ(r.line.status_flags(), static_cast<uint32_t>(CAN_STATUS_ININIT));
  EXPECT_TRUE(r.node.controller().listen_only());
  Traffic250k traffic(r.b, 10);
  // Frame k (from 0) starts at k x (L + 3) bits and is received at the end of its EOF: L bits
  // from SOF to the end of EOF, 3 of intermission.
  const int64_t bits =
      frame_duration(encode(k123), sja1000::timing_from_btr(0x01, 0x1C)).ns() / k250kBit;
  auto received_at = [&](int64_t k) { return (k * (bits + 3) + bits) * k250kBit; };
  r.b.run_until(received_at(3) - 1);
  EXPECT_FALSE(r.line.autobaud_rate_known());
  EXPECT_TRUE(p.data().empty());
  r.b.run_until(received_at(3));
  EXPECT_TRUE(r.line.autobaud_rate_known());
  EXPECT_EQ(r.line.status_flags(), 0u);
  s = r.line.line_status();
  EXPECT_EQ(s.bOpMode, kOpAll | CAN_OPMODE_AUTOBAUD);
  EXPECT_EQ(s.bBtReg0, CAN_BT0_250KB);
  EXPECT_EQ(s.bBtReg1, CAN_BT1_250KB);
  EXPECT_FALSE(r.node.controller().listen_only());
  r.b.run_until(10 * kMs);
  const auto got = p.data();
  ASSERT_EQ(got.size(), 7u);  // the fourth frame to the tenth
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].dwMsgId, 0x123u);
    EXPECT_EQ(got[k].dwTime, static_cast<uint32_t>(received_at(3 + k) / kUs)) << k;
    EXPECT_EQ(int64_t{got[k].dwTime} * kUs, traffic.acker.log.received[3 + k].at) << k;
  }
  // No ERROR messages for the three frames it could not decode, and nobody saw an error flag.
  EXPECT_TRUE(p.of_type(CAN_MSGTYPE_ERROR).empty());
  EXPECT_EQ(r.b.bus.stats(traffic.sender.node.node()).errors_as_transmitter.total(), 0u);
  // Now it sends at 250 kbit/s.
  r.send(p, msg(0x321, {5}));
  r.b.run_until(20 * kMs);
  ASSERT_EQ(traffic.acker.log.received.size(), 11u);
  EXPECT_EQ(traffic.acker.log.received.back().frame.id(), 0x321u);
  EXPECT_EQ(r.b.bus.stats(r.node.node()).frames_sent, 1u);
}

// On a silent bus an AUTOBAUD line listens with its current rate for as long as the bus stays
// silent: CAN_STATUS_ININIT, no timing in its status, frames posted wait in the FIFO. Traffic
// that starts later is detected then; the posted frame goes out after the lock-in.
TEST(VciCanLine, AutobaudOnASilentBusKeepsListeningUntilTrafficComes) {
  Rig r;
  Port p;
  ASSERT_NO_FATAL_FAILURE(start_autobaud(r, p));
  r.send(p, msg(0x321, {5}));
  r.b.run_until(1'000 * kMs);
  EXPECT_FALSE(r.line.autobaud_rate_known());
  EXPECT_EQ(r.line.status_flags(), static_cast<uint32_t>(CAN_STATUS_ININIT));
  EXPECT_EQ(r.line.line_status().bBtReg0, 0u);
  EXPECT_EQ(r.b.bus.stats(r.node.node()).frames_sent, 0u);
  EXPECT_EQ(p.tx.size(), 1u);  // still in the FIFO
  Traffic250k traffic(r.b, 4);
  const int64_t bits =
      frame_duration(encode(k123), sja1000::timing_from_btr(0x01, 0x1C)).ns() / k250kBit;
  const int64_t lock_in = 1'000 * kMs + (3 * (bits + 3) + bits) * k250kBit;
  r.b.run_until(lock_in);
  EXPECT_TRUE(r.line.autobaud_rate_known());
  ASSERT_EQ(p.data().size(), 1u);
  EXPECT_EQ(p.data()[0].dwTime, static_cast<uint32_t>(lock_in / kUs));
  r.b.run_until(1'100 * kMs);
  ASSERT_EQ(traffic.acker.log.received.size(), 5u);
  EXPECT_EQ(traffic.acker.log.received.back().frame.id(), 0x321u);
  EXPECT_TRUE(p.tx.empty());
}

// Stopping an AUTOBAUD line before it found its rate stops the listening; the next start listens
// again from the first rate. ResetLine leaves it not initialized; InitLine while it listens
// (online) is allowed and replaces the mode.
TEST(VciCanLine, AutobaudListeningEndsWithStopResetAndInit) {
  Rig r;
  Port p;
  ASSERT_NO_FATAL_FAILURE(start_autobaud(r, p));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::offline);
  EXPECT_FALSE(r.node.running());
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  EXPECT_TRUE(r.node.running());
  EXPECT_TRUE(r.node.controller().listen_only());
  EXPECT_EQ(r.line.status_flags(), static_cast<uint32_t>(CAN_STATUS_ININIT));
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  EXPECT_EQ(r.line.start_line(), VCI_E_INVALID_STATE);
  ASSERT_EQ(r.line.init_line(autobaud_init()), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  ASSERT_EQ(r.line.init_line(v1_init()), VCI_OK);  // a fixed rate instead
  EXPECT_TRUE(r.line.autobaud_rate_known());
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  EXPECT_EQ(r.line.status_flags(), 0u);
  EXPECT_FALSE(r.node.controller().listen_only());
}

// ---------------------------------------------------------------- the detector on its own

// The node's owner while the detector listens: passes frames and errors on, counts the ends.
struct Owner final : ControllerEvents {
  void frame_received(SimTime, const Frame&, bool) override { detector->frame_received(); }
  void frame_transmitted(SimTime, const Frame&) override {}
  void transmission_dropped(SimTime, const Frame&) override {}
  void bus_error(const BusErrorEvent&) override {
    ++errors;
    detector->bus_error();
  }
  void state_changed(SimTime, ErrorState, uint16_t, uint16_t) override {}
  void overrun(SimTime, const Frame&) override {}
  ixxat::BitrateDetector* detector = nullptr;
  int errors = 0;
  std::vector<int64_t> finished_at;
};

struct DetectorAlone {
  DetectorAlone() { owner.detector = &detector; }
  HostedNodeSettings btr(uint8_t btr0, uint8_t btr1) const {
    HostedNodeSettings s;
    s.btr0 = btr0;
    s.btr1 = btr1;
    return s;
  }
  testing::BusFixture b;
  Sja1000Node node{b.sched, b.bus};
  Owner owner;
  ixxat::BitrateDetector detector{b.sched, node, owner,
                                  [this] { owner.finished_at.push_back(b.sched.now().ns()); }};
};

TEST(BitrateDetector, EveryEntryListensItsTimeOnASilentBusThenItTimesOut) {
  DetectorAlone d;
  d.detector.start({d.btr(0x00, 0x1C), d.btr(0x01, 0x1C), d.btr(0x03, 0x1C)}, milliseconds(4));
  EXPECT_TRUE(d.detector.running());
  EXPECT_EQ(d.detector.result().hr, VCI_E_PENDING);
  EXPECT_TRUE(d.node.running());
  EXPECT_TRUE(d.node.controller().listen_only());  // made listen-only, whatever it asked
  d.b.run_until(12 * kMs - 1);
  EXPECT_TRUE(d.owner.finished_at.empty());
  d.b.run_until(12 * kMs);
  EXPECT_EQ(d.detector.result().hr, VCI_E_TIMEOUT);
  EXPECT_EQ(d.owner.finished_at, (std::vector<int64_t>{12 * kMs}));
  EXPECT_FALSE(d.detector.running());
  EXPECT_FALSE(d.node.running());  // off the bus
}

TEST(BitrateDetector, AnEntryThatSeesErrorsGivesWayAndTheOneThatDecodesAFrameWins) {
  DetectorAlone d;
  Traffic250k traffic(d.b, 20);
  d.detector.start({d.btr(0x00, 0x1C), d.btr(0x01, 0x1C)}, milliseconds(10));
  d.b.run_until(10 * kMs);
  EXPECT_EQ(d.detector.result().hr, VCI_OK);
  EXPECT_EQ(d.detector.result().index, 1u);
  ASSERT_EQ(d.owner.finished_at.size(), 1u);
  EXPECT_LT(d.owner.finished_at[0], 10 * kMs);  // errors, not silence, moved it on
  EXPECT_GE(d.owner.errors, 1);
  EXPECT_FALSE(d.node.running());
  // Listen-only all along: the sender never missed an acknowledgement or saw an error flag.
  EXPECT_EQ(d.b.bus.stats(traffic.sender.node.node()).errors_as_transmitter.total(), 0u);
}

TEST(BitrateDetector, CancelEndsItWithAbortAndNoTimerOfItFiresLater) {
  DetectorAlone d;
  d.detector.start({d.btr(0x00, 0x1C)}, milliseconds(4));
  d.b.run_until(1 * kMs);
  d.detector.cancel();
  EXPECT_EQ(d.detector.result().hr, VCI_E_ABORT);
  EXPECT_EQ(d.owner.finished_at, (std::vector<int64_t>{1 * kMs}));
  EXPECT_FALSE(d.node.running());
  d.b.run_until(50 * kMs);
  EXPECT_EQ(d.owner.finished_at.size(), 1u);
  d.detector.cancel();  // not running: nothing happens
  EXPECT_EQ(d.owner.finished_at.size(), 1u);
}

}  // namespace
}  // namespace canemu::model
