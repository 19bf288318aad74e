// Faults on the bus and the counter rules that depend on what each node sees: injected errors of
// every type, bus-off and its recovery, bit-rate mismatch, unplugged nodes, dominant holds.
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "test_controller.hpp"

namespace canemu::model::testing {
namespace {

using Fixture = BusFixture;

// k123 from `tx` to `rx`, sent once with `rule` planned; the bus then runs for 1 ms.
struct OneFault {
  explicit OneFault(const FaultRule& rule) {
    f.plan.add(rule);
    tx.send(k123);
    f.run_until(1'000'000);
  }
  Fixture f;
  TestController tx{f.bus};
  TestController rx{f.bus};
};

// A node's first error: its type and the frame bit (none if it saw no error).
std::optional<std::pair<CanErrorType, uint16_t>> first_error(const TestController& n) {
  if (n.errors.empty()) {
    return std::nullopt;
  }
  return std::make_pair(n.errors[0].type, n.errors[0].bit);
}
using Seen = std::pair<CanErrorType, uint16_t>;

// A frame longer than a word: at its start the bus encodes only as much as a frame without
// errors needs (the first word, docs/bus-engine.md "The head of the encoding"); whatever reads
// further must be given the whole frame.
const Frame kLong =
    *Frame::classic(0x555, std::vector<uint8_t>{0xFF, 0, 0xFF, 0, 0x0F, 0xF0, 1, 8});

TEST(CanBusFaults, ThirtyTwoBitErrorsDriveTheSenderBusOffAndItRecoversAfter128x11Bits) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  f.plan.add(fault_rule(CanErrorType::bit, 32));
  std::vector<BusEvent> events;
  f.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  a.send(k123);
  f.run_until(100'000'000);
  ASSERT_EQ(a.errors.size(), 32u);
  for (std::size_t k = 0; k < 32; ++k) {
    EXPECT_EQ(a.errors[k].type, CanErrorType::bit);
    EXPECT_EQ(a.errors[k].role, ErrorRole::transmitter);
    EXPECT_EQ(a.errors[k].bit, 13);  // default: first bit after the arbitration field
    EXPECT_EQ(a.errors[k].tec, std::min<uint16_t>(256, static_cast<uint16_t>(8 * (k + 1))));
  }
  // Receiver: one stuff error per error frame, never a dominant bit right after its flag.
  EXPECT_EQ(b.errors.size(), 32u);
  EXPECT_EQ(b.errors[0].type, CanErrorType::stuff);
  // States: warning at TEC 96, passive at 128, bus-off at 256, active after recovery.
  ASSERT_EQ(a.states.size(), 4u);
  EXPECT_EQ(a.states[0].state, ErrorState::warning);
  EXPECT_EQ(a.states[1].state, ErrorState::passive);
  EXPECT_EQ(a.states[2].state, ErrorState::bus_off);
  EXPECT_EQ(a.states[2].at, a.errors[31].at);
  EXPECT_EQ(a.states[3].state, ErrorState::active);
  // Recovery: 128 x 11 recessive bits after the last dominant bit of the 32nd error frame, which
  // ends with its 8-bit delimiter.
  ASSERT_GE(events.size(), 33u);
  const BusEvent& last_error = events[31];
  EXPECT_EQ(last_error.kind, BusEvent::Kind::error_frame);
  const int64_t last_dominant = last_error.end.ns() - 8 * kBit;
  EXPECT_EQ(a.states[3].at.ns(), last_dominant + 128 * 11 * kBit);
  EXPECT_EQ(a.fc.tec(), 0);
  // Then the frame, still pending, goes out.
  ASSERT_EQ(b.received.size(), 1u);
  EXPECT_EQ(b.received[0].frame, k123);
  EXPECT_EQ(events[32].kind, BusEvent::Kind::frame);
  EXPECT_EQ(events[32].start, a.states[3].at);
  EXPECT_EQ(b.fc.rec(), 31);  // 32 errors, one success
}

TEST(CanBusFaults, ControllerThatRecoversOnlyOnRestartWaitsForIt) {
  Fixture f;
  TestController a, b;
  a.recovery = BusOffRecovery::on_restart;
  a.attach_to(f.bus);
  b.attach_to(f.bus);
  f.plan.add(fault_rule(CanErrorType::bit, 32));
  a.send(k123);
  f.run_until(50'000'000);
  EXPECT_TRUE(a.fc.bus_off());
  EXPECT_TRUE(b.received.empty());
  const int64_t restart_at = 50'000'000;
  f.bus.restart(a.id());
  f.run_until(100'000'000);
  ASSERT_EQ(a.states.back().state, ErrorState::active);
  EXPECT_EQ(a.states.back().at.ns(), restart_at + 128 * 11 * kBit);
  EXPECT_EQ(b.received.size(), 1u);
}

TEST(CanBusFaults, RecoveryCountsElevenRecessiveBitsBetweenOtherNodesFrames) {
  // While other nodes keep the bus busy, each frame leaves one sequence of 11 recessive bits
  // (ACK delimiter, EOF and intermission), so recovery takes 128 frames.
  Fixture f;
  TestController victim(f.bus), talker(f.bus), listener(f.bus);
  victim.fc.set_counters(256, 0);
  f.bus.restart(victim.id());
  ASSERT_TRUE(victim.fc.recovering());
  for (int i = 0; i < 200; ++i) {
    talker.send(k123);
  }
  f.run_until(127 * 65 * kBit);
  EXPECT_TRUE(victim.fc.bus_off());
  EXPECT_EQ(victim.fc.recovery_sequences_left(), 1u);
  f.run_until(129 * 65 * kBit);
  EXPECT_FALSE(victim.fc.bus_off());
  // One report of the recovery, at the start of the frame after the 128th sequence.
  ASSERT_EQ(victim.states.size(), 1u);
  EXPECT_EQ(victim.states[0].state, ErrorState::active);
  EXPECT_EQ(victim.states[0].at.ns(), 128 * 65 * kBit);
  EXPECT_EQ(f.bus.stats(victim.id()).state_changes.size(), 1u);
}

TEST(CanBusFaults, ASlowOscillatorStillCountsElevenBitsBetweenFrames) {
  // At -3000 ppm the 11 recessive bits between two frames measure 10.97 of the node's bits;
  // counting to the nearest bit, recovery still takes 128 frames.
  Fixture f;
  TestController victim(f.bus), talker(f.bus), listener(f.bus);
  f.bus.set_oscillator_ppm(victim.id(), -3000);
  victim.fc.set_counters(256, 0);
  f.bus.restart(victim.id());
  for (int i = 0; i < 200; ++i) {
    talker.send(k123);
  }
  f.run_until(129 * 65 * kBit);
  EXPECT_FALSE(victim.fc.bus_off());
}

TEST(CanBusFaults, ReceiversRejectAFrameWhoseLastButOneEofBitIsDominant) {
  // EOF bit 5: the transmitter's flag starts at EOF bit 6.
  const OneFault o(fault_rule(CanErrorType::bit, 1, 59));
  EXPECT_EQ(o.rx.errors.size(), 1u);
  EXPECT_EQ(first_error(o.rx), (Seen{CanErrorType::form, 60}));
  EXPECT_EQ(o.rx.received.size(), 1u);  // only the retransmission
}

TEST(CanBusFaults, AnErrorInTheLastEofBitLeavesReceiversWithTheFrameTwice) {
  // The transmitter's flag starts at the last EOF bit: receivers have already accepted the
  // frame (at the last-but-one EOF bit), and the retransmission arrives again, as on a real bus.
  const OneFault o(fault_rule(CanErrorType::bit, 1, 60));
  ASSERT_EQ(o.rx.received.size(), 2u);
  EXPECT_EQ(o.rx.received[0].at.ns(), 62 * kBit);  // delivered at the end of EOF
  EXPECT_EQ(o.tx.sent.size(), 1u);
}

TEST(CanBusFaults, SelfReceptionWorksWhenTheFrameSucceedsDespiteAPassiveFlag) {
  Fixture f;
  TestController tx(f.bus), rx(f.bus);
  TestController slow(f.bus, testing::timing_250k());
  slow.fc.set_counters(0, 200);  // error-passive: its flag does not disturb the others
  tx.send(k123, false, /*self_reception=*/true);
  f.run_until(1'000'000);
  EXPECT_FALSE(slow.errors.empty());
  ASSERT_EQ(tx.received.size(), 1u);
  EXPECT_TRUE(tx.received[0].own);
  EXPECT_EQ(tx.received[0].at.ns(), 62 * kBit);
  EXPECT_EQ(rx.received.size(), 1u);
}

TEST(CanBusFaults, ZeroLengthHoldsChangeNothing) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  f.bus.hold_dominant(SimTime::from_ns(0), SimDuration(0));
  f.run_until(1'000'000);
  EXPECT_TRUE(a.errors.empty());
  EXPECT_EQ(f.bus.error_frames_on_bus(), 0u);
}

TEST(CanBusFaults, CrcErrorOnEveryReceiverEndsInAnAckErrorForTheTransmitter) {
  Fixture f;
  TestController tx(f.bus), r1(f.bus), r2(f.bus);
  f.plan.add(fault_rule(CanErrorType::crc, 1));
  tx.send(k123);
  f.run_until(1'000'000);
  // Receivers with a CRC error give no ACK, so the transmitter detects an ACK error at the ACK
  // slot (bit 53) and flags from the ACK delimiter; the receivers flag one bit later (after the
  // ACK delimiter, as for any CRC error) and their flags end after the transmitter's: +1 each.
  ASSERT_EQ(r1.errors.size(), 1u);
  EXPECT_EQ(r1.errors[0].type, CanErrorType::crc);
  EXPECT_EQ(r1.errors[0].bit, 54);
  EXPECT_EQ(r1.errors[0].rec, 1);
  EXPECT_EQ(r1.fc.rec(), 0);  // then the retransmission succeeds: -1
  EXPECT_EQ(r2.fc.rec(), 0);
  ASSERT_EQ(tx.errors.size(), 1u);
  EXPECT_EQ(tx.errors[0].type, CanErrorType::ack);
  EXPECT_EQ(tx.errors[0].bit, 53);
  EXPECT_EQ(tx.fc.tec(), 8 - 1);
  EXPECT_EQ(r1.received.size(), 1u);
}

TEST(CanBusFaults, InjectedStuffErrorIsDetectedByReceiversAtTheChosenBit) {
  const OneFault o(fault_rule(CanErrorType::stuff, 1, 30));
  EXPECT_EQ(first_error(o.rx), (Seen{CanErrorType::stuff, 30}));
  ASSERT_FALSE(o.rx.errors.empty());
  EXPECT_EQ(o.rx.errors[0].at.ns(), 31 * kBit);
  EXPECT_EQ(o.tx.errors.size(), 1u);
  EXPECT_EQ(o.tx.errors[0].type, CanErrorType::bit);
  EXPECT_EQ(o.tx.fc.tec(), 8 - 1);
  EXPECT_EQ(o.rx.received.size(), 1u);
}

TEST(CanBusFaults, InjectedFormErrorHitsTheCrcDelimiterByDefault) {
  const OneFault o(fault_rule(CanErrorType::form, 1));
  EXPECT_EQ(first_error(o.rx), (Seen{CanErrorType::form, encode(k123).crc_delimiter_index}));
  ASSERT_FALSE(o.rx.errors.empty());
  EXPECT_EQ(to_string(o.rx.errors[0].field), "CRC-del");
}

TEST(CanBusFaults, AckErrorOnOneFrameCostsTheTransmitterEightAndTheReceiverOne) {
  const OneFault o(fault_rule(CanErrorType::ack, 1));
  EXPECT_EQ(o.tx.errors.size(), 1u);
  EXPECT_EQ(first_error(o.tx),
            (Seen{CanErrorType::ack, 53}));  // ACK slot: 62 bits, CRC delimiter at 52
  EXPECT_EQ(o.rx.errors.size(), 1u);
  EXPECT_EQ(first_error(o.rx), (Seen{CanErrorType::form, 54}));  // the flag in the ACK delimiter
  EXPECT_EQ(o.rx.fc.rec(), 0);  // +1, then -1 for the retransmission
  EXPECT_EQ(o.tx.fc.tec(), 7);
  EXPECT_EQ(o.rx.received.size(), 1u);
}

TEST(CanBusFaults, PassiveTransmitterWithAckErrorAndNoDominantBitKeepsItsCounter) {
  Fixture f;
  TestController lone(f.bus);
  lone.fc.set_counters(130, 0);
  lone.send(kZero, /*single_shot=*/true);
  f.run_until(1'000'000);
  ASSERT_EQ(lone.errors.size(), 1u);
  EXPECT_EQ(lone.errors[0].type, CanErrorType::ack);
  EXPECT_EQ(lone.fc.tec(), 130);
}

TEST(CanBusFaults, UnpluggedNodeLeavesTheOtherUnacknowledged) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  f.bus.set_connected(b.id(), false);
  a.send(kZero);
  f.run_until(3 * 59 * kBit - 1);
  EXPECT_EQ(a.errors.size(), 3u);
  EXPECT_EQ(a.errors[0].type, CanErrorType::ack);
  EXPECT_TRUE(b.received.empty());
  EXPECT_TRUE(b.errors.empty());
  f.bus.set_connected(b.id(), true);
  f.run_until(10 * 59 * kBit);
  EXPECT_EQ(b.received.size(), 1u);
  EXPECT_EQ(a.fc.tec(), 3 * 8 - 1);
}

// A node at another bit rate on the bus while `frame` is sent: it destroys frames until it is
// error-passive (NodeAtAnotherBitRateDestroysFramesUntilItIsErrorPassive).
void node_at_another_bit_rate(const Frame& frame) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  TestController slow(f.bus, testing::timing_250k());
  a.send(frame);
  f.run_until(20'000'000);
  // The slow node detects a stuff error at the end of the arbitration field (bit 13) and, while
  // error-active, destroys every frame; it sees a dominant bit after each of its flags: +9.
  ASSERT_GE(slow.errors.size(), 15u);
  EXPECT_EQ(slow.errors[0].type, CanErrorType::stuff);
  EXPECT_EQ(slow.errors[0].bit, 13);
  EXPECT_EQ(a.errors.size(), 15u);  // 15 frames destroyed: REC of the slow node 15 x 9 = 135
  EXPECT_EQ(a.errors[0].type, CanErrorType::bit);
  ASSERT_EQ(b.received.size(), 1u);
  EXPECT_EQ(b.received[0].frame, frame);
  EXPECT_EQ(a.fc.tec(), 15 * 8 - 1);
  EXPECT_EQ(b.fc.rec(), 15 - 1);
  EXPECT_TRUE(slow.received.empty());
  EXPECT_GE(slow.fc.rec(), 128);
  EXPECT_EQ(slow.fc.state(), ErrorState::passive);
}

TEST(CanBusFaults, NodeAtAnotherBitRateDestroysFramesUntilItIsErrorPassive) {
  // Also with a frame longer than a word, whose bits after the first word the error phase plays
  // out once the slow node's flags are passive and leave them alone.
  for (const Frame& frame : {k123, kLong}) {
    SCOPED_TRACE(frame.id());
    node_at_another_bit_rate(frame);
  }
}

TEST(CanBusFaults, OscillatorOffsetBeyondToleranceStopsDecoding) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  f.bus.set_oscillator_ppm(b.id(), 7000);  // beyond 2 x 0.3125 %
  a.send(k123);
  f.run_until(200'000);
  EXPECT_TRUE(b.received.empty());
  ASSERT_FALSE(b.errors.empty());
  f.bus.set_oscillator_ppm(b.id(), 3000);  // within tolerance
  f.run_until(10'000'000);
  EXPECT_EQ(b.received.size(), 1u);
}

TEST(CanBusFaults, DominantHoldOnAnIdleBusRaisesReceiveCountersBySequences) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  f.bus.hold_dominant(SimTime::from_ns(0), SimDuration(100 * kBit));
  f.run_until(1'000'000);
  // Seen as a start of frame: stuff error at the sixth dominant bit (+1), a dominant bit after
  // the flag (+8), then the 14th dominant bit from the flag's start and every 8 more (+8 each:
  // bits 19, 27, ..., 99).
  ASSERT_EQ(a.errors.size(), 1u);
  EXPECT_EQ(a.errors[0].type, CanErrorType::stuff);
  EXPECT_EQ(a.errors[0].bit, 5);
  EXPECT_FALSE(a.errors[0].in_frame);
  EXPECT_EQ(a.fc.rec(), 1 + 8 + 11 * 8);
  EXPECT_EQ(b.fc.rec(), 1 + 8 + 11 * 8);
}

TEST(CanBusFaults, RecessiveStuffBitOverwrittenInArbitrationCostsTheTransmitterNothing) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  // kZero's bit 5 is a recessive stuff bit inside the identifier.
  ASSERT_TRUE(encode(kZero).is_stuff(5));
  f.bus.hold_dominant(SimTime::from_ns(5 * kBit), SimDuration(kBit));
  a.send(kZero);
  f.run_until(300'000);
  ASSERT_GE(a.errors.size(), 1u);
  EXPECT_EQ(a.errors[0].type, CanErrorType::stuff);
  EXPECT_EQ(a.errors[0].role, ErrorRole::transmitter);
  EXPECT_EQ(a.errors[0].tec, 0);
}

// A node that notes the simulated instant it is told of a lost arbitration.
struct ToldAt final : TestController {
  ToldAt(CanBus& bus, const SimScheduler& s) : TestController(bus), sched(&s) {}
  void on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed) override {
    told_at.push_back(sched->now());
    TestController::on_arbitration_lost(at, bit, destuffed);
  }
  const SimScheduler* sched;
  std::vector<SimTime> told_at;
};

// a sends `fa`, b `fb`, which loses to it in the arbitration field; a one-bit dominant hold
// overwrites the recessive stuff bit 5 that both send.
struct HoldInArbitration {
  HoldInArbitration(const Frame& fa, const Frame& fb) {
    f.bus.on_bus_event = [this](const BusEvent& e) { events.push_back(e); };
    f.bus.hold_dominant(SimTime::from_ns(5 * kBit), SimDuration(kBit));
    a.send(fa);
    b.send(fb);
    f.run_until(1'000'000);
  }
  Fixture f;
  TestController a{f.bus};
  ToldAt b{f.bus, f.sched};
  std::vector<BusEvent> events;
};

TEST(CanBusFaults, ANodeStillInArbitrationWhenTheErrorComesIsOneOfItsTransmitters) {
  // 0x000 and 0x001 are alike up to ID0, wire bit 13 (after the stuff bits 5 and 11): at bit 5
  // b still sends. Like a, it detects a stuff error as a transmitter, which costs it nothing
  // (rule 3, exception b), not one as a receiver (REC + 1); and it never lost that arbitration.
  const Frame k001 = *Frame::classic(0x001, {});
  ASSERT_TRUE(encode(kZero).is_stuff(5));
  ASSERT_TRUE(encode(kZero).is_stuff(11));
  const HoldInArbitration h(kZero, k001);
  ASSERT_GE(h.b.errors.size(), 1u);
  EXPECT_EQ(h.b.errors[0].type, CanErrorType::stuff);
  EXPECT_EQ(h.b.errors[0].role, ErrorRole::transmitter);
  EXPECT_EQ(h.b.errors[0].bit, 5);
  EXPECT_EQ(h.b.errors[0].tec, 0);
  EXPECT_EQ(h.b.errors[0].rec, 0);
  EXPECT_EQ(h.a.errors.size(), 1u);
  // Both retry: a wins, b loses at bit 13 of that frame and sends after it.
  ASSERT_GE(h.events.size(), 3u);
  EXPECT_EQ(h.events[0].kind, BusEvent::Kind::error_frame);
  EXPECT_EQ(h.events[1].kind, BusEvent::Kind::frame);
  EXPECT_EQ(h.events[1].transmitter, h.a.id());
  ASSERT_EQ(h.b.lost.size(), 1u);
  EXPECT_EQ(h.b.lost[0].bit, 13);
  EXPECT_EQ(h.b.lost[0].at, h.events[1].start + SimDuration(14 * kBit));
  EXPECT_EQ(h.a.sent.size(), 1u);
  EXPECT_EQ(h.b.sent.size(), 1u);
  EXPECT_EQ(h.b.fc.rec(), 0);
  EXPECT_EQ(h.b.fc.tec(), 0);
}

TEST(CanBusFaults, AnErrorFrameOverBeforeALosersBitLeavesNoLossToReportLate) {
  // Extended identifiers 0 and 1 part at ID0, past the end of the error frame that the hold at
  // bit 5 starts (flag, delimiter and intermission: bit 23). b's one loss is in the
  // retransmission, told at that frame's instant, never ahead of it.
  const Frame e0 = *Frame::classic(0x0, {}, true);
  const Frame e1 = *Frame::classic(0x1, {}, true);
  const HoldInArbitration h(e0, e1);
  ASSERT_GE(h.events.size(), 2u);
  EXPECT_EQ(h.events[0].kind, BusEvent::Kind::error_frame);
  EXPECT_EQ(h.events[1].transmitter, h.a.id());
  ASSERT_EQ(h.b.lost.size(), 1u);
  EXPECT_GT(h.b.lost[0].bit, 23);
  EXPECT_EQ(h.b.lost[0].at, h.events[1].start + SimDuration((int64_t{h.b.lost[0].bit} + 1) * kBit));
  ASSERT_EQ(h.b.told_at.size(), 1u);
  EXPECT_EQ(h.b.told_at[0], h.events[1].end);  // a frame that succeeds tells its losers at its end
  ASSERT_GE(h.b.errors.size(), 1u);
  EXPECT_EQ(h.b.errors[0].role, ErrorRole::transmitter);
  EXPECT_EQ(h.b.sent.size(), 1u);
}

TEST(CanBusFaults, ALateContenderThatLosesReceivesAcknowledgesAndDropsItsSingleShot) {
  // A hold over bit 1, dominant in both 0x000 and 0x001: nothing goes wrong, but the activity is
  // played bit by bit from there with b among its transmitters. b (a single shot) loses at bit 13
  // as it would have: it is told so and drops its frame, and as the only other node it receives
  // a's frame and gives it the ACK.
  Fixture f;
  TestController a(f.bus);
  TestController b(f.bus);
  f.bus.hold_dominant(SimTime::from_ns(kBit), SimDuration(kBit));
  a.send(kZero);
  b.send(*Frame::classic(0x001, {}), /*single_shot=*/true);
  f.run_until(1'000'000);
  ASSERT_EQ(b.lost.size(), 1u);
  EXPECT_EQ(b.lost[0].bit, 13);
  EXPECT_EQ(b.lost[0].at.ns(), 14 * kBit);
  EXPECT_EQ(b.dropped.size(), 1u);
  EXPECT_TRUE(b.sent.empty());
  ASSERT_EQ(a.sent.size(), 1u);
  EXPECT_EQ(a.sent[0].at.ns(), 50 * kBit);
  ASSERT_EQ(b.received.size(), 1u);
  EXPECT_EQ(b.received[0].frame, kZero);
  EXPECT_TRUE(a.errors.empty());
  EXPECT_TRUE(b.errors.empty());
}

TEST(CanBusFaults, ASenderThatLosesArbitrationToAHoldDoesNotSuspendItsNextTransmission) {
  // An error-passive node that transmitted in an error frame waits 8 more bits before it sends
  // again; one that lost arbitration on the way (here to a hold over its recessive ID10) was a
  // receiver of it, and starts again right after the intermission.
  Fixture f;
  TestController a(f.bus), b(f.bus);
  a.fc.set_counters(128, 0);
  std::vector<BusEvent> events;
  f.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  f.bus.hold_dominant(SimTime::from_ns(kBit), SimDuration(kBit));
  a.send(*Frame::classic(0x400, {}));
  f.run_until(1'000'000);
  ASSERT_EQ(a.lost.size(), 1u);
  EXPECT_EQ(a.lost[0].bit, 1);
  EXPECT_EQ(a.lost[0].at.ns(), 2 * kBit);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].kind, BusEvent::Kind::error_frame);
  EXPECT_EQ(events[1].kind, BusEvent::Kind::frame);
  EXPECT_EQ(events[1].start, events[0].end + SimDuration(3 * kBit));
  EXPECT_EQ(a.sent.size(), 1u);
}

TEST(CanBusFaults, AckSuppressionLeavesALoneSenderPassiveAtTec128) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  f.bus.suppress_acks_until(SimTime::from_ns(1'000'000'000));
  a.send(kZero);
  f.run_until(500'000'000);
  EXPECT_EQ(a.fc.tec(), 128);
  EXPECT_EQ(a.fc.state(), ErrorState::passive);
  EXPECT_TRUE(a.sent.empty());
  // While the sender is error-active its flag in the ACK delimiter destroys the frame for b
  // (form error, REC + 1). Once it is passive its flag is recessive: b finds nothing wrong and
  // takes every retransmission as a new frame, as real receivers do. Without its ACK sent, b's
  // counter does not fall.
  EXPECT_EQ(b.errors.size(), 16u);
  EXPECT_EQ(b.fc.rec(), 16);
  ASSERT_GT(b.received.size(), 100u);
  EXPECT_EQ(b.received.back().frame, kZero);
}

TEST(CanBusFaults, BusLoadIsBusyTimeOverTheLastSecond) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  for (int i = 0; i < 10000; ++i) {
    a.send(kZero);
  }
  f.run_until(1'000'000'000);
  // 53 bits per frame (with intermission) back to back: the bus never idles.
  EXPECT_NEAR(f.bus.bus_load_percent(SimTime::from_ns(1'000'000'000)), 100.0, 0.01);
  f.run_until(2'500'000'000);
  EXPECT_EQ(f.bus.bus_load_percent(SimTime::from_ns(2'500'000'000)), 0.0);
}

TEST(CanBusFaults, InjectorActsBeforeArbitrationAtFrameBoundaries) {
  // An injector that unplugs node b from 1 ms on: the first frame that starts after that
  // instant goes unacknowledged.
  struct Unplug final : FaultInjector {
    NodeId node = 0;
    std::vector<int64_t> calls;
    void before_arbitration(SimTime now, CanBus& bus) override {
      calls.push_back(now.ns());
      if (now.ns() >= 1'000'000 && bus.connected(node)) {
        bus.set_connected(node, false);
      }
    }
  };
  SimScheduler sched;
  CanBus bus(sched, "can0");
  Unplug unplug;
  bus.set_injector(&unplug);
  TestController a, b;
  a.attach_to(bus);
  b.attach_to(bus);
  unplug.node = b.id();
  for (int i = 0; i < 20; ++i) {
    a.send(k123);
  }
  sched.run_until(SimTime::from_ns(1'200'000));
  // 65 bits per frame with intermission: frames start at 0, 130 us, ..., 1040 us; the one at
  // 1040 us is the first after 1 ms and fails.
  EXPECT_EQ(b.received.size(), 8u);
  ASSERT_FALSE(a.errors.empty());
  EXPECT_EQ(a.errors[0].type, CanErrorType::ack);
  EXPECT_EQ(a.errors[0].at.ns(), 1'040'000 + 54 * kBit);
  EXPECT_GE(unplug.calls.size(), 9u);
}

TEST(CanBusFaults, AnInjectorIsShownTheWholeEncodingOfAFrameLongerThanAWord) {
  struct Look final : FaultInjector {
    std::vector<std::pair<std::string, std::string>> seen;  // bits and stuff marks
    FrameFault on_frame(const FrameContext& c) override {
      seen.emplace_back(c.bits.to_string(), c.bits.stuff_marks());
      return {};
    }
  };
  ASSERT_GT(encode(kLong).length, 64);
  SimScheduler sched;
  CanBus bus(sched, "can0");
  Look look;
  bus.set_injector(&look);
  TestController a(bus), b(bus);
  // Another long frame first: its encoding's later words stay in the node's room.
  a.send(*Frame::classic(0x0F0, std::vector<uint8_t>(8, 0x5A)));
  a.send(kLong);
  sched.run_until(SimTime::from_ns(1'000'000));
  ASSERT_EQ(look.seen.size(), 2u);
  EXPECT_EQ(look.seen[1].first, encode(kLong).to_string());
  EXPECT_EQ(look.seen[1].second, encode(kLong).stuff_marks());
  EXPECT_EQ(b.received.size(), 2u);
}

TEST(CanBusFaults, FramesThatDifferOnlyPastTheFirstWordCollideWhereTheyDiffer) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  const Frame other =
      *Frame::classic(0x555, std::vector<uint8_t>{0xFF, 0, 0xFF, 0, 0x0F, 0xF0, 1, 9});
  const auto d = Arbitration::first_difference(encode(kLong), encode(other));
  ASSERT_TRUE(d);
  ASSERT_GE(*d, 64);
  ASSERT_TRUE(encode(other).level_at(*d));  // `other` sends recessive there, and sees dominant
  a.send(kLong);
  b.send(other);
  f.run_until(1'000'000);
  ASSERT_FALSE(b.errors.empty());
  EXPECT_EQ(b.errors[0].type, CanErrorType::bit);
  EXPECT_EQ(b.errors[0].bit, *d);
  EXPECT_EQ(b.errors[0].role, ErrorRole::transmitter);
  EXPECT_EQ(b.errors[0].at.ns(), (*d + 1) * kBit);
}

TEST(FaultPlan, MatchesByTransmitterIdentifierFormatAndOccurrence) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  FaultRule r = fault_rule(CanErrorType::bit, 2);
  r.match.transmitter = a.id();
  r.match.id = 0x120;
  r.match.mask = 0x7F0;
  r.match.extended = false;
  r.skip = 1;  // from the second matching frame
  const std::size_t idx = f.plan.add(r);
  a.send(frame(0x123, {}));
  a.send(frame(0x124, {}));
  a.send(frame(0x200, {}));
  b.send(frame(0x125, {}));
  f.run_until(10'000'000);
  EXPECT_EQ(f.plan.rule(idx).hits, 2u);
  EXPECT_EQ(a.errors.size(), 2u);  // the first retry of 0x124 and the one after it
  EXPECT_EQ(b.errors.size(), 2u);
  EXPECT_EQ(a.sent.size(), 3u);
  EXPECT_TRUE(b.sent.size() == 1u);
}

// The timeline of a node's counters: each counted error with its kind and role at its instant,
// the state it gave, the end of bus-off recovery, each count-down by a good frame.
TEST(CanBusFaults, TheCounterTimelineHoldsEveryErrorTheRecoveryAndEachCountDown) {
  Fixture f;
  TestController a(f.bus), b(f.bus);
  f.plan.add(fault_rule(CanErrorType::bit, 32));
  a.send(k123);
  f.run_until(100'000'000);
  ASSERT_EQ(a.errors.size(), 32u);
  const auto& ta = f.bus.stats(a.id()).timeline.samples();
  ASSERT_EQ(ta.size(), 33u);
  for (std::size_t k = 0; k < 32; ++k) {
    EXPECT_EQ(ta[k].at, a.errors[k].at);
    EXPECT_EQ(ta[k].tec, 8 * (k + 1));
    EXPECT_EQ(ta[k].rec, 0);
    EXPECT_EQ(ta[k].cause, CounterCause::error);
    EXPECT_EQ(ta[k].error, CanErrorType::bit);
    EXPECT_EQ(ta[k].role, ErrorRole::transmitter);
    const ErrorState want = k < 11   ? ErrorState::active
                            : k < 15 ? ErrorState::warning
                            : k < 31 ? ErrorState::passive
                                     : ErrorState::bus_off;
    EXPECT_EQ(ta[k].state, want) << k;
  }
  EXPECT_EQ(ta[32].at, a.states[3].at);
  EXPECT_EQ(ta[32].cause, CounterCause::recovered);
  EXPECT_EQ(ta[32].tec, 0);
  EXPECT_EQ(ta[32].state, ErrorState::active);
  EXPECT_EQ(f.bus.stats(a.id()).timeline.forgotten(), 0u);
  // The receiver: one more per error it detected (a stuff error in the transmitter's flag),
  // one less for the frame it finally received.
  const auto& tb = f.bus.stats(b.id()).timeline.samples();
  ASSERT_EQ(tb.size(), 33u);
  for (std::size_t k = 0; k < 32; ++k) {
    EXPECT_EQ(tb[k].rec, b.errors[k].rec);
    EXPECT_EQ(tb[k].cause, CounterCause::error);
    EXPECT_EQ(tb[k].error, CanErrorType::stuff);
    EXPECT_EQ(tb[k].role, ErrorRole::receiver);
  }
  EXPECT_EQ(tb[32].cause, CounterCause::success);
  EXPECT_EQ(tb[32].rec, tb[31].rec - 1);
  EXPECT_EQ(tb[32].at.ns(), b.received[0].at.ns());
}

// Every change is kept, count-downs by good frames too (a plot draws each at its instant), up
// to the newest kSamples.
TEST(CounterTimeline, EveryCountDownIsKeptAndTheOldestAreForgotten) {
  CounterTimeline t;
  const auto sample = [](int64_t ns, uint16_t tec, CounterCause cause) {
    CounterSample s;
    s.at = SimTime::from_ns(ns);
    s.tec = tec;
    s.cause = cause;
    return s;
  };
  t.add(sample(10, 8, CounterCause::error));
  for (uint16_t k = 1; k <= 8; ++k) {
    t.add(sample(10 + k, static_cast<uint16_t>(8 - k), CounterCause::success));
  }
  ASSERT_EQ(t.samples().size(), 9u);
  for (uint16_t k = 1; k <= 8; ++k) {
    EXPECT_EQ(t.samples()[k].at.ns(), 10 + k);
    EXPECT_EQ(t.samples()[k].tec, 8 - k);
  }
  for (std::size_t k = 0; k < CounterTimeline::kSamples; ++k) {
    t.add(sample(100 + static_cast<int64_t>(k), 8, CounterCause::written));
  }
  EXPECT_EQ(t.samples().size(), CounterTimeline::kSamples);
  EXPECT_EQ(t.forgotten(), 9u);
  EXPECT_EQ(t.samples().front().at.ns(), 100);
}

}  // namespace
}  // namespace canemu::model::testing
