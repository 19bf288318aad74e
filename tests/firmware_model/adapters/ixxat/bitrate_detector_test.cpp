// Bit-rate detection (bitrate_detector.hpp, ICanControl::DetectBaud): through the line, and
// the BitrateDetector on its own.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/bitrate_detector.hpp"

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
