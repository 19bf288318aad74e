// LIN's arithmetic against independent computations and published values: protected
// identifiers of all 64 IDs, checksums (classic, enhanced, the diagnostic frames), and frame
// layouts and durations to the ns.
#include "canemu/firmware_model/bus/lin_frame.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

namespace canemu::model::lin {
namespace {

// Parity by counting bits (the implementation XORs them one by one).
uint8_t reference_pid(uint8_t id) {
  const unsigned p0 = __builtin_popcount(id & 0b010111u) & 1u;         // ID0, ID1, ID2, ID4
  const unsigned p1 = (__builtin_popcount(id & 0b111010u) & 1u) ^ 1u;  // !(ID1^ID3^ID4^ID5)
  return static_cast<uint8_t>(id | p0 << 6 | p1 << 7);
}

// The checksum by summing everything first and folding the carries afterwards.
uint8_t reference_checksum(std::vector<uint8_t> bytes) {
  unsigned sum = 0;
  for (uint8_t b : bytes) {
    sum += b;
  }
  while (sum > 0xFF) {
    sum = (sum & 0xFF) + (sum >> 8);
  }
  return static_cast<uint8_t>(~sum);
}

TEST(LinFrame, ProtectedIdentifiersOfAll64Ids) {
  for (unsigned id = 0; id <= kMaxId; ++id) {
    EXPECT_EQ(protected_id(static_cast<uint8_t>(id)), reference_pid(static_cast<uint8_t>(id)))
        << id;
  }
  // Published table values.
  const std::array<std::pair<uint8_t, uint8_t>, 10> table{{{0x00, 0x80},
                                                           {0x01, 0xC1},
                                                           {0x02, 0x42},
                                                           {0x03, 0x03},
                                                           {0x10, 0x50},
                                                           {0x20, 0x20},
                                                           {0x3C, 0x3C},
                                                           {0x3D, 0x7D},
                                                           {0x3E, 0xFE},
                                                           {0x3F, 0xBF}}};
  for (auto [id, pid] : table) {
    EXPECT_EQ(protected_id(id), pid) << int{id};
  }
}

TEST(LinFrame, OnlyTheSixtyFourProtectedIdentifiersHaveRightParity) {
  int valid = 0;
  for (unsigned b = 0; b <= 0xFF; ++b) {
    const auto id = id_of_protected(static_cast<uint8_t>(b));
    if (id) {
      ++valid;
      EXPECT_EQ(protected_id(*id), b);
    }
  }
  EXPECT_EQ(valid, 64);
  EXPECT_EQ(id_of_protected(0x80), 0x00);
  EXPECT_EQ(id_of_protected(0x00), std::nullopt);  // ID 0 needs P1
}

TEST(LinFrame, ChecksumsClassicAndEnhanced) {
  // The LIN specification's worked example: bytes 4Ah 55h 93h E5h sum to E6h inverted.
  const std::array<uint8_t, 4> example{0x4A, 0x55, 0x93, 0xE5};
  EXPECT_EQ(checksum(Checksum::classic, 0x10, example), 0xE6);
  uint32_t seed = 12345;
  for (unsigned id = 0; id <= kMaxId; ++id) {
    std::vector<uint8_t> data;
    for (unsigned k = 0; k <= id % 8; ++k) {
      seed = seed * 1103515245u + 12345u;
      data.push_back(static_cast<uint8_t>(seed >> 16));
    }
    const auto pid = reference_pid(static_cast<uint8_t>(id));
    std::vector<uint8_t> with_pid{pid};
    with_pid.insert(with_pid.end(), data.begin(), data.end());
    const bool diagnostic = id == 0x3C || id == 0x3D;
    EXPECT_EQ(checksum(Checksum::classic, static_cast<uint8_t>(id), data), reference_checksum(data))
        << id;
    EXPECT_EQ(checksum(Checksum::enhanced, static_cast<uint8_t>(id), data),
              reference_checksum(diagnostic ? data : with_pid))
        << id;
  }
  EXPECT_EQ(effective_checksum(Checksum::enhanced, 0x3C), Checksum::classic);
  EXPECT_EQ(effective_checksum(Checksum::enhanced, 0x3D), Checksum::classic);
  EXPECT_EQ(effective_checksum(Checksum::enhanced, 0x3B), Checksum::enhanced);
  // All bytes FFh: the sum folds to FFh, the checksum is 00h.
  const std::array<uint8_t, 8> ones{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  EXPECT_EQ(checksum(Checksum::classic, 1, ones), 0x00);
}

TEST(LinFrame, LayoutInBitsWithSpaces) {
  Layout l;
  l.interbyte_bits = 1;
  l.response_space_bits = 2;
  const FrameBits f = frame_bits(l, 2);
  EXPECT_EQ(f.break_end, 13u);
  EXPECT_EQ(f.sync_end, 24u);    // break 13, delimiter 1, sync 10
  EXPECT_EQ(f.header_end, 35u);  // a space, then the PID
  EXPECT_EQ(f.response_start, 37u);
  EXPECT_EQ(f.byte_end(0), 47u);
  EXPECT_EQ(f.byte_end(1), 58u);
  EXPECT_EQ(f.response_end, 69u);  // the checksum, after two more spaces
  const FrameBits header = frame_bits(Layout{}, 0);
  EXPECT_EQ(header.header_end, kNominalHeaderBits);
  EXPECT_EQ(header.response_end, kNominalHeaderBits);
}

TEST(LinFrame, DurationsToTheNanosecond) {
  // 19200 bit/s: a bit is 52083.33 ns; instants are counted from the frame's start.
  const FrameBits eight = frame_bits(Layout{}, 8);
  EXPECT_EQ(eight.response_end, 124u);  // 34 + 10 x 9
  EXPECT_EQ(bits_duration(34, 19200).ns(), 1'770'833);
  EXPECT_EQ(bits_duration(124, 19200).ns(), 6'458'333);
  EXPECT_EQ(after_bits(SimTime::from_ns(1), 124, 19200).ns(), 6'458'334);
  EXPECT_EQ(maximum_frame_duration(8, 19200).ns(), 9'041'666);
  EXPECT_EQ(maximum_response_bits(8), 126u);
  EXPECT_EQ(nominal_response_bits(2), 30u);
  // 9600 bit/s, two bytes: 6.67 ms nominal, 9.33 ms at most.
  EXPECT_EQ(bits_duration(64, 9600).ns(), 6'666'666);
  EXPECT_EQ(maximum_frame_duration(2, 9600).ns(), 9'333'333);
  // 20000 bit/s: whole 50 us bits.
  EXPECT_EQ(bits_duration(124, 20000).ns(), 6'200'000);
}

}  // namespace
}  // namespace canemu::model::lin
