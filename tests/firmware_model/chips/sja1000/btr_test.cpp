#include "canemu/firmware_model/chips/sja1000/btr.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "timing_expect.hpp"

namespace canemu::model {
namespace {

using test_support::check;
using test_support::Expect;

// Golden vectors: the VCI bit-rate table (CAN_BT0_xxKB / CAN_BT1_xxKB, SJA1000 at 16 MHz).
struct BtrRow {
  int kbit;
  uint8_t btr0, btr1;
  Expect expect;
};

class Sja1000VciTable : public ::testing::TestWithParam<BtrRow> {};

TEST_P(Sja1000VciTable, DecodesToTheNominalRate) {
  const BtrRow& r = GetParam();
  check(sja1000::decode_btr(r.btr0, r.btr1), r.expect, std::to_string(r.kbit) + " kbit/s");
  EXPECT_EQ(sja1000::decode_btr(r.btr0, r.btr1)->bit_rate().bps(), r.kbit * 1000.0);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, Sja1000VciTable,
    ::testing::Values(BtrRow{5, 0x3F, 0x7F, {5000, 1, 8'000'000, 25, 680, 1}},
                      BtrRow{10, 0x31, 0x1C, {10000, 1, 6'250'000, 16, 875, 1}},
                      BtrRow{20, 0x18, 0x1C, {20000, 1, 3'125'000, 16, 875, 1}},
                      BtrRow{50, 0x09, 0x1C, {50000, 1, 1'250'000, 16, 875, 1}},
                      BtrRow{100, 0x04, 0x1C, {100000, 1, 625'000, 16, 875, 1}},
                      BtrRow{125, 0x03, 0x1C, {125000, 1, 500'000, 16, 875, 1}},
                      BtrRow{250, 0x01, 0x1C, {250000, 1, 250'000, 16, 875, 1}},
                      BtrRow{500, 0x00, 0x1C, {500000, 1, 125'000, 16, 875, 1}},
                      BtrRow{800, 0x00, 0x16, {800000, 1, 125'000, 10, 800, 1}},
                      BtrRow{1000, 0x00, 0x14, {1000000, 1, 125'000, 8, 750, 1}}),
    [](const auto& param_info) { return std::to_string(param_info.param.kbit) + "kbit"; });

TEST(Sja1000Btr, SixHundredSixtySevenKbitIsExactlyTwoThirdsOfAMegabit) {
  // CAN_BT0_667KB / CAN_BT1_667KB of VCI V4: 12 quanta of 125 ns.
  check(sja1000::decode_btr(0x00, 0x18), {2'000'000, 3, 125'000, 12, 833, 1}, "667k");
}

TEST(Sja1000Btr, DecodesSjwAndTripleSampling) {
  auto t = sja1000::decode_btr(0x81, 0xAB);  // SJW 3, BRP 2, SAM, TSEG2 3, TSEG1 12
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_EQ(t->sjw, 3u);
  EXPECT_EQ(t->samples, 3);
  EXPECT_EQ(t->prescaler, 4u);
  EXPECT_EQ(t->bit_rate().bps(), 250000.0);
}

TEST(Sja1000Btr, RejectsFewerThanEightQuanta) {
  auto t = sja1000::decode_btr(0x00, 0x10);  // TSEG1 1, TSEG2 2: 4 quanta
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error().code, ModelErrc::timing_rule_violated);
  EXPECT_EQ(t.error().message,
            "BTR0=0x00 BTR1=0x10: 1 + TSEG1 + TSEG2 = 4 quanta, but a bit needs at least 8");
}

TEST(Sja1000Btr, RejectsPhaseSegmentTwoShorterThanTheProcessingTime) {
  auto t = sja1000::decode_btr(0x00, 0x0F);  // TSEG1 16, TSEG2 1
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find("TSEG2 = 1"), std::string::npos) << t.error().message;
}

TEST(Sja1000Btr, RejectsSjwLongerThanPhaseSegmentTwo) {
  auto t = sja1000::decode_btr(0xC0, 0x1C);  // SJW 4, TSEG2 2
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error().message,
            "BTR0=0xC0 BTR1=0x1C: SJW = 4 exceeds TSEG2 = 2 (rule SJW <= TSEG2)");
}

}  // namespace
}  // namespace canemu::model

namespace canemu::model {
namespace {

TEST(Sja1000BtrFor, FindsIxxatsFiveHundredKbitValuesForAnEightySevenAndAHalfPercentSamplePoint) {
  EXPECT_EQ(sja1000::btr_for(500'000, 875), (sja1000::Btr{0x00, 0x1C}));
}

TEST(Sja1000BtrFor, PrefersTheSamplePointClosestToTheOneAskedFor) {
  const auto btr = sja1000::btr_for(125'000, 750);
  ASSERT_TRUE(btr);
  const auto t = sja1000::decode_btr(btr->btr0, btr->btr1);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->bit_rate(), (BitRate{125'000, 1}));
  EXPECT_EQ(t->sample_point_permille(), 750u);
}

TEST(Sja1000BtrFor, FindsNothingForARateTheOscillatorCannotMake) {
  EXPECT_FALSE(sja1000::btr_for(7, 875));
  EXPECT_FALSE(sja1000::btr_for(2'000'000, 875));  // 8 quanta at least: 1 Mbit/s is the top
  EXPECT_FALSE(sja1000::btr_for(0, 875));
  EXPECT_FALSE(sja1000::btr_for(500'000, 875, 0));
}

// The search as the register map defines it: all 7,168 (BRP, TSEG1, TSEG2) values in order,
// the first with the smallest sample-point error among those that decode to the rate.
std::optional<sja1000::Btr> every_register_value(uint32_t bitrate, uint32_t point, uint32_t osc) {
  std::optional<sja1000::Btr> best;
  uint32_t best_error = UINT32_MAX;
  for (uint8_t brp = 0; brp < 64; ++brp) {
    for (uint8_t t2 = 1; t2 < 8; ++t2) {
      for (uint8_t t1 = 0; t1 < 16; ++t1) {
        const uint8_t btr1 = static_cast<uint8_t>((t2 << 4) | t1);
        if (!(sja1000::timing_from_btr(brp, btr1, osc).bit_rate() == BitRate{bitrate, 1})) {
          continue;
        }
        const auto t = sja1000::decode_btr(brp, btr1, osc);
        if (!t) {
          continue;
        }
        const uint32_t p = t->sample_point_permille();
        const uint32_t error = p > point ? p - point : point - p;
        if (error < best_error) {
          best_error = error;
          best = sja1000::Btr{brp, btr1};
        }
      }
    }
  }
  return best;
}

TEST(Sja1000BtrFor, ChoosesWhatTryingEveryRegisterValueChooses) {
  int found = 0;
  for (const uint32_t osc : {16'000'000u, 24'000'000u, 8'000'000u}) {
    for (uint32_t rate = 5'000; rate <= 1'000'000; rate += 5'000) {
      for (const uint32_t point : {500u, 750u, 800u, 875u, 900u}) {
        const auto expected = every_register_value(rate, point, osc);
        ASSERT_EQ(sja1000::btr_for(rate, point, osc), expected)
            << rate << " bit/s at " << point << " per mille, " << osc << " Hz";
        found += expected ? 1 : 0;
      }
    }
  }
  EXPECT_GE(found, 250);  // not vacuous: many of these rates exist on these oscillators
}

}  // namespace
}  // namespace canemu::model
