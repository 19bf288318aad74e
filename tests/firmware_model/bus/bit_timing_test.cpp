#include "canemu/firmware_model/bus/bit_timing.hpp"

#include <gtest/gtest.h>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/adapters/sorcus/bit_params.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model {
namespace {

NodeTiming node(const BitTiming& t, int32_t ppm = 0) {
  NodeTiming n;
  n.nominal = t;
  n.oscillator_ppm = ppm;
  return n;
}

const BitTiming k500k = *sja1000::decode_btr(0x00, 0x1C);

TEST(BitTiming, DurationsAreExactAndRoundedOnce) {
  EXPECT_EQ(k500k.bits_duration(1).ns(), 2000);
  EXPECT_EQ(k500k.bits_duration(111).ns(), 222'000);
  // 666 2/3 kbit/s: 1500 ns per bit; 833 1/3 kbit/s (SL-CANi): 1200 ns.
  EXPECT_EQ(sja1000::decode_btr(0x00, 0x18)->bits_duration(3).ns(), 4500);
  const BitTiming sl125 = *sorcus::decode_sorcus(sorcus::kSlCani, {400, 16, 2, 1, 1});
  EXPECT_EQ(sl125.bits_duration(1).ns(), 7600);
}

TEST(BitTiming, QuantaDurationMixesTwoQuantaExactly) {
  // 80 MHz: 12.5 ns data quanta. Three of them are 37.5 ns: rounding happens once, at the end.
  const BitTiming data =
      *ixxat::decode_btp({0, 8000000, 8, 2, 1, 0}, ixxat::kFdDataRange, ixxat::Phase::data);
  EXPECT_EQ(quanta_duration(data, 3, data, 0).ns(), 38);  // 37.5 rounds to nearest (up)
  EXPECT_EQ(quanta_duration(data, 3, data, 1).ns(), 50);
  EXPECT_EQ(quanta_duration(k500k, 2, data, 4).ns(), 300);
}

TEST(BitTiming, ToleranceFollowsTheIsoConditions) {
  // 16 quanta, SJW 1: sjw / (20 * 16) = 0.3125 %; phase condition 2 / (2 * (208 - 2)) = 0.485 %.
  EXPECT_DOUBLE_EQ(k500k.oscillator_tolerance(), 1.0 / 320.0);
  // 8 quanta, SJW 1, TSEG2 2: min(1/160, 2 / (2 * (104 - 2))) = 1/102.
  EXPECT_DOUBLE_EQ(sja1000::decode_btr(0x00, 0x14)->oscillator_tolerance(), 1.0 / 160.0);
}

TEST(Compatibility, IdenticalTimingsTalk) {
  const auto c = check_compatibility(node(k500k), node(k500k), false);
  EXPECT_TRUE(c.ok);
  EXPECT_EQ(c.mismatch, 0.0);
  EXPECT_DOUBLE_EQ(c.tolerance, 2.0 / 320.0);
}

TEST(Compatibility, DifferentSamplePointsAtTheSameRateTalk) {
  // SORCUS 500k (85 %) and IXXAT 500k (87.5 %).
  const BitTiming sl500 = *sorcus::decode_sorcus(sorcus::kSlCani, {100, 16, 3, 1, 1});
  EXPECT_TRUE(check_compatibility(node(sl500), node(k500k), false).ok);
  EXPECT_TRUE(check_compatibility(node(k500k), node(sl500), false).ok);
}

TEST(Compatibility, TheMisTabledSlCaniRowCannotTalkToA125kBus) {
  const BitTiming sl125 = *sorcus::decode_sorcus(sorcus::kSlCani, {400, 16, 2, 1, 1});
  const BitTiming ix125 = *sja1000::decode_btr(0x03, 0x1C);
  const auto c = check_compatibility(node(sl125), node(ix125), false);
  EXPECT_FALSE(c.ok);
  EXPECT_NEAR(c.mismatch, 0.0526, 0.0001);
}

TEST(Compatibility, OscillatorOffsetsBreakDecodingExactlyBeyondTolerance) {
  // Tolerance of the 500k timing is 2 * 0.3125 % = 6250 ppm of relative mismatch.
  EXPECT_TRUE(check_compatibility(node(k500k, 3000), node(k500k, -3000), false).ok);
  EXPECT_FALSE(check_compatibility(node(k500k, 3200), node(k500k, -3200), false).ok);
  EXPECT_TRUE(check_compatibility(node(k500k, 6000), node(k500k, 0), false).ok);
  EXPECT_FALSE(check_compatibility(node(k500k, 6500), node(k500k, 0), false).ok);
}

TEST(Compatibility, BitRateSwitchNeedsMatchingDataPhases) {
  const BitTiming nominal =
      *ixxat::decode_btp({0, 500000, 14, 2, 1, 0}, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  const BitTiming d2m =
      *ixxat::decode_btp({0, 2000000, 30, 10, 4, 0}, ixxat::kFdDataRange, ixxat::Phase::data);
  const BitTiming d4m =
      *ixxat::decode_btp({0, 4000000, 15, 5, 2, 0}, ixxat::kFdDataRange, ixxat::Phase::data);
  NodeTiming a = node(nominal);
  a.data = d2m;
  a.has_data_phase = true;
  NodeTiming b = a;
  EXPECT_TRUE(check_compatibility(a, b, true).ok);
  b.data = d4m;
  const auto c = check_compatibility(a, b, true);
  EXPECT_FALSE(c.ok);
  EXPECT_TRUE(c.data_phase);
  // Without BRS the data phase does not matter.
  EXPECT_TRUE(check_compatibility(a, b, false).ok);
  // A classic-only receiver cannot follow a bit-rate switch.
  EXPECT_FALSE(check_compatibility(a, node(nominal), true).ok);
}

}  // namespace
}  // namespace canemu::model
