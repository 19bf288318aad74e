#include "canemu/firmware_model/bus/can_bus.hpp"

#include <gtest/gtest.h>

#include "test_controller.hpp"

namespace canemu::model::testing {
namespace {

using Fixture = BusFixture;

TEST(CanBus, TwoNodesExchangeFramesBackToBackWithExactTimes) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  a.send(k123);
  b.send(kZero);
  f.run_until(1'000'000);
  // Both start at 0; 0x000 wins at bit 3 (ID8: 0x123 sends recessive) and ends after 50 bits.
  ASSERT_EQ(a.lost.size(), 1u);
  EXPECT_EQ(a.lost[0].bit, 3);
  EXPECT_EQ(a.lost[0].at.ns(), 4 * kBit);
  ASSERT_EQ(a.received.size(), 1u);
  EXPECT_EQ(a.received[0].at.ns(), 50 * kBit);
  EXPECT_EQ(a.received[0].frame, kZero);
  ASSERT_EQ(b.sent.size(), 1u);
  EXPECT_EQ(b.sent[0].at.ns(), 50 * kBit);
  // 0x123 starts after the 3-bit intermission and takes 62 bits.
  ASSERT_EQ(b.received.size(), 1u);
  EXPECT_EQ(b.received[0].at.ns(), (53 + 62) * kBit);
  EXPECT_EQ(b.received[0].frame, k123);
  ASSERT_EQ(a.sent.size(), 1u);
  EXPECT_EQ(a.sent[0].at.ns(), 115 * kBit);
  EXPECT_EQ(a.fc.tec(), 0);
  EXPECT_EQ(b.fc.rec(), 0);
  EXPECT_EQ(f.bus.stats(a.id()).arbitration_lost, 1u);
  EXPECT_EQ(f.bus.stats(b.id()).frames_received, 1u);
  EXPECT_TRUE(a.errors.empty());
  EXPECT_TRUE(b.errors.empty());
}

TEST(CanBus, ThreeWayArbitrationGoesByIdentifierAndReportsTheLosingBit) {
  Fixture f;
  TestController a(f.bus), b(f.bus), c(f.bus), listener(f.bus);
  a.send(frame(0x100, {}));
  b.send(frame(0x0FF, {}));
  c.send(frame(0x101, {}));
  f.run_until(10'000'000);
  // 0x0FF = 000 1111 1111 wins at ID8 (bit 3) against 0x100 and 0x101 = 001 ...; then 0x100
  // beats 0x101 at ID0, which is bit 12 because a stuff bit follows the five zeros of ID7..ID3.
  ASSERT_EQ(listener.received_ids(), (std::vector<uint32_t>{0x0FF, 0x100, 0x101}));
  ASSERT_EQ(a.lost.size(), 1u);
  EXPECT_EQ(a.lost[0].bit, 3);
  ASSERT_EQ(c.lost.size(), 2u);
  EXPECT_EQ(c.lost[0].bit, 3);
  EXPECT_EQ(c.lost[1].bit, 12);
  const EncodedFrame ff = encode(frame(0x0FF, {}));
  const EncodedFrame f100 = encode(frame(0x100, {}));
  const int64_t second_sof = (ff.length + 3) * kBit;
  EXPECT_EQ(listener.received[1].at.ns(), second_sof + f100.length * kBit);
  EXPECT_EQ(c.lost[1].at.ns(), second_sof + 13 * kBit);
}

TEST(CanBus, ElevenBitFrameBeatsTwentyNineBitFrameWithTheSameBaseIdAndDataBeatsRemote) {
  Fixture f;
  TestController std_node(f.bus), ext_node(f.bus), remote_node(f.bus), listener(f.bus);
  FrameSpec r;
  r.id = 0x123;
  r.remote = true;
  remote_node.send(*Frame::create(r));
  ext_node.send(frame(0x123u << 18, {}, true));
  std_node.send(frame(0x123, {}));
  f.run_until(10'000'000);
  ASSERT_EQ(listener.received.size(), 3u);
  EXPECT_FALSE(listener.received[0].frame.remote());
  EXPECT_FALSE(listener.received[0].frame.extended());
  EXPECT_TRUE(listener.received[1].frame.remote());
  EXPECT_TRUE(listener.received[2].frame.extended());
  // The remote frame loses at RTR (bit 12), the extended one at SRR (bit 12) to the data frame.
  ASSERT_GE(ext_node.lost.size(), 1u);
  ASSERT_EQ(remote_node.lost.size(), 1u);
  EXPECT_EQ(ext_node.lost[0].bit, 12);
  EXPECT_EQ(remote_node.lost[0].bit, 12);
  // Then the standard remote frame (IDE dominant) beats the extended one at IDE (bit 13).
  ASSERT_EQ(ext_node.lost.size(), 2u);
  EXPECT_EQ(ext_node.lost[1].bit, 13);
}

TEST(CanBus, SameArbitrationFieldWithDifferentDataCollidesInABitError) {
  Fixture f;
  TestController a(f.bus), b(f.bus), rx(f.bus);
  a.send(frame(0x200, {0x00}));
  b.send(frame(0x200, {0x80}));  // sends recessive first where a sends dominant
  f.run_until(300'000);
  // 0x200 with one data byte goes out as SOF 0, ID 01 00000[1]0000 0[1] (stuff bits after five
  // zeros), IDE, r0, DLC 000[1]1, so the first data bit, where b sends recessive, is bit 22.
  ASSERT_FALSE(b.errors.empty());
  EXPECT_EQ(b.errors[0].type, CanErrorType::bit);
  EXPECT_EQ(b.errors[0].role, ErrorRole::transmitter);
  EXPECT_EQ(b.errors[0].bit, 22);
  EXPECT_EQ(to_string(b.errors[0].field), "data");
  EXPECT_EQ(b.errors[0].tec, 8);
  // a sees b's error flag and detects a bit error of its own when it sends recessive.
  ASSERT_FALSE(a.errors.empty());
  EXPECT_EQ(a.errors[0].type, CanErrorType::bit);
  EXPECT_EQ(a.errors[0].role, ErrorRole::transmitter);
  EXPECT_EQ(a.errors[0].tec, 8);
  EXPECT_GT(a.errors[0].bit, 22);
  // The receiver sees six dominant bits: a stuff error.
  ASSERT_FALSE(rx.errors.empty());
  EXPECT_EQ(rx.errors[0].type, CanErrorType::stuff);
  EXPECT_TRUE(b.lost.empty());
  EXPECT_TRUE(rx.received.empty());
}

TEST(CanBus, LoneNodeClimbsToTec128AndStaysErrorPassiveRetrying) {
  Fixture f;
  TestController lone(f.bus);
  lone.send(kZero);
  // Error-active: ACK error at the ACK slot (bit 41), 6-bit active flag, 8-bit delimiter, 3-bit
  // intermission: a new attempt every 41 + 1 + 6 + 8 + 3 = 59 bits, TEC + 8 each time.
  f.run_until(15 * 59 * kBit + 42 * kBit);
  ASSERT_EQ(lone.errors.size(), 16u);
  for (std::size_t k = 0; k < 16; ++k) {
    EXPECT_EQ(lone.errors[k].type, CanErrorType::ack);
    EXPECT_EQ(lone.errors[k].bit, 41);
    EXPECT_EQ(lone.errors[k].at.ns(), (int64_t(k) * 59 + 42) * kBit);
    EXPECT_EQ(lone.errors[k].tec, 8 * (k + 1));
  }
  EXPECT_EQ(lone.fc.tec(), 128);
  ASSERT_EQ(lone.states.size(), 2u);
  EXPECT_EQ(lone.states[0].state, ErrorState::warning);
  EXPECT_EQ(lone.states[0].at.ns(), (11 * 59 + 42) * kBit);  // 12th error: TEC 96
  EXPECT_EQ(lone.states[1].state, ErrorState::passive);
  EXPECT_EQ(lone.states[1].at.ns(), (15 * 59 + 42) * kBit);
  // Error-passive: passive flag, and 8 bits of suspend transmission: every 67 bits, TEC stays.
  // The 16th attempt already ends error-passive, so the 17th starts after a suspension too.
  const int64_t passive_start = (16 * 59 + 8) * kBit;
  f.run_until(passive_start + 100 * 67 * kBit);
  EXPECT_EQ(lone.fc.tec(), 128);
  EXPECT_EQ(lone.fc.state(), ErrorState::passive);
  EXPECT_EQ(lone.errors.size(), 116u);
  EXPECT_EQ(lone.errors[16].at.ns(), passive_start + 42 * kBit);
  EXPECT_EQ(lone.errors[17].at.ns(), passive_start + (67 + 42) * kBit);
  EXPECT_EQ(lone.states.size(), 2u);  // never bus-off
  EXPECT_TRUE(lone.sent.empty());
}

TEST(CanBus, ListenOnlyNodesGiveNoAck) {
  Fixture f;
  TestController tx, lom;
  lom.listen = true;
  tx.attach_to(f.bus);
  lom.attach_to(f.bus);
  tx.send(kZero);
  f.run_until(10 * 59 * kBit);
  EXPECT_EQ(tx.errors.size(), 10u);
  EXPECT_EQ(tx.errors[0].type, CanErrorType::ack);
  EXPECT_TRUE(lom.received.empty());
  EXPECT_EQ(lom.fc.rec(), 0);  // counters frozen, no error flags
  EXPECT_TRUE(tx.sent.empty());
}

TEST(CanBus, AListenOnlyNodeStillReceivesAcknowledgedFrames) {
  Fixture f;
  TestController tx, rx, lom;
  lom.listen = true;
  for (auto* n : {&tx, &rx, &lom}) {
    n->attach_to(f.bus);
  }
  tx.send(k123);
  f.run_until(200'000);
  ASSERT_EQ(lom.received.size(), 1u);
  EXPECT_EQ(lom.received[0].at.ns(), 62 * kBit);
}

TEST(CanBus, SingleShotFrameIsNotRetried) {
  Fixture f;
  TestController lone(f.bus);
  lone.send(kZero, /*single_shot=*/true);
  f.run_until(1'000'000);
  EXPECT_EQ(lone.errors.size(), 1u);
  ASSERT_EQ(lone.dropped.size(), 1u);
  EXPECT_EQ(lone.dropped[0].ns(), (41 + 1 + 6 + 8) * kBit);  // end of the error delimiter
  EXPECT_EQ(lone.fc.tec(), 8);
  EXPECT_EQ(f.bus.error_frames_on_bus(), 1u);
}

TEST(CanBus, SingleShotFrameThatLosesArbitrationIsDropped) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  a.send(k123, /*single_shot=*/true);
  b.send(kZero);
  f.run_until(1'000'000);
  EXPECT_EQ(a.lost.size(), 1u);
  ASSERT_EQ(a.dropped.size(), 1u);
  EXPECT_EQ(a.dropped[0].ns(), 4 * kBit);  // at the bit it lost, reported at the frame's end
  EXPECT_TRUE(a.sent.empty());
  ASSERT_EQ(b.sent.size(), 1u);
  EXPECT_EQ(b.sent[0].at.ns(), 50 * kBit);
  EXPECT_EQ(f.bus.frames_on_bus(), 1u);
}

// a sends k123 single shot against b's kZero, which wins: k123 lost at bit 3, and the run stops
// at bit 20, before kZero's end (its 50 bits), where the loss is reported.
struct LostSingleShot {
  Fixture f;
  TestController a{f.bus};
  TestController b{f.bus};
  LostSingleShot() {
    a.send(k123, /*single_shot=*/true);
    b.send(kZero);
    f.run_until(20 * kBit);
  }
};

// The single shot left the controller before its loss was reported: the frame queued in its
// place is sent, not dropped.
TEST(CanBus, ASingleShotWithdrawnAfterItLostArbitrationTakesNoOtherFrameWithIt) {
  LostSingleShot t;
  t.a.abort();
  t.a.send(frame(0x300, {}));
  t.f.run_until(1'000'000);
  ASSERT_EQ(t.a.lost.size(), 1u);
  EXPECT_EQ(t.a.lost[0].bit, 3u);
  EXPECT_TRUE(t.a.dropped.empty());
  ASSERT_EQ(t.a.sent.size(), 1u);
  EXPECT_EQ(t.a.sent[0].frame.id(), 0x300u);
  // After kZero (50 bits) and the intermission (3): 0x300 without data, 44 bits and 4 stuff bits.
  EXPECT_EQ(t.a.sent[0].at.ns(), (50 + 3 + 48) * kBit);
  EXPECT_EQ(t.b.received_ids(), std::vector<uint32_t>{0x300});
}

// The same frame queued again in its place, but not single shot: sent, not dropped.
TEST(CanBus, ASingleShotReplacedByTheSameFrameToRepeatIsSent) {
  LostSingleShot t;
  t.a.abort();
  t.a.send(k123);
  t.f.run_until(1'000'000);
  EXPECT_TRUE(t.a.dropped.empty());
  ASSERT_EQ(t.a.sent.size(), 1u);
  EXPECT_EQ(t.a.sent[0].at.ns(), (50 + 3 + 62) * kBit);
}

// A controller that only looks at its pending frame again keeps it: the single shot is dropped.
TEST(CanBus, ASingleShotLookedAtAgainAfterItLostArbitrationIsStillDropped) {
  LostSingleShot t;
  t.a.look_again();
  t.f.run_until(1'000'000);
  ASSERT_EQ(t.a.dropped.size(), 1u);
  EXPECT_EQ(t.a.dropped[0].ns(), 4 * kBit);
  EXPECT_TRUE(t.a.sent.empty());
  EXPECT_EQ(t.f.bus.frames_on_bus(), 1u);
}

TEST(CanBus, SelfReceptionDeliversTheOwnFrame) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  a.send(k123, false, /*self_reception=*/true);
  f.run_until(200'000);
  ASSERT_EQ(a.received.size(), 1u);
  EXPECT_TRUE(a.received[0].own);
  EXPECT_EQ(a.received[0].at.ns(), 62 * kBit);
}

TEST(CanBus, SelfTestModeNeedsNoAcknowledge) {
  Fixture f;
  TestController lone;
  lone.self_test_mode = true;
  lone.attach_to(f.bus);
  lone.send(k123);
  f.run_until(200'000);
  ASSERT_EQ(lone.sent.size(), 1u);
  EXPECT_TRUE(lone.errors.empty());
}

// `node` error-passive (TEC 130) with 0x010 and 0x011 queued: after the first frame it suspends
// its transmission for 8 bits.
void passive_with_two_frames(TestController& node) {
  node.fc.set_counters(130, 0);
  node.send(frame(0x010, {}));
  node.send(frame(0x011, {}));
}

TEST(CanBus, ErrorPassiveTransmitterSuspendsEightBitsAndYields) {
  Fixture f;
  TestController passive(f.bus), active(f.bus), rx(f.bus);
  passive_with_two_frames(passive);
  active.send(frame(0x500, {}));
  f.run_until(1'000'000);
  // After its first frame the passive node must wait 8 bits past the intermission, so the
  // active node's higher identifier goes next; then the passive node's second frame.
  ASSERT_EQ(rx.received_ids(), (std::vector<uint32_t>{0x010, 0x500, 0x011}));
  const int64_t first_len = encode(frame(0x010, {})).length;
  const int64_t second_len = encode(frame(0x500, {})).length;
  EXPECT_EQ(rx.received[1].at.ns(), (first_len + 3 + second_len) * kBit);
  // The active node sent without waiting; the passive one, after its own suspension had ended.
  EXPECT_EQ(rx.received[2].at.ns(),
            (first_len + 3 + second_len + 3 + encode(frame(0x011, {})).length) * kBit);
  EXPECT_EQ(passive.fc.tec(), 128);
}

TEST(CanBus, ANodeMayStartWhileAnErrorPassiveNodeIsSuspended) {
  Fixture f;
  TestController passive(f.bus), late(f.bus), rx(f.bus);
  passive_with_two_frames(passive);
  const int64_t len = encode(frame(0x010, {})).length;
  // The late node's request comes 2 bits into the passive node's suspension: it starts at once.
  const int64_t request = (len + 3 + 2) * kBit;
  f.run_until(request);
  late.send(frame(0x7F0, {}));
  f.run_until(2'000'000);
  ASSERT_EQ(rx.received_ids(), (std::vector<uint32_t>{0x010, 0x7F0, 0x011}));
  EXPECT_EQ(rx.received[1].at.ns(), request + encode(frame(0x7F0, {})).length * kBit);
}

TEST(CanBus, AControllerWithoutABitTimeStaysOffTheBus) {
  Fixture f;
  TestController broken(BitTiming{}), rx;
  broken.attach_to(f.bus);
  rx.attach_to(f.bus);
  broken.send(kZero);
  EXPECT_LE(f.sched.run_until(SimTime::from_ns(1'000'000)), 1u);  // one look for transmitters
  EXPECT_TRUE(rx.received.empty());
  EXPECT_TRUE(broken.errors.empty());
}

TEST(CanBus, ReceiveCounterFallsByOneAndFromPassiveBackTo127) {
  Fixture f;
  TestController tx(f.bus), rx(f.bus);
  rx.fc.set_counters(0, 140);
  tx.send(kZero);
  tx.send(kZero);
  f.run_until(1'000'000);
  EXPECT_EQ(rx.fc.rec(), 126);
  EXPECT_EQ(tx.fc.tec(), 0);
}

}  // namespace
}  // namespace canemu::model::testing
