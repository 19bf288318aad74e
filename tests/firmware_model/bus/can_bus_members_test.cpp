// The bus keeps the nodes that may take part in a frame (connected, participating, with a usable
// bit time) and their listen-only, self-test and CAN FD settings as a list it rebuilds only after
// attach(), controller_changed() or set_connected(); error states it reads from the counters at
// every frame. Each test changes one of these between two frames and checks that the second
// frame comes out exactly as if nothing had been kept (instants, bits and counters as the engine
// gave before it kept the list).
#include <gtest/gtest.h>

#include <deque>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "test_controller.hpp"

namespace canemu::model::testing {
namespace {

using Fixture = BusFixture;

// k123 is 62 bits: CRC delimiter at bit 52, ACK slot 53; its arbitration field ends at bit 13.
constexpr int64_t kFrame = 62;
constexpr uint16_t kAckSlot = 53;

// The bus after a first k123 from `a` at 0 (received by everybody at bit 62), at bit 100.
void first_frame(Fixture& f, TestController& a) {
  a.send(k123);
  f.run_until(100 * kBit);
  ASSERT_EQ(a.sent.size(), 1u);
  EXPECT_EQ(a.sent[0].at.ns(), kFrame * kBit);
}

// The second k123, sent at bit 100 with `b` off the bus for it: nobody acknowledges, so `a` has
// an ACK error at the end of the ACK slot, and `b` still holds only the first frame.
void expect_unacknowledged(const TestController& a, const TestController& b) {
  ASSERT_EQ(a.errors.size(), 1u);
  EXPECT_EQ(a.errors[0].type, CanErrorType::ack);
  EXPECT_EQ(a.errors[0].at.ns(), (100 + kAckSlot + 1) * kBit);
  EXPECT_EQ(b.received.size(), 1u);
  EXPECT_TRUE(b.errors.empty());
}

// `n` switched to another nominal bit timing, and the bus told.
void switch_timing(Fixture& f, TestController& n, const BitTiming& nominal) {
  n.timing_.nominal = nominal;
  f.bus.controller_changed(n.id());
}

TEST(CanBusMembers, AnUnpluggedReceiverNoLongerAcknowledgesAndOnePluggedBackDoes) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  first_frame(f, a);
  ASSERT_EQ(b.received.size(), 1u);

  f.bus.set_connected(b.id(), false);
  a.send(k123);
  f.run_until(160 * kBit);
  // Nobody acknowledges: an ACK error at the ACK slot (its end: 100 + 54 bits).
  ASSERT_EQ(a.errors.size(), 1u);
  EXPECT_EQ(a.errors[0].type, CanErrorType::ack);
  EXPECT_EQ(a.errors[0].bit, kAckSlot);
  EXPECT_EQ(a.errors[0].at.ns(), (100 + kAckSlot + 1) * kBit);
  EXPECT_EQ(a.errors[0].tec, 8);
  EXPECT_EQ(b.received.size(), 1u);
  EXPECT_TRUE(b.errors.empty());

  // Plugged back during the error frame: the retry after flag (6 bits), delimiter (8) and
  // intermission (3) is acknowledged.
  f.bus.set_connected(b.id(), true);
  f.run_until(1000 * kBit);
  const int64_t retry = 100 + kAckSlot + 1 + 6 + 8 + 3;
  ASSERT_EQ(b.received.size(), 2u);
  EXPECT_EQ(b.received[1].at.ns(), (retry + kFrame) * kBit);
  ASSERT_EQ(a.sent.size(), 2u);
  EXPECT_EQ(a.sent[1].at.ns(), (retry + kFrame) * kBit);
  EXPECT_EQ(a.errors.size(), 1u);
  EXPECT_EQ(a.fc.tec(), 7);
}

TEST(CanBusMembers, AStoppedReceiverAndAListenOnlyOneLeaveTheFrameUnacknowledged) {
  Fixture f;
  TestController a(f.bus), b(f.bus), c(f.bus);
  first_frame(f, a);

  // b stops (no longer participating), c turns listen-only: c still follows the frame, nobody
  // acknowledges it.
  b.running = false;
  f.bus.controller_changed(b.id());
  c.listen = true;
  f.bus.controller_changed(c.id());
  a.send(k123);
  f.run_until(160 * kBit);
  expect_unacknowledged(a, b);
  // c sees a's error flag in the ACK delimiter: a form error a bit later (counted by nobody:
  // a listen-only node keeps its counters).
  ASSERT_EQ(c.errors.size(), 1u);
  EXPECT_EQ(c.errors[0].type, CanErrorType::form);
  EXPECT_EQ(c.errors[0].role, ErrorRole::receiver);
  EXPECT_EQ(c.errors[0].bit, kAckSlot + 1);
  EXPECT_EQ(c.errors[0].at.ns(), (100 + kAckSlot + 2) * kBit);

  // c may acknowledge again: the retry succeeds once c's error frame, a bit behind a's, is over;
  // b, still stopped, gets nothing.
  c.listen = false;
  f.bus.controller_changed(c.id());
  f.run_until(1000 * kBit);
  const int64_t retry = 100 + kAckSlot + 2 + 6 + 8 + 3;
  ASSERT_EQ(c.received.size(), 2u);
  EXPECT_EQ(c.received[1].at.ns(), (retry + kFrame) * kBit);
  EXPECT_EQ(b.received.size(), 1u);
  EXPECT_EQ(a.sent.size(), 2u);
}

TEST(CanBusMembers, AReceiverSwitchedToAnotherBitRateDetectsAStuffErrorAfterArbitration) {
  Fixture f;
  TestController a(f.bus), b(f.bus), c(f.bus);
  first_frame(f, a);

  switch_timing(f, b, testing::timing_250k());
  a.send(k123);
  f.run_until(130 * kBit);
  // b cannot follow 500 kbit/s: a stuff error at the first bit after the arbitration field.
  ASSERT_EQ(b.errors.size(), 1u);
  EXPECT_EQ(b.errors[0].type, CanErrorType::stuff);
  EXPECT_EQ(b.errors[0].role, ErrorRole::receiver);
  EXPECT_EQ(b.errors[0].bit, 13);
  EXPECT_EQ(b.errors[0].at.ns(), (100 + 14) * kBit);
  EXPECT_EQ(b.errors[0].rec, 1);
  // Its error flag is a bit error for a and a stuff error for c, at the first recessive bit of
  // k123 it overwrites (bit 17).
  ASSERT_EQ(a.errors.size(), 1u);
  EXPECT_EQ(a.errors[0].type, CanErrorType::bit);
  EXPECT_EQ(a.errors[0].bit, 17);
  EXPECT_EQ(a.errors[0].at.ns(), (100 + 18) * kBit);
  EXPECT_EQ(a.errors[0].tec, 8);
  ASSERT_EQ(c.errors.size(), 1u);
  EXPECT_EQ(c.errors[0].type, CanErrorType::stuff);
  EXPECT_EQ(c.errors[0].bit, 17);
  // b sees c's and a's flags after its own: 1 + 8.
  EXPECT_EQ(b.fc.rec(), 9);

  // Back at 500 kbit/s during the error frame: the retry is received by both.
  switch_timing(f, b, testing::timing_500k());
  f.run_until(1000 * kBit);
  ASSERT_EQ(b.received.size(), 2u);
  ASSERT_EQ(c.received.size(), 2u);
  EXPECT_EQ(b.received[1].at.ns(), 197 * kBit);
  EXPECT_EQ(c.received[1].at.ns(), 197 * kBit);
  EXPECT_EQ(b.fc.rec(), 8);
}

TEST(CanBusMembers, ANodeAttachedBetweenFramesReceivesTheNextOne) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  first_frame(f, a);
  TestController late;
  late.attach_to(f.bus);
  a.send(k123);
  f.run_until(1000 * kBit);
  ASSERT_EQ(late.received.size(), 1u);
  EXPECT_EQ(late.received[0].at.ns(), (100 + kFrame) * kBit);
  EXPECT_EQ(f.bus.stats(late.id()).frames_received, 1u);
  EXPECT_EQ(b.received.size(), 2u);
}

// A controller that attaches `n` more nodes to its bus from one of its callbacks (which one, a
// test's subclass says), into `more`.
class Attacher : public TestController {
 public:
  Attacher(CanBus& bus, std::deque<TestController>& more)
      : TestController(bus), bus_(bus), more_(more) {}

 protected:
  void attach_more(int n) {
    for (int i = 0; i < n; ++i) {
      more_.emplace_back().attach_to(bus_);
    }
  }

 private:
  CanBus& bus_;
  std::deque<TestController>& more_;
};

TEST(CanBusMembers, ANodeAttachedFromAReceiversCallbackLeavesTheFramesEndWhole) {
  // The frame's end walks its receivers and tells each: a controller that attaches another node
  // from that call (the node vector may move) leaves the walk intact, every receiver told once.
  struct Attaching final : Attacher {
    using Attacher::Attacher;
    void on_frame(SimTime at, const Frame& frame, bool own) override {
      TestController::on_frame(at, frame, own);
      attach_more(4);
    }
  };
  Fixture f;
  std::deque<TestController> more;
  TestController a(f.bus);
  Attaching b(f.bus, more);
  TestController c(f.bus), d(f.bus);
  a.send(k123);
  f.run_until(100 * kBit);
  EXPECT_EQ(b.received.size(), 1u);
  EXPECT_EQ(c.received.size(), 1u);
  EXPECT_EQ(d.received.size(), 1u);
  ASSERT_EQ(more.size(), 4u);
  a.send(k123);
  f.run_until(200 * kBit);
  EXPECT_EQ(d.received.size(), 2u);
  EXPECT_EQ(more[0].received.size(), 1u);  // the nodes attached meanwhile get the next frame
}

TEST(CanBusMembers, ANodeAttachedFromALosersCallbackLeavesTheLossesWhole) {
  // The frame's end reports its losses from the arbitration's list: a loser that attaches nodes
  // from that call (the list's room and the node vector may move) leaves the report intact, the
  // single-shot loser after it told of its loss and of its dropped frame once.
  struct Attaching final : Attacher {
    using Attacher::Attacher;
    void on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed) override {
      TestController::on_arbitration_lost(at, bit, destuffed);
      attach_more(8);
    }
  };
  Fixture f;
  std::deque<TestController> more;
  TestController a(f.bus);
  Attaching b(f.bus, more);
  TestController c(f.bus);
  a.send(*Frame::classic(0x100, std::vector<uint8_t>{}));
  b.send(*Frame::classic(0x300, std::vector<uint8_t>{}));
  c.send(*Frame::classic(0x200, std::vector<uint8_t>{}), true);
  f.run_until(60 * kBit);
  ASSERT_EQ(a.sent.size(), 1u);
  ASSERT_EQ(b.lost.size(), 1u);
  ASSERT_EQ(c.lost.size(), 1u);
  // 0x100 against 0x300 and 0x200: both depart at bit 2 (SOF, then identifier bit 10).
  EXPECT_EQ(b.lost[0].bit, 2);
  EXPECT_EQ(c.lost[0].bit, 2);
  EXPECT_EQ(c.lost[0].at.ns(), 3 * kBit);
  ASSERT_EQ(c.dropped.size(), 1u);
  EXPECT_EQ(c.dropped[0].ns(), 3 * kBit);
  EXPECT_EQ(f.bus.stats(c.id()).tx_dropped, 1u);
  EXPECT_EQ(more.size(), 8u);
  // b tries again, and the nodes attached meanwhile receive its frame.
  f.run_until(200 * kBit);
  ASSERT_EQ(b.sent.size(), 1u);
  EXPECT_EQ(more[7].received.size(), 1u);
}

TEST(CanBusMembers, CountersWrittenWithoutTellingTheBusStillDecideBusOff) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  first_frame(f, a);

  // Bus-off by a direct write the bus is not told of: b is off the bus for the next frame.
  b.fc.set_counters(256, 0);
  a.send(k123);
  f.run_until(160 * kBit);
  expect_unacknowledged(a, b);

  // Back to error-passive (REC 130), again unannounced: b takes part and acknowledges the
  // retry; the reception takes REC from above 127 back to 127.
  b.fc.set_counters(0, 130);
  f.run_until(1000 * kBit);
  const int64_t retry = 100 + kAckSlot + 1 + 6 + 8 + 3;
  ASSERT_EQ(b.received.size(), 2u);
  EXPECT_EQ(b.received[1].at.ns(), (retry + kFrame) * kBit);
  EXPECT_EQ(b.fc.rec(), 127);
}

TEST(CanBusMembers, ANodeMadeErrorPassiveByADirectWriteSendsAPassiveFlag) {
  // As in AReceiverSwitchedToAnotherBitRate...: b cannot follow the frame. Error-passive (by a
  // write the bus is not told of), its flag is recessive: nobody else sees an error, and the
  // frame goes through for a and c.
  Fixture f;
  TestController a(f.bus), b(f.bus), c(f.bus);
  first_frame(f, a);
  switch_timing(f, b, testing::timing_250k());
  b.fc.set_counters(0, 130);
  a.send(k123);
  f.run_until(1000 * kBit);
  ASSERT_EQ(b.errors.size(), 1u);
  EXPECT_EQ(b.errors[0].type, CanErrorType::stuff);
  EXPECT_EQ(b.errors[0].at.ns(), (100 + 14) * kBit);
  EXPECT_EQ(b.errors[0].rec, 131);
  EXPECT_TRUE(a.errors.empty());
  EXPECT_TRUE(c.errors.empty());
  ASSERT_EQ(a.sent.size(), 2u);
  EXPECT_EQ(a.sent[1].at.ns(), (100 + kFrame) * kBit);
  ASSERT_EQ(c.received.size(), 2u);
  EXPECT_EQ(c.received[1].at.ns(), (100 + kFrame) * kBit);
  EXPECT_EQ(b.received.size(), 1u);
  EXPECT_EQ(a.fc.tec(), 0);
}

TEST(CanBusMembers, AReceiverThatDropsCanFdSeesAFormErrorAfterFdf) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  a.fd = true;
  b.fd = true;
  f.bus.controller_changed(a.id());
  f.bus.controller_changed(b.id());
  const Frame fd = *Frame::fd_frame(0x123, std::vector<uint8_t>{1, 2, 3}, false, false);
  const EncodedFrame e = encode(fd);
  ASSERT_EQ(e.length, 87);
  ASSERT_EQ(e.field_begin(Field::fdf), 14);
  a.send(fd);
  f.run_until(200 * kBit);
  ASSERT_EQ(b.received.size(), 1u);
  EXPECT_EQ(b.received[0].at.ns(), 87 * kBit);

  b.fd = false;
  f.bus.controller_changed(b.id());
  a.send(fd);
  f.run_until(230 * kBit);
  // A classic controller takes the recessive FDF for the old reserved bit: a form error at the
  // bit after it; its flag is a bit error for a at the next recessive bit it sends.
  ASSERT_EQ(b.errors.size(), 1u);
  EXPECT_EQ(b.errors[0].type, CanErrorType::form);
  EXPECT_EQ(b.errors[0].bit, 15);
  EXPECT_EQ(b.errors[0].at.ns(), (200 + 16) * kBit);
  ASSERT_EQ(a.errors.size(), 1u);
  EXPECT_EQ(a.errors[0].type, CanErrorType::bit);
  EXPECT_EQ(a.errors[0].bit, 20);
  EXPECT_EQ(a.errors[0].at.ns(), (200 + 21) * kBit);

  // CAN FD again: the retry goes through.
  b.fd = true;
  f.bus.controller_changed(b.id());
  f.run_until(1000 * kBit);
  ASSERT_EQ(b.received.size(), 2u);
  EXPECT_EQ(b.received[1].at.ns(), 325 * kBit);
  EXPECT_EQ(b.errors.size(), 1u);
}

}  // namespace
}  // namespace canemu::model::testing
