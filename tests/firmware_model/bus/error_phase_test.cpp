// The bit-by-bit error phase on its own (docs/bus-engine.md, "Errors: what is bit-exact"):
// participants as CanBus builds them at a start of frame, the actions and instants the phase
// gives. All at 500 kbit/s (2000 ns a bit), start of frame at 0.
//
// kZero, the all-zero standard frame, on the wire (wire_encoding.hpp's worked example):
//   bits  0-4 SOF, ID10..7      5 stuff   6-10 ID6..2        11 stuff  12-16 ID1, ID0, RTR, IDE, r0
//   17 stuff  18-21 DLC  22 CRC14  23 stuff  24-39 CRC (stuff at 29, 35)
//   40 CRC delimiter  41 ACK slot  42 ACK delimiter  43-49 EOF            (50 bits)
#include "canemu/firmware_model/bus/error_phase.hpp"

#include <gtest/gtest.h>

#include <ostream>
#include <vector>

#include "test_controller.hpp"

namespace canemu::model {
namespace {

using testing::kBit;
using testing::kZero;
using Kind = ErrorPhase::Action::Kind;
using Tx = ErrorPhase::Outcome::Transmitter;

const EncodedFrame kZeroBits = encode(kZero);

BusParticipant sender(NodeId id, bool passive = false) {
  BusParticipant p;
  p.id = id;
  p.transmitter = true;
  p.passive = passive;
  p.bits = &kZeroBits;
  return p;
}

BusParticipant receiver(NodeId id, bool acks = true) {
  BusParticipant p;
  p.id = id;
  p.acks = acks;
  return p;
}

ErrorPhase::Setup frame_setup(uint16_t first_bit) {
  return {SimTime{}, &kZeroBits, testing::timing_500k(), testing::timing_500k(), first_bit, {}};
}

// Who did what, as which role, at which frame bit. step() also checks that the action's instant
// is the end of that bit (start of frame at 0).
struct Step {
  NodeId node;
  Kind kind;
  CanErrorType type;
  ErrorRole role;
  uint16_t bit;
  friend bool operator==(const Step&, const Step&) = default;
  friend std::ostream& operator<<(std::ostream& os, const Step& s) {
    return os << "{node " << s.node << ", kind " << static_cast<int>(s.kind) << ", "
              << to_string(s.type) << ", role " << static_cast<int>(s.role) << ", bit " << s.bit
              << "}";
  }
};
Step step(const ErrorPhase::Action& a) {
  EXPECT_EQ(a.at.ns(), (a.bit + 1) * kBit) << "node " << a.node << " bit " << a.bit;
  return {a.node, a.kind, a.type, a.role, a.bit};
}
constexpr ErrorRole kTx = ErrorRole::transmitter;
constexpr ErrorRole kRx = ErrorRole::receiver;

TEST(ErrorPhase, TheDynamicallyStuffedPartOfAClassicFrameEndsAtTheCrcDelimiter) {
  EXPECT_EQ(ErrorPhase::stuffed_end(kZeroBits), 40);
}

TEST(ErrorPhase, ALoneActiveTransmitterFlagsTheAckErrorAndEndsAfterItsDelimiter) {
  const std::vector<BusParticipant> parts{sender(0)};
  const ErrorPhase::Outcome out = ErrorPhase(frame_setup(41), parts).run();
  // ACK error at bit 41 (recessive ACK slot), flag 42-47, delimiter 48-55.
  ASSERT_EQ(out.actions.size(), 1u);
  const ErrorPhase::Action& a = out.actions[0];
  EXPECT_EQ(step(a), (Step{0, Kind::error, CanErrorType::ack, kTx, 41}));
  EXPECT_TRUE(a.count);  // rule 3: error-active, the exception does not apply
  EXPECT_TRUE(a.in_frame);
  EXPECT_EQ(a.field, Field::ack_slot);
  EXPECT_EQ(a.destuffed_bit, 35);  // 41 less the six stuff bits
  EXPECT_FALSE(a.extended);
  EXPECT_EQ(out.end_bit, 55u);
  EXPECT_EQ(out.end.ns(), 56 * kBit);
  EXPECT_EQ(out.ifs_end.ns(), 59 * kBit);
  EXPECT_EQ(out.dominant_end.ns(), 48 * kBit);  // the flag's last bit, 47
  ASSERT_EQ(out.transmitters.size(), 1u);
  EXPECT_EQ(out.transmitters[0], (Tx{0, /*sent=*/false, /*lost_arbitration=*/false}));
}

TEST(ErrorPhase, AnErrorPassiveTransmitterWithOnlyAnAckErrorIsNotCounted) {
  const std::vector<BusParticipant> parts{sender(0, true)};
  const ErrorPhase::Outcome out = ErrorPhase(frame_setup(41), parts).run();
  // Rule 3, exception a: no dominant bit during its passive flag (42-47, recessive).
  ASSERT_EQ(out.actions.size(), 1u);
  EXPECT_EQ(out.actions[0].kind, Kind::error);
  EXPECT_EQ(out.actions[0].type, CanErrorType::ack);
  EXPECT_FALSE(out.actions[0].count);
  EXPECT_EQ(out.end_bit, 55u);
  EXPECT_EQ(out.end.ns(), 56 * kBit);
}

TEST(ErrorPhase, FlagsSuperposeAndTheFirstDetectorSeesADominantBitAfterItsFlag) {
  // Receiver 1 detects a stuff error at bit 20 and flags 21-26. The transmitter's recessive
  // stuff bit 23 is overwritten: bit error. Receiver 2 has seen bits 18-23 dominant: stuff
  // error at 23. Both flag 24-29; receiver 1 sees bit 27 dominant after its flag (rule 2).
  std::vector<BusParticipant> parts{sender(0), receiver(1), receiver(2)};
  parts[1].planned = std::make_pair(CanErrorType::stuff, uint16_t{20});
  const ErrorPhase::Outcome out = ErrorPhase(frame_setup(20), parts).run();
  ASSERT_EQ(out.actions.size(), 4u);
  const auto& r1 = out.actions[0];
  EXPECT_EQ(step(r1), (Step{1, Kind::error, CanErrorType::stuff, kRx, 20}));
  EXPECT_EQ(r1.field, Field::dlc);
  EXPECT_EQ(r1.destuffed_bit, 17);
  const auto& tx = out.actions[1];
  EXPECT_EQ(step(tx), (Step{0, Kind::error, CanErrorType::bit, kTx, 23}));
  EXPECT_EQ(tx.field, Field::crc);  // a stuff bit belongs to the field before it
  EXPECT_EQ(tx.destuffed_bit, 20);
  EXPECT_EQ(step(out.actions[2]), (Step{2, Kind::error, CanErrorType::stuff, kRx, 23}));
  EXPECT_EQ(step(out.actions[3]), (Step{1, Kind::severe, CanErrorType::bit, kRx, 27}));
  // Everybody's delimiter: 30-37.
  EXPECT_EQ(out.end_bit, 37u);
  EXPECT_EQ(out.end.ns(), 38 * kBit);
  EXPECT_EQ(out.ifs_end.ns(), 41 * kBit);
  EXPECT_EQ(out.dominant_end.ns(), 30 * kBit);
  ASSERT_EQ(out.transmitters.size(), 1u);
  EXPECT_FALSE(out.transmitters[0].sent);
}

TEST(ErrorPhase, ReceiversKeepAFrameWhoseTransmitterFlagsAnErrorInTheLastEofBits) {
  // The transmitter detects a bit error at bit 48 (EOF 6): the receiver validated the frame at
  // 48 and gets it at the end of EOF, its REC decremented (it sent the ACK).
  std::vector<BusParticipant> parts{sender(0), receiver(1)};
  parts[0].planned = std::make_pair(CanErrorType::bit, uint16_t{48});
  const ErrorPhase::Outcome out = ErrorPhase(frame_setup(48), parts).run();
  ASSERT_EQ(out.actions.size(), 2u);
  EXPECT_EQ(out.actions[0].node, 0u);
  EXPECT_EQ(out.actions[0].kind, Kind::error);
  EXPECT_EQ(out.actions[0].at.ns(), 49 * kBit);
  EXPECT_EQ(out.actions[1].node, 1u);
  EXPECT_EQ(out.actions[1].kind, Kind::rx_ok);
  EXPECT_TRUE(out.actions[1].count);
  EXPECT_EQ(out.actions[1].at.ns(), 50 * kBit);
  // Flag 49-54, delimiter 55-62.
  EXPECT_EQ(out.end_bit, 62u);
  EXPECT_EQ(out.end.ns(), 63 * kBit);
  EXPECT_FALSE(out.transmitters[0].sent);
}

TEST(ErrorPhase, AListenOnlyReceiversErrorDisturbsNobodyAndTheFrameSucceeds) {
  // The listen-only node cannot follow the frame (stuff error at the end of arbitration, not
  // counted); its flag is never driven, so the others see a clean frame.
  std::vector<BusParticipant> parts{sender(0), receiver(1, false), receiver(2)};
  parts[1].drives = false;
  parts[1].decodes = false;
  parts[1].planned = std::make_pair(CanErrorType::stuff, uint16_t{15});
  const ErrorPhase::Outcome out = ErrorPhase(frame_setup(15), parts).run();
  ASSERT_EQ(out.actions.size(), 3u);
  EXPECT_EQ(out.actions[0].node, 1u);
  EXPECT_EQ(out.actions[0].kind, Kind::error);
  EXPECT_FALSE(out.actions[0].count);
  EXPECT_EQ(out.actions[0].at.ns(), 16 * kBit);
  // Both at the end of EOF: the receiver's validation was found at bit 48, the transmitter's
  // success at 49.
  EXPECT_EQ(out.actions[1].node, 2u);
  EXPECT_EQ(out.actions[1].kind, Kind::rx_ok);
  EXPECT_EQ(out.actions[1].at.ns(), 50 * kBit);
  EXPECT_EQ(out.actions[2].node, 0u);
  EXPECT_EQ(out.actions[2].kind, Kind::tx_ok);
  EXPECT_EQ(out.actions[2].at.ns(), 50 * kBit);
  // The listen-only node finds 8 recessive bits only in ACK delimiter and EOF: the activity
  // ends with the frame.
  EXPECT_EQ(out.end_bit, 49u);
  EXPECT_EQ(out.end.ns(), 50 * kBit);
  EXPECT_EQ(out.ifs_end.ns(), 53 * kBit);
  EXPECT_TRUE(out.transmitters[0].sent);
}

TEST(ErrorPhase, ABusHeldDominantGivesAStuffErrorAndTheRule2And6Increments) {
  // Held for 20 bit times from 0, nobody sending: after six dominant bits the node detects a
  // stuff error (outside a frame), flags 6-11, sees bit 12 dominant (rule 2) and 14 dominant
  // bits from its flag's start at bit 19 (rule 6); delimiter 20-27.
  const std::vector<DominantHold> holds{{SimTime{}, SimDuration(20 * kBit)}};
  const std::vector<BusParticipant> parts{receiver(0, false)};
  ErrorPhase::Setup setup{SimTime{}, nullptr, testing::timing_500k(), testing::timing_500k(),
                          0,         holds};
  const ErrorPhase::Outcome out = ErrorPhase(setup, parts).run();
  ASSERT_EQ(out.actions.size(), 3u);
  EXPECT_EQ(out.actions[0].kind, Kind::error);
  EXPECT_EQ(out.actions[0].type, CanErrorType::stuff);
  EXPECT_EQ(out.actions[0].bit, 5);
  EXPECT_EQ(out.actions[0].at.ns(), 6 * kBit);
  EXPECT_FALSE(out.actions[0].in_frame);
  EXPECT_TRUE(out.actions[0].count);
  EXPECT_EQ(out.actions[1].kind, Kind::severe);
  EXPECT_EQ(out.actions[1].bit, 12);
  EXPECT_EQ(out.actions[1].at.ns(), 13 * kBit);
  EXPECT_EQ(out.actions[2].kind, Kind::severe);
  EXPECT_EQ(out.actions[2].bit, 19);
  EXPECT_EQ(out.actions[2].at.ns(), 20 * kBit);
  EXPECT_EQ(out.end_bit, 27u);
  EXPECT_EQ(out.end.ns(), 28 * kBit);
  EXPECT_EQ(out.ifs_end.ns(), 31 * kBit);
  EXPECT_EQ(out.dominant_end.ns(), 20 * kBit);
  EXPECT_TRUE(out.transmitters.empty());
}

TEST(ErrorPhase, ATransmitterThatLosesArbitrationInThePhaseIsListedAsHavingLostIt) {
  // 0x400 and kZero sent at once, a hold over bit 1 (dominant for kZero, 0x400's recessive
  // ID10): 0x400's sender loses arbitration there and receives the rest, kZero's sends its whole
  // frame. Both were transmitters; only the first lost arbitration (a receiver of the activity:
  // no suspend transmission after it).
  static const EncodedFrame k400Bits = encode(*Frame::classic(0x400, {}));
  BusParticipant loser = sender(1);
  loser.bits = &k400Bits;
  const std::vector<BusParticipant> parts{sender(0), loser, receiver(2)};
  const std::vector<DominantHold> holds{{SimTime::from_ns(kBit), SimDuration(kBit)}};
  ErrorPhase::Setup setup = frame_setup(1);
  setup.holds = holds;
  const ErrorPhase::Outcome out = ErrorPhase(setup, parts).run();
  ASSERT_GE(out.actions.size(), 1u);
  EXPECT_EQ(step(out.actions[0]), (Step{1, Kind::arbitration_lost, CanErrorType::bit, kTx, 1}));
  ASSERT_EQ(out.transmitters.size(), 2u);
  EXPECT_EQ(out.transmitters[0], (Tx{0, /*sent=*/true, /*lost_arbitration=*/false}));
  EXPECT_EQ(out.transmitters[1], (Tx{1, /*sent=*/false, /*lost_arbitration=*/true}));
}

}  // namespace
}  // namespace canemu::model
