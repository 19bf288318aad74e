// The restbus signal codec and payload checks against vectors from outside the project:
// payloads cantools 45.1.0 encodes (Message.encode) for the layouts below, and the CRC-8
// SAE J1850 check values of the CRC catalogue and of AUTOSAR's CRC library specification.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "canemu/daemon/restbus/signal_codec.hpp"

namespace canemu::daemon::restbus {
namespace {

using Order = SignalLayout::ByteOrder;
using Type = SignalLayout::Type;

SignalLayout layout(uint32_t start, uint32_t length, Order order, bool is_signed = false,
                    double scale = 1, double offset = 0, Type type = Type::integer) {
  return SignalLayout{.start = start,
                      .length = length,
                      .byte_order = order,
                      .type = type,
                      .is_signed = is_signed,
                      .scale = scale,
                      .offset = offset};
}

struct Placed {
  SignalLayout layout;
  double physical;
};

std::vector<uint8_t> encode(const std::vector<Placed>& signals) {
  std::vector<uint8_t> payload(8, 0);
  for (const Placed& p : signals) {
    auto raw = to_raw(p.layout, p.physical);
    EXPECT_TRUE(raw) << raw.error();
    put_raw(payload, p.layout, raw.value_or(0));
  }
  return payload;
}

// cantools, of this DBC message (M1, 8 bytes):
//   SG_ LeU16 : 16|16@1+ (0.25,0)    = 1234.5
//   SG_ BeU12 : 7|12@0+ (1,0)        = 0xABC
//   SG_ BeS10 : 37|10@0- (0.5,-1)    = -100.5
//   SG_ LeS7 : 50|7@1- (1,0)         = -5
//   SG_ LeU1 : 63|1@1+ (1,0)         = 1
// encodes ab c0 4a 13 33 90 ec 81.
const std::vector<Placed> kM1 = {
    {layout(16, 16, Order::little_endian, false, 0.25), 1234.5},
    {layout(7, 12, Order::big_endian), 0xABC},
    {layout(37, 10, Order::big_endian, true, 0.5, -1), -100.5},
    {layout(50, 7, Order::little_endian, true), -5},
    {layout(63, 1, Order::little_endian), 1},
};
const std::vector<uint8_t> kM1Bytes = {0xab, 0xc0, 0x4a, 0x13, 0x33, 0x90, 0xec, 0x81};

// and of M2: SG_ F32 : 7|32@0- with SIG_VALTYPE_ 1 (float32) = -1.5; SG_ Half : 32|8@1+
// (0.5,0) = 0.25; SG_ Half2 : 40|8@1+ (0.5,0) = 0.75 (both halves rounded to even: 0, 2);
// SG_ Big : 48|16@1- (10,100) = -327580: bf c0 00 00 00 02 00 80.
const std::vector<Placed> kM2 = {
    {layout(7, 32, Order::big_endian, true, 1, 0, Type::float32), -1.5},
    {layout(32, 8, Order::little_endian, false, 0.5), 0.25},
    {layout(40, 8, Order::little_endian, false, 0.5), 0.75},
    {layout(48, 16, Order::little_endian, true, 10, 100), -327580},
};
const std::vector<uint8_t> kM2Bytes = {0xbf, 0xc0, 0x00, 0x00, 0x00, 0x02, 0x00, 0x80};

TEST(RestbusCodec, SignalsLandWhereCantoolsPutsThem) {
  EXPECT_EQ(encode(kM1), kM1Bytes);
  EXPECT_EQ(encode(kM2), kM2Bytes);
}

TEST(RestbusCodec, RawValuesReadBackAsTheirPhysicalValues) {
  for (const Placed& p : kM1) {
    EXPECT_EQ(to_physical(p.layout, get_raw(kM1Bytes, p.layout)), p.physical);
  }
  // As cantools decodes M2: the halves as rounded.
  const std::vector<double> m2 = {-1.5, 0.0, 1.0, -327580};
  for (std::size_t i = 0; i < kM2.size(); ++i) {
    EXPECT_EQ(to_physical(kM2[i].layout, get_raw(kM2Bytes, kM2[i].layout)), m2[i]);
  }
}

TEST(RestbusCodec, PuttingASignalLeavesTheOtherBitsAsTheyWere) {
  std::vector<uint8_t> payload(8, 0xFF);
  put_raw(payload, layout(7, 12, Order::big_endian), 0);
  EXPECT_EQ(payload, (std::vector<uint8_t>{0x00, 0x0F, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
  put_raw(payload, layout(50, 7, Order::little_endian), 0);
  EXPECT_EQ(payload, (std::vector<uint8_t>{0x00, 0x0F, 0xFF, 0xFF, 0xFF, 0xFF, 0x03, 0xFE}));
}

TEST(RestbusCodec, ASixtyFourBitSignalTakesTheWholePayload) {
  const SignalLayout le = layout(0, 64, Order::little_endian);
  const SignalLayout be = layout(7, 64, Order::big_endian);
  std::vector<uint8_t> payload(8, 0);
  put_raw(payload, le, 0x0102030405060708);
  EXPECT_EQ(payload, (std::vector<uint8_t>{8, 7, 6, 5, 4, 3, 2, 1}));
  EXPECT_EQ(get_raw(payload, be), 0x0807060504030201u);
}

TEST(RestbusCodec, ValuesTheBitsCannotHoldAreRefusedWithTheRange) {
  const SignalLayout u4 = layout(0, 4, Order::little_endian, false, 1, -5);
  EXPECT_EQ(to_raw(u4, 10).value(), 15u);
  EXPECT_EQ(to_raw(u4, 11).error(), "11 is outside what 4 unsigned bits hold (-5 .. 10)");
  EXPECT_EQ(to_raw(u4, -6).error(), "-6 is outside what 4 unsigned bits hold (-5 .. 10)");
  const SignalLayout s4 = layout(0, 4, Order::little_endian, true);
  EXPECT_EQ(to_raw(s4, -8).value(), 0x8u);
  EXPECT_EQ(to_raw(s4, 7).value(), 0x7u);
  EXPECT_EQ(to_raw(s4, 8).error(), "8 is outside what 4 signed bits hold (-8 .. 7)");
  EXPECT_EQ(to_raw(s4, std::nan("")).error(), "nan is not a number a signal can carry");
  const SignalLayout f32 = layout(0, 32, Order::little_endian, true, 1, 0, Type::float32);
  EXPECT_EQ(to_raw(f32, 1e39).error(), "1e+39 is beyond what a 32-bit float holds");
}

TEST(RestbusCodec, ASignalFitsItsPayloadOrNot) {
  EXPECT_TRUE(fits(layout(56, 8, Order::little_endian), 8));
  EXPECT_FALSE(fits(layout(57, 8, Order::little_endian), 8));
  EXPECT_TRUE(fits(layout(7, 64, Order::big_endian), 8));
  EXPECT_FALSE(fits(layout(6, 64, Order::big_endian), 8));
  EXPECT_TRUE(fits(layout(63, 8, Order::big_endian), 8));  // the last byte
  EXPECT_FALSE(fits(layout(63, 9, Order::big_endian), 8));
  EXPECT_FALSE(fits(layout(0, 0, Order::little_endian), 8));
  EXPECT_FALSE(fits(layout(0, 16, Order::little_endian, true, 1, 0, Type::float32), 8));
  EXPECT_TRUE(fits(layout(0, 64, Order::little_endian, true, 1, 0, Type::float64), 8));
  EXPECT_FALSE(fits(layout(0, 8, Order::little_endian), 0));
}

std::vector<uint8_t> bytes(std::initializer_list<int> list) {
  std::vector<uint8_t> out;
  for (int b : list) {
    out.push_back(static_cast<uint8_t>(b));
  }
  return out;
}

TEST(RestbusCrc8SaeJ1850, MatchesTheCatalogueAndAutosarCheckValues) {
  const std::string digits = "123456789";  // the CRC catalogue's check input: 0x4B
  EXPECT_EQ(crc8_sae_j1850(std::span(reinterpret_cast<const uint8_t*>(digits.data()), 9)), 0x4B);
  // AUTOSAR SWS CRC Library, Crc_CalculateCRC8's test results.
  EXPECT_EQ(crc8_sae_j1850(bytes({0x00, 0x00, 0x00, 0x00})), 0x59);
  EXPECT_EQ(crc8_sae_j1850(bytes({0xF2, 0x01, 0x83})), 0x37);
  EXPECT_EQ(crc8_sae_j1850(bytes({0x0F, 0xAA, 0x00, 0x55})), 0x79);
  EXPECT_EQ(crc8_sae_j1850(bytes({0x00, 0xFF, 0x55, 0x11})), 0xB8);
  EXPECT_EQ(crc8_sae_j1850(bytes({0x33, 0x22, 0x55, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF})), 0xCB);
  EXPECT_EQ(crc8_sae_j1850(bytes({0x92, 0x6B, 0x55})), 0x8C);
  EXPECT_EQ(crc8_sae_j1850(bytes({0xFF, 0xFF, 0xFF, 0xFF})), 0x74);
}

TEST(RestbusChecksum, CoversTheDataIdAndTheOtherBytes) {
  // The check byte at 0 of F2 01 83 under data ID 0x0000: the CRC of 00 00 01 83; the byte
  // that is there does not count.
  const auto payload = bytes({0xEE, 0x01, 0x83});
  EXPECT_EQ(checksum(ChecksumKind::crc8_sae_j1850, 0, payload, 0),
            crc8_sae_j1850(bytes({0x00, 0x00, 0x01, 0x83})));
  EXPECT_EQ(checksum(ChecksumKind::crc8_sae_j1850, 0x55FF, bytes({0x00, 0x11, 0x99}), 2),
            crc8_sae_j1850(bytes({0xFF, 0x55, 0x00, 0x11})));
  EXPECT_EQ(checksum(ChecksumKind::xor8, 0, bytes({0x0F, 0xF0, 0xAA, 0x01}), 2), 0xFE);
  EXPECT_EQ(checksum(ChecksumKind::sum8, 0, bytes({0x80, 0x80, 0x7F, 0x05}), 3), 0x7F);
}

}  // namespace
}  // namespace canemu::daemon::restbus
