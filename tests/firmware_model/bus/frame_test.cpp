#include "canemu/firmware_model/bus/frame.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "case_name.hpp"

namespace canemu::model {
namespace {

TEST(FrameDlc, ClassicCodesAboveEightMeanEightBytes) {
  for (uint8_t dlc = 0; dlc <= 8; ++dlc) {
    EXPECT_EQ(dlc_to_length(dlc, false), dlc);
  }
  for (uint8_t dlc = 9; dlc <= 15; ++dlc) {
    EXPECT_EQ(dlc_to_length(dlc, false), 8u);
  }
}

TEST(FrameDlc, FdCodesFollowTheIsoLengthTable) {
  const std::array<std::size_t, 16> expected{0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  for (uint8_t dlc = 0; dlc <= 15; ++dlc) {
    EXPECT_EQ(dlc_to_length(dlc, true), expected[dlc]) << "DLC " << int{dlc};
    EXPECT_EQ(length_to_dlc(expected[dlc], true), dlc);
  }
  EXPECT_FALSE(length_to_dlc(13, true).has_value());
  EXPECT_FALSE(length_to_dlc(9, false).has_value());
}

TEST(Frame, ClassicFrameDerivesItsDlcFromTheData) {
  const std::vector<uint8_t> data{1, 2, 3};
  auto f = Frame::classic(0x123, data);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ(f->id(), 0x123u);
  EXPECT_EQ(f->dlc(), 3);
  EXPECT_EQ(f->length(), 3u);
  EXPECT_FALSE(f->extended());
  EXPECT_FALSE(f->fd());
  EXPECT_EQ(std::vector<uint8_t>(f->data().begin(), f->data().end()), data);
}

TEST(Frame, ClassicFrameMayUseDlcAboveEightWithEightBytes) {
  const std::array<uint8_t, 8> data{};
  FrameSpec spec;
  spec.id = 1;
  spec.dlc = 15;
  spec.data = data;
  auto f = Frame::create(spec);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ(f->dlc(), 15);
  EXPECT_EQ(f->length(), 8u);
}

TEST(Frame, RejectsAnIdentifierTooWideForItsFormat) {
  auto f = Frame::classic(0x800, {});
  ASSERT_FALSE(f);
  EXPECT_EQ(f.error().code, ModelErrc::invalid_identifier);
  EXPECT_EQ(f.error().message, "identifier 0x800 does not fit 11 bits (maximum 0x7FF)");
  EXPECT_TRUE(Frame::classic(0x1FFFFFFF, {}, true));
  auto ext = Frame::classic(0x20000000, {}, true);
  ASSERT_FALSE(ext);
  EXPECT_EQ(ext.error().message, "identifier 0x20000000 does not fit 29 bits (maximum 0x1FFFFFFF)");
}

// Frames the model refuses, each with the error code and the whole message.
enum Flag : unsigned { kRemote = 1, kFd = 2, kBrs = 4, kEsi = 8 };

FrameSpec spec(uint32_t id, unsigned flags, std::optional<uint8_t> dlc = std::nullopt,
               std::size_t bytes = 0) {
  static const std::array<uint8_t, 64> zeros{};
  FrameSpec s;
  s.id = id;
  s.remote = (flags & kRemote) != 0;
  s.fd = (flags & kFd) != 0;
  s.brs = (flags & kBrs) != 0;
  s.esi = (flags & kEsi) != 0;
  s.dlc = dlc;
  s.data = std::span<const uint8_t>(zeros).first(bytes);
  return s;
}

struct Rejected {
  const char* name;
  FrameSpec spec;
  ModelErrc code;
  const char* message;
};

class FrameRejects : public ::testing::TestWithParam<Rejected> {};

TEST_P(FrameRejects, WithACodeAndAMessageThatSaysWhy) {
  const auto f = Frame::create(GetParam().spec);
  ASSERT_FALSE(f);
  EXPECT_EQ(f.error().code, GetParam().code);
  EXPECT_EQ(f.error().message, GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    Frame, FrameRejects,
    ::testing::Values(
        Rejected{"RemoteFramesInCanFd", spec(0, kRemote | kFd), ModelErrc::invalid_flags,
                 "CAN FD has no remote frames: remote and fd cannot both be set"},
        Rejected{"BrsOnAClassicFrame", spec(0, kBrs), ModelErrc::invalid_flags,
                 "BRS is a CAN FD bit: it needs fd set"},
        Rejected{"EsiOnAClassicFrame", spec(0, kEsi), ModelErrc::invalid_flags,
                 "ESI is a CAN FD bit: it needs fd set"},
        Rejected{"DlcOutOfRange", spec(0, kRemote, 16), ModelErrc::invalid_dlc,
                 "DLC 16 is out of range 0..15"},
        Rejected{"DataThatDisagreesWithTheDlc", spec(0, 0, 4, 3), ModelErrc::data_length_mismatch,
                 "DLC 4 means 4 data bytes, but 3 were given"},
        Rejected{"FdPayloadLengthsThatNoDlcGives", spec(0x10, kFd, std::nullopt, 13),
                 ModelErrc::data_length_mismatch,
                 "no DLC gives 13 data bytes (CAN FD lengths above 8 are 12, 16, 20, 24, 32, 48, "
                 "64)"},
        Rejected{"MoreThanEightBytesInAClassicFrame", spec(0x10, 0, std::nullopt, 12),
                 ModelErrc::data_length_mismatch,
                 "12 data bytes exceed the 8 bytes of a classic frame"}),
    test_support::CaseName{});

TEST(Frame, RemoteFrameKeepsItsDlcButCarriesNoData) {
  FrameSpec spec;
  spec.id = 0x7FF;
  spec.remote = true;
  spec.dlc = 8;
  auto f = Frame::create(spec);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ(f->dlc(), 8);
  EXPECT_EQ(f->length(), 0u);
  const std::array<uint8_t, 1> data{};
  spec.data = data;
  auto bad = Frame::create(spec);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "a remote frame carries no data, but 1 bytes were given");
}

TEST(Frame, FramesCompareByContent) {
  const std::array<uint8_t, 2> a{1, 2};
  const std::array<uint8_t, 2> b{1, 3};
  EXPECT_EQ(*Frame::classic(5, a), *Frame::classic(5, a));
  EXPECT_FALSE(*Frame::classic(5, a) == *Frame::classic(5, b));
  EXPECT_FALSE(*Frame::classic(5, a) == *Frame::classic(5, a, true));
}

TEST(Frame, WithEsiChangesOnlyTheErrorStateOfACanFdFrame) {
  const std::vector<uint8_t> data(12, 0xA5);
  const Frame fd = *Frame::fd_frame(0x123, data, false, true);
  const Frame passive = fd.with_esi(true);
  EXPECT_TRUE(passive.esi());
  EXPECT_FALSE(passive == fd);
  EXPECT_EQ(passive.id(), 0x123u);
  EXPECT_TRUE(passive.brs());
  EXPECT_EQ(passive.dlc(), fd.dlc());
  EXPECT_TRUE(std::ranges::equal(passive.data(), fd.data()));
  EXPECT_EQ(passive.with_esi(false), fd);
  const Frame classic = *Frame::classic(0x123, std::vector<uint8_t>{1, 2});
  EXPECT_EQ(classic.with_esi(true), classic);  // no ESI bit in a classic frame
}

TEST(ModelErrc, EveryCodeHasAName) {
  EXPECT_EQ(to_string(ModelErrc::invalid_identifier), "invalid_identifier");
  EXPECT_EQ(to_string(ModelErrc::timing_not_realizable), "timing_not_realizable");
}

}  // namespace
}  // namespace canemu::model
