// The part of each node in a frame, decided at its start of frame: acknowledgement, the
// detections that inability to decode and injected faults plan, and where an injected error
// lands. Frame bit indices of kZero as in error_phase_test.cpp: arbitration ends at bit 15,
// CRC delimiter 40, ACK slot 41, ACK delimiter 42, EOF 43-49.
#include "canemu/firmware_model/bus/frame_roles.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "test_controller.hpp"

namespace canemu::model {
namespace {

using Decoding = FrameRoles::Decoding;
using Planned = std::optional<std::pair<CanErrorType, uint16_t>>;

const EncodedFrame kZeroBits = encode(testing::kZero);

Planned planned(CanErrorType type, uint16_t bit) {
  return std::make_pair(type, bit);
}

FrameFault injected(CanErrorType type, std::optional<uint16_t> bit = std::nullopt) {
  return FrameFault{type, bit, false};
}

TEST(FrameRoles, AReceiverThatDecodesAcknowledgesAndPlansNothing) {
  const FrameFault none;
  const FrameRoles roles(kZeroBits, none, false);
  const BusParticipant p = roles.receiver({3, false, true, false}, Decoding::ok);
  EXPECT_EQ(p.id, 3u);
  EXPECT_FALSE(p.transmitter);
  EXPECT_TRUE(p.drives);
  EXPECT_TRUE(p.passive);
  EXPECT_TRUE(p.decodes);
  EXPECT_TRUE(p.acks);
  EXPECT_EQ(p.planned, std::nullopt);
}

TEST(FrameRoles, ListenOnlyAndSuppressedAcknowledgementsLeaveTheAckSlotRecessive) {
  const FrameFault none;
  EXPECT_FALSE(FrameRoles(kZeroBits, none, false).receiver({0, true}, Decoding::ok).acks);
  EXPECT_FALSE(FrameRoles(kZeroBits, none, true).receiver({0}, Decoding::ok).acks);
  const FrameFault suppress{std::nullopt, std::nullopt, true};
  EXPECT_FALSE(FrameRoles(kZeroBits, suppress, false).receiver({0}, Decoding::ok).acks);
  // An injected ACK error is a missing acknowledgement, not a detection by receivers.
  const FrameFault ack = injected(CanErrorType::ack);
  const BusParticipant p = FrameRoles(kZeroBits, ack, false).receiver({0}, Decoding::ok);
  EXPECT_FALSE(p.acks);
  EXPECT_EQ(p.planned, std::nullopt);
}

TEST(FrameRoles, AReceiverThatCannotDecodePlansItsErrorAndDoesNotAcknowledge) {
  const FrameFault none;
  const FrameRoles roles(kZeroBits, none, false);
  const BusParticipant timing = roles.receiver({0}, Decoding::timing);
  EXPECT_FALSE(timing.decodes);
  EXPECT_FALSE(timing.acks);
  EXPECT_EQ(timing.planned, planned(CanErrorType::stuff, 15));
  // An FD frame with identifier 0: SOF and ID10..7 (0-4), stuff (5), ID6..2 (6-10), stuff (11),
  // ID1, ID0, RRS, IDE (12-15), FDF (16): a classic controller sees a form error at 17.
  const std::vector<uint8_t> data{1};
  const EncodedFrame fd = encode(*Frame::fd_frame(0, data));
  const FrameRoles fd_roles(fd, none, false);
  const BusParticipant classic = fd_roles.receiver({0}, Decoding::not_fd);
  EXPECT_FALSE(classic.decodes);
  EXPECT_FALSE(classic.acks);
  EXPECT_EQ(classic.planned, planned(CanErrorType::form, 17));
}

TEST(FrameRoles, InjectedReceiverErrorsArePlannedForReceiversAndACrcErrorWithholdsTheAck) {
  const FrameFault crc = injected(CanErrorType::crc);
  const BusParticipant c = FrameRoles(kZeroBits, crc, false).receiver({0}, Decoding::ok);
  EXPECT_EQ(c.planned, planned(CanErrorType::crc, 42));
  EXPECT_FALSE(c.acks);
  const FrameFault form = injected(CanErrorType::form);
  const BusParticipant f = FrameRoles(kZeroBits, form, false).receiver({0}, Decoding::ok);
  EXPECT_EQ(f.planned, planned(CanErrorType::form, 40));
  EXPECT_TRUE(f.acks);
  // A receiver that cannot decode the frame makes its own detection instead.
  EXPECT_EQ(FrameRoles(kZeroBits, form, false).receiver({0}, Decoding::timing).planned,
            planned(CanErrorType::stuff, 15));
  // Senders do not detect receiver-side errors.
  EXPECT_EQ(FrameRoles(kZeroBits, form, false).sender({1}, kZeroBits, std::nullopt).planned,
            std::nullopt);
}

TEST(FrameRoles, SendersPlanTheirCollisionOrAnInjectedBitError) {
  const FrameFault none;
  const BusParticipant s = FrameRoles(kZeroBits, none, false).sender({5}, kZeroBits, 21);
  EXPECT_EQ(s.id, 5u);
  EXPECT_TRUE(s.transmitter);
  EXPECT_EQ(s.bits, &kZeroBits);
  EXPECT_EQ(s.planned, planned(CanErrorType::bit, 21));
  const FrameFault bit = injected(CanErrorType::bit, 30);
  const FrameRoles roles(kZeroBits, bit, false);
  EXPECT_EQ(roles.sender({5}, kZeroBits, std::nullopt).planned, planned(CanErrorType::bit, 30));
  EXPECT_EQ(roles.sender({5}, kZeroBits, 21).planned, planned(CanErrorType::bit, 21));
  EXPECT_EQ(roles.receiver({6}, Decoding::ok).planned, std::nullopt);
}

TEST(FrameRoles, InjectedErrorsLandWhereSuchAnErrorCanBeDetected) {
  const auto place = [](CanErrorType t, std::optional<uint16_t> bit) {
    return FrameRoles::place_injected(kZeroBits, t, bit);
  };
  // Bit errors: after arbitration, before the last bit.
  EXPECT_EQ(place(CanErrorType::bit, std::nullopt), 15);
  EXPECT_EQ(place(CanErrorType::bit, 3), 15);
  EXPECT_EQ(place(CanErrorType::bit, 30), 30);
  EXPECT_EQ(place(CanErrorType::bit, 60), 48);
  // Stuff errors: within the stuffed part after arbitration.
  EXPECT_EQ(place(CanErrorType::stuff, std::nullopt), 15);
  EXPECT_EQ(place(CanErrorType::stuff, 45), 39);
  // Form errors: CRC delimiter, ACK delimiter, EOF but its last bit; else the CRC delimiter.
  EXPECT_EQ(place(CanErrorType::form, std::nullopt), 40);
  EXPECT_EQ(place(CanErrorType::form, 42), 42);
  EXPECT_EQ(place(CanErrorType::form, 48), 48);
  EXPECT_EQ(place(CanErrorType::form, 41), 40);
  EXPECT_EQ(place(CanErrorType::form, 49), 40);
  // CRC errors are flagged after the ACK delimiter, ACK errors at the ACK slot.
  EXPECT_EQ(place(CanErrorType::crc, 20), 42);
  EXPECT_EQ(place(CanErrorType::ack, 20), 41);
}

TEST(FrameRoles, WithoutAnAcknowledgementTheFirstDetectionIsAtTheAckSlot) {
  const FrameFault none;
  const FrameRoles roles(kZeroBits, none, false);
  const BusParticipant tx = roles.sender({0}, kZeroBits, std::nullopt);
  const BusParticipant rx = roles.receiver({1}, Decoding::ok);
  const BusParticipant deaf = roles.receiver({2}, Decoding::timing);
  EXPECT_EQ(roles.first_detection(std::vector<BusParticipant>{tx}), 41);
  EXPECT_EQ(roles.first_detection(std::vector<BusParticipant>{tx, rx}), std::nullopt);
  EXPECT_EQ(roles.first_detection(std::vector<BusParticipant>{tx, rx, deaf}), 15);
  BusParticipant self_test = tx;
  self_test.self_test = true;
  EXPECT_EQ(roles.first_detection(std::vector<BusParticipant>{self_test}), std::nullopt);
  // A detection planned after the ACK slot comes second to the missing acknowledgement.
  const FrameFault crc = injected(CanErrorType::crc);
  const FrameRoles crc_roles(kZeroBits, crc, false);
  EXPECT_EQ(crc_roles.first_detection(
                std::vector<BusParticipant>{tx, crc_roles.receiver({1}, Decoding::ok)}),
            41);
}

}  // namespace
}  // namespace canemu::model
