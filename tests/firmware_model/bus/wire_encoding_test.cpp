#include "canemu/firmware_model/bus/wire_encoding.hpp"

#include <gtest/gtest.h>

#include <initializer_list>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model {
namespace {

Frame make(const FrameSpec& spec) {
  auto f = Frame::create(spec);
  EXPECT_TRUE(f) << f.error().message;
  return *f;
}

std::vector<uint8_t> bytes(std::initializer_list<int> v) {
  return std::vector<uint8_t>(v.begin(), v.end());
}

// Hand-checked: 34 dominant bits (CRC-15 of all-zero bits is 0), a recessive stuff bit after
// every five, then CRC delimiter, ACK slot (sent recessive), ACK delimiter, 7 EOF bits.
TEST(WireEncoding, AllZeroStandardFrameIsTheHandCheckedSequence) {
  FrameSpec spec;
  const EncodedFrame e = encode(make(spec));
  std::string expected;
  for (int k = 0; k < 6; ++k) {
    expected += "000001";  // five dominant bits, then a recessive stuff bit
  }
  expected += "0000";     // the last four dominant bits: 34 in all
  expected += "111";      // CRC delimiter, ACK slot, ACK delimiter
  expected += "1111111";  // EOF
  EXPECT_EQ(e.to_string(), expected);
  EXPECT_EQ(e.crc, 0u);
  EXPECT_EQ(e.crc_bits, 15);
  EXPECT_EQ(e.dynamic_stuff_bits, 6);
  EXPECT_EQ(e.length, 50);
  for (std::size_t i : {5u, 11u, 17u, 23u, 29u, 35u}) {
    EXPECT_TRUE(e.is_stuff(i)) << i;
  }
  EXPECT_FALSE(e.is_stuff(4));
}

// Golden vectors: tests/firmware_model/golden/can_reference.py, an independent string-based
// encoder (CRC by polynomial division), with the arguments given in each comment.
struct Golden {
  const char* recipe;
  FrameSpec spec;
  std::vector<uint8_t> data;
  const char* bits;
};

class WireEncodingGolden : public ::testing::TestWithParam<int> {};

std::vector<Golden> goldens() {
  std::vector<Golden> g;
  auto add = [&](const char* recipe, FrameSpec spec, std::vector<uint8_t> data, const char* bits) {
    g.push_back(Golden{recipe, spec, std::move(data), bits});
  };
  FrameSpec s;
  s.id = 0x123;
  add("123 2 1122", s, bytes({0x11, 0x22}),
      "00010010001100000110000100010010001000001100101101111111111111");
  s = {};
  s.id = 0x1ABCDEF0;
  s.extended = true;
  add("1ABCDEF0 4 DEADBEEF ext", s, bytes({0xDE, 0xAD, 0xBE, 0xEF}),
      "0110101011111010011011110111100000100010011011110101011011011111001110111110101010001011111"
      "111111111");
  s = {};
  s.id = 0x7FF;
  s.remote = true;
  s.dlc = 8;
  add("7FF 8 - rtr", s, {}, "01111101111101100100001000001111011011111111111");
  s = {};
  s.id = 0x555;
  s.fd = true;
  s.brs = true;
  add("555 9 000102030405060708090A0B fd brs", s, bytes({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}),
      "0101010101010010101001000001000001000001100000101000001001100000110000010010100000111000001"
      "011100001000001001001000010100000110110010100011001010011101110101111111111");
  s = {};
  s.fd = true;
  add("000 0 - fd", s, {}, "00000100000100001000001001010100011010010010101111011111111111");
  return g;
}

TEST_P(WireEncodingGolden, MatchesTheReferenceEncoderBitForBit) {
  Golden g = goldens()[static_cast<std::size_t>(GetParam())];
  g.spec.data = g.data;
  EXPECT_EQ(encode(make(g.spec)).to_string(), g.bits) << "recipe: can_reference.py " << g.recipe;
}

INSTANTIATE_TEST_SUITE_P(Vectors, WireEncodingGolden, ::testing::Range(0, 5));

TEST(WireEncoding, FdFrameWith64BytesUsesCrc21AndSevenFixedStuffBits) {
  std::vector<uint8_t> data(64);
  for (std::size_t i = 0; i < data.size(); ++i) {
    data[i] = static_cast<uint8_t>(i * 37);
  }
  FrameSpec s;
  s.id = 0x1F00F00F;
  s.extended = true;
  s.fd = true;
  s.brs = true;
  s.esi = true;
  s.data = data;
  const EncodedFrame e = encode(make(s));
  EXPECT_EQ(e.crc_bits, 21);
  EXPECT_EQ(e.fixed_stuff_bits, 7);
  EXPECT_EQ(e.stuff_count, e.dynamic_stuff_bits % 8);
  // SBC field: fixed stuff bit, Gray code, even parity over the Gray bits.
  const uint16_t sbc = e.field_begin(Field::stuff_count);
  EXPECT_TRUE(e.is_stuff(sbc));
  int ones = 0;
  for (int i = 1; i <= 4; ++i) {
    ones += e.level_at(sbc + i);
  }
  EXPECT_EQ(ones % 2, 0);
  // 41 header + 512 data + dynamic stuff + 33 CRC field + 9 tail.
  EXPECT_EQ(e.length, 41 + 512 + e.dynamic_stuff_bits + 33 + 9);
}

TEST(WireEncoding, FdFramesUpTo16BytesUseCrc17AndSixFixedStuffBits) {
  std::vector<uint8_t> data(16, 0xA5);
  FrameSpec s;
  s.fd = true;
  s.data = data;
  const EncodedFrame e = encode(make(s));
  EXPECT_EQ(e.crc_bits, 17);
  EXPECT_EQ(e.fixed_stuff_bits, 6);
  EXPECT_EQ(e.length, 22 + 128 + e.dynamic_stuff_bits + 28 + 9);
}

// Where fields begin in `e`: each (field, first bit) of `begins`.
void expect_field_begins(const EncodedFrame& e,
                         std::initializer_list<std::pair<Field, uint16_t>> begins) {
  for (const auto& [field, bit] : begins) {
    EXPECT_EQ(e.field_begin(field), bit) << to_string(field);
  }
}

TEST(WireEncoding, FieldsOfAStandardFrameAreWhereTheStandardPutsThem) {
  FrameSpec s;
  s.id = 0x123;
  const auto data = bytes({0x11, 0x22});
  s.data = data;
  const EncodedFrame e = encode(make(s));
  // 0 00100100011 0 0 0 0010: one stuff bit after the five zeros of RTR..DLC.
  expect_field_begins(e, {{Field::sof, 0},
                          {Field::base_id, 1},
                          {Field::rtr, 12},
                          {Field::ide, 13},
                          {Field::fdf, 14},
                          {Field::dlc, 15},
                          {Field::data, 20}});
  EXPECT_EQ(e.arbitration_end, 13);
  EXPECT_EQ(e.field_at(17), Field::dlc);
  EXPECT_TRUE(e.is_stuff(17));
  EXPECT_EQ(e.field_begin(Field::srr), e.length);  // absent
  EXPECT_EQ(e.field_begin(Field::eof), e.length - 7);
  EXPECT_EQ(e.crc_delimiter_index, e.length - 10);
  EXPECT_EQ(to_string(e.field_at(e.length - 1)), "EOF");
}

TEST(WireEncoding, ArbitrationFieldOfAnExtendedFrameEndsAfterRtr) {
  FrameSpec s;
  s.id = 0x15555555;
  s.extended = true;
  const EncodedFrame e = encode(make(s));
  expect_field_begins(e, {{Field::srr, 12}, {Field::ext_id, 14}, {Field::rtr, 32}});
  EXPECT_EQ(e.arbitration_end, 33);
}

TEST(WireEncoding, NoStuffBitFollowsTheLastDataBitOfAnFdFrame) {
  // Four dominant DLC bits end a run of five zeros at the last control bit of an empty FD frame
  // (see the golden "000 0 - fd"): the fixed stuff bit comes instead of a dynamic one.
  FrameSpec s;
  s.fd = true;
  const EncodedFrame e = encode(make(s));
  const uint16_t sbc = e.field_begin(Field::stuff_count);
  EXPECT_EQ(e.dynamic_stuff_bits, 3);
  EXPECT_FALSE(e.level_at(sbc - 1));
  EXPECT_FALSE(e.is_stuff(sbc - 1));
  EXPECT_TRUE(e.is_stuff(sbc));
  EXPECT_TRUE(e.level_at(sbc));
}

TEST(WireEncoding, ReusingTheOutputGivesTheSameBits) {
  std::vector<uint8_t> big(64, 0xFF);
  FrameSpec s;
  s.fd = true;
  s.data = big;
  EncodedFrame out;
  encode(make(s), out);
  FrameSpec small;
  small.id = 0x123;
  encode(make(small), out);
  EXPECT_EQ(out.to_string(), encode(make(small)).to_string());
  EXPECT_EQ(out.fixed_stuff_bits, 0);
}

// Property check over many frames: never six equal bits in the stuffed part, lengths between
// the kernel's bounds, and the bits agree with the counters.
TEST(WireEncoding, RandomFramesObeyTheStuffRuleAndTheKernelBounds) {
  std::mt19937 rng(7);
  for (int n = 0; n < 3000; ++n) {
    FrameSpec s;
    s.fd = rng() % 2;
    s.extended = rng() % 2;
    s.brs = s.fd && rng() % 2;
    s.remote = !s.fd && rng() % 5 == 0;
    s.id = s.extended ? rng() & kMaxExtendedId : rng() & kMaxStandardId;
    const auto dlc = static_cast<uint8_t>(rng() % 16);
    s.dlc = dlc;
    std::vector<uint8_t> data(s.remote ? 0 : dlc_to_length(dlc, s.fd));
    for (auto& b : data) {
      b = (rng() % 3 == 0) ? static_cast<uint8_t>(rng() % 2 ? 0xFF : 0x00)
                           : static_cast<uint8_t>(rng());
    }
    s.data = data;
    const Frame f = make(s);
    const EncodedFrame e = encode(f);
    const uint16_t stuffed_end = s.fd ? e.field_begin(Field::stuff_count) : e.crc_delimiter_index;
    int run = 0;
    bool last = true;
    int stuff = 0;
    for (uint16_t i = 0; i < stuffed_end; ++i) {
      run = e.level_at(i) == last ? run + 1 : 1;
      last = e.level_at(i);
      ASSERT_LE(run, 5) << "frame " << n << " bit " << i;
      stuff += e.is_stuff(i);
    }
    ASSERT_EQ(stuff, e.dynamic_stuff_bits);
    const uint32_t with_ifs = e.length + kIntermissionBits;
    ASSERT_GE(with_ifs, frame_length_bound(s.fd, s.extended, f.length(), Stuffing::none));
    ASSERT_LE(with_ifs, frame_length_bound(s.fd, s.extended, f.length(), Stuffing::worst_case));
    for (uint16_t i = e.crc_delimiter_index; i < e.length; ++i) {
      ASSERT_TRUE(e.level_at(i));
    }
  }
}

// A classic frame's bits written out one at a time from its fields (SOF, identifier, RTR or
// SRR, IDE, r1 / r0, DLC, data, a CRC-15 computed bit by bit), stuffed bit by bit, and the ten
// recessive bits after the CRC: what encode() must produce, stuff marks included.
std::pair<std::string, std::string> classic_bit_by_bit(const Frame& f) {
  std::string d;
  auto put = [&](uint32_t value, int bits) {
    for (int i = bits - 1; i >= 0; --i) {
      d += ((value >> i) & 1u) != 0 ? '1' : '0';
    }
  };
  put(0, 1);
  if (f.extended()) {
    put(f.id() >> 18, 11);
    put(3, 2);  // SRR, IDE
    put(f.id() & 0x3FFFF, 18);
    put(f.remote() ? 1 : 0, 1);
    put(0, 2);  // r1, r0
  } else {
    put(f.id(), 11);
    put(f.remote() ? 1 : 0, 1);
    put(0, 2);  // IDE, r0
  }
  put(f.dlc(), 4);
  for (const uint8_t b : f.data()) {
    put(b, 8);
  }
  uint32_t crc = 0;
  for (const char c : d) {
    const bool feedback = (c == '1') != (((crc >> 14) & 1u) != 0);
    crc = ((crc << 1) & 0x7FFF) ^ (feedback ? 0x4599u : 0u);
  }
  put(crc, 15);
  std::string wire;
  std::string marks;
  int run = 0;
  char last = 'x';
  for (const char c : d) {
    wire += c;
    marks += '0';
    run = c == last ? run + 1 : 1;
    last = c;
    if (run == 5) {
      last = c == '1' ? '0' : '1';
      wire += last;
      marks += '1';
      run = 1;
    }
  }
  wire += std::string(10, '1');
  marks += std::string(10, '0');
  return {wire, marks};
}

// Against that, 20,000 random classic frames, most of them with long runs of equal bits (zero
// and 0xFF bytes, identifiers of few ones), so that stuff bits fall everywhere, at the first
// bit of the second and third words too.
TEST(WireEncoding, ClassicFramesAreTheirFieldsStuffedBitByBit) {
  std::mt19937 rng(11);
  FrameSpec other;  // what encode_head's output held before
  other.id = 0x7FF;
  other.extended = true;
  other.fd = true;
  for (int n = 0; n < 20000; ++n) {
    FrameSpec s;
    s.extended = rng() % 2;
    s.remote = rng() % 8 == 0;
    const auto r = static_cast<uint32_t>(rng());
    const uint32_t id =
        r % 4 == 0 ? static_cast<uint32_t>(rng()) : (r % 8 < 4 ? 0u : ~0u) ^ (1u << (rng() % 29));
    s.id = id & (s.extended ? kMaxExtendedId : kMaxStandardId);
    const auto dlc = static_cast<uint8_t>(rng() % 16);
    s.dlc = dlc;
    std::vector<uint8_t> data(s.remote ? 0 : dlc_to_length(dlc, false));
    for (auto& b : data) {
      const uint32_t kind = rng() % 4;
      b = static_cast<uint8_t>(kind == 0 ? rng() : kind == 1 ? 0xFF : kind == 2 ? 0 : 1);
    }
    s.data = data;
    const Frame f = make(s);
    const EncodedFrame e = encode(f);
    const auto [wire, marks] = classic_bit_by_bit(f);
    ASSERT_EQ(e.to_string(), wire) << "frame " << n;
    ASSERT_EQ(e.stuff_marks(), marks) << "frame " << n;
    // encode_head: every field and the first word as encode() has them, into an output that
    // held another frame (words past the first keep what they had unless it says whole).
    EncodedFrame head = encode(make(other));
    const EncodedFrame before = head;
    const bool whole = encode_head(f, head);
    ASSERT_EQ(whole, e.length <= 64) << "frame " << n;
    ASSERT_EQ(head.level[0], e.level[0]) << "frame " << n;
    ASSERT_EQ(head.stuff[0], e.stuff[0]) << "frame " << n;
    ASSERT_EQ(head.level[1], before.level[1]) << "frame " << n;
    ASSERT_EQ(head.stuff[1], before.stuff[1]) << "frame " << n;
    ASSERT_EQ(
        std::tie(head.length, head.dynamic_stuff_bits, head.fixed_stuff_bits, head.crc,
                 head.crc_bits, head.crc_delimiter_index, head.arbitration_end, head.brs_index,
                 head.stuff_count, head.extended, head.data_bytes, head.fd, head.brs),
        std::tie(e.length, e.dynamic_stuff_bits, e.fixed_stuff_bits, e.crc, e.crc_bits,
                 e.crc_delimiter_index, e.arbitration_end, e.brs_index, e.stuff_count, e.extended,
                 e.data_bytes, e.fd, e.brs))
        << "frame " << n;
  }
}

TEST(WireEncoding, TheHeadOfACanFdFrameIsTheWholeEncoding) {
  std::vector<uint8_t> data(64, 0x00);
  FrameSpec s;
  s.fd = true;
  s.brs = true;
  s.data = data;
  const Frame f = make(s);
  // Into an output that held a long classic frame.
  const std::vector<uint8_t> ones(8, 0xFF);
  FrameSpec before;
  before.id = 0x0F0;
  before.data = ones;
  EncodedFrame head = encode(make(before));
  ASSERT_TRUE(encode_head(f, head));
  const EncodedFrame e = encode(f);
  EXPECT_EQ(head.to_string(), e.to_string());
  EXPECT_EQ(head.stuff_marks(), e.stuff_marks());
}

TEST(FrameLengthBound, ReproducesTheKernelTable) {
  EXPECT_EQ(frame_length_bound(false, false, 8, Stuffing::none), 111u);
  EXPECT_EQ(frame_length_bound(false, false, 8, Stuffing::worst_case), 135u);
  EXPECT_EQ(frame_length_bound(false, true, 8, Stuffing::none), 131u);
  EXPECT_EQ(frame_length_bound(false, true, 8, Stuffing::worst_case), 160u);
  EXPECT_EQ(frame_length_bound(true, false, 64, Stuffing::none), 579u);
  EXPECT_EQ(frame_length_bound(true, false, 64, Stuffing::worst_case), 712u);
  EXPECT_EQ(frame_length_bound(true, true, 64, Stuffing::none), 598u);
  EXPECT_EQ(frame_length_bound(true, true, 64, Stuffing::worst_case), 736u);
  // Davis et al.: 55 + 10n and 80 + 10n for classic frames.
  for (std::size_t n = 0; n <= 8; ++n) {
    EXPECT_EQ(frame_length_bound(false, false, n, Stuffing::worst_case), 55 + 10 * n);
    EXPECT_EQ(frame_length_bound(false, true, n, Stuffing::worst_case), 80 + 10 * n);
  }
}

TEST(FrameDuration, ClassicFrameTakesItsBitsTimesTheBitTime) {
  const BitTiming t500k = *sja1000::decode_btr(0x00, 0x1C);
  FrameSpec s;
  const EncodedFrame e = encode(make(s));
  EXPECT_EQ(bit_counts(e).nominal, 50u);
  EXPECT_EQ(bit_counts(e).data, 0u);
  EXPECT_EQ(frame_duration(e, t500k).ns(), 50 * 2000);
  EXPECT_EQ(intermission_duration(t500k).ns(), 6000);
  const BitTiming t1m = *sja1000::decode_btr(0x00, 0x14);
  EXPECT_EQ(frame_duration(e, t1m).ns(), 50'000);
}

TEST(FrameDuration, BitRateSwitchTimesBrsAndCrcDelimiterAtTheirSamplePoints) {
  // 500 kbit/s nominal: 80 MHz / 10 = 125 ns quanta, 1 + 13 + 2. 2 Mbit/s data: 12.5 ns quanta,
  // 1 + 29 + 10.
  const BitTiming nominal =
      *ixxat::decode_btp({0, 500000, 14, 2, 1, 0}, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  const BitTiming data =
      *ixxat::decode_btp({0, 2000000, 30, 10, 1, 0}, ixxat::kFdDataRange, ixxat::Phase::data);
  FrameSpec s;
  s.id = 0x555;
  s.fd = true;
  s.brs = true;
  const auto payload = bytes({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11});
  s.data = payload;
  const EncodedFrame e = encode(make(s));
  ASSERT_EQ(e.length, 166);
  EXPECT_EQ(e.brs_index, 16);
  EXPECT_EQ(e.crc_delimiter_index, 156);
  EXPECT_EQ(bit_counts(e).nominal, 27u);
  EXPECT_EQ(bit_counts(e).data, 139u);
  // 16 nominal bits, BRS = 14 nominal quanta + 10 data quanta, 139 data bits, CRC delimiter =
  // 30 data quanta + 2 nominal quanta, then ACK, ACK delimiter and EOF at the nominal rate.
  const int64_t expected = 16 * 2000 + (14 * 125 + 125) + 139 * 500 + (375 + 2 * 125) + 9 * 2000;
  EXPECT_EQ(expected, 122'000);
  EXPECT_EQ(frame_duration(e, nominal, data).ns(), expected);
  // Without BRS the same frame runs at the nominal rate throughout.
  s.brs = false;
  const EncodedFrame slow = encode(make(s));
  EXPECT_EQ(bit_counts(slow).data, 0u);
  EXPECT_EQ(frame_duration(slow, nominal, data).ns(), int64_t{slow.length} * 2000);
}

}  // namespace
}  // namespace canemu::model
