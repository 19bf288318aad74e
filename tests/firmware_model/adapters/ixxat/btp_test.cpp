#include "canemu/firmware_model/adapters/ixxat/btp.hpp"

#include <gtest/gtest.h>

#include <string>

#include "timing_expect.hpp"

namespace canemu::model {
namespace {

using test_support::check;
using test_support::Expect;

// VCI CANBTP against the emulated 80 MHz CAN FD controller.
TEST(VciBtp, BitPerSecondPresetsDecodeToTheirRates) {
  struct Row {
    uint32_t bps;
    uint16_t ts1, ts2;
    uint32_t prescaler;
  };
  // CAN_BTP_xxKB presets: 5k {17, 8}, 10k..500k {14, 2}, 800k {8, 2}, 1000k {6, 2}.
  for (const Row& r : {Row{5000, 17, 8, 640}, Row{10000, 14, 2, 500}, Row{125000, 14, 2, 40},
                       Row{500000, 14, 2, 10}, Row{800000, 8, 2, 10}, Row{1000000, 6, 2, 10}}) {
    auto t = ixxat::decode_btp({0, r.bps, r.ts1, r.ts2, 1, 0}, ixxat::kFdNominalRange,
                               ixxat::Phase::nominal);
    ASSERT_TRUE(t) << r.bps << ": " << t.error().message;
    EXPECT_EQ(t->bit_rate(), (BitRate{r.bps, 1}));
    EXPECT_EQ(t->prescaler, r.prescaler);
    EXPECT_EQ(t->tseg1, r.ts1 - 1u);  // the sync quantum leaves tseg1
    EXPECT_EQ(t->quanta_per_bit(), uint32_t{r.ts1} + r.ts2);
  }
}

TEST(VciBtp, RawFormUsesThePrescalerAndExcludesSync) {
  auto t = ixxat::decode_btp({ixxat::kBtModeRaw | ixxat::kBtModeTsm, 10, 13, 2, 1, 0},
                             ixxat::kFdNominalRange, ixxat::Phase::nominal);
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_EQ(t->bit_rate(), (BitRate{500000, 1}));
  EXPECT_EQ(t->samples, 3);
  EXPECT_EQ(t->sample_point_permille(), 875u);
  auto raw = ixxat::to_raw({0, 500000, 14, 2, 1, 0}, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  ASSERT_TRUE(raw);
  EXPECT_EQ(raw->mode, ixxat::kBtModeRaw);
  EXPECT_EQ(raw->bps, 10u);
  EXPECT_EQ(raw->ts1, 13);
}

TEST(VciBtp, DataPhaseDecodesFastRates) {
  auto t = ixxat::decode_btp({0, 8000000, 8, 2, 1, 0}, ixxat::kFdDataRange, ixxat::Phase::data);
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_EQ(t->bit_rate(), (BitRate{8000000, 1}));
  EXPECT_EQ(t->quantum_ps(), 12'500u);
  EXPECT_EQ(t->sample_point_permille(), 800u);
}

TEST(VciBtp, RejectsRatesTheClockCannotDivideTo) {
  auto t =
      ixxat::decode_btp({0, 300000, 14, 2, 1, 0}, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error().code, ModelErrc::timing_not_realizable);
  EXPECT_NE(t.error().message.find("80000000 Hz controller clock is not a whole multiple of "
                                   "300000 bit/s x 16 quanta"),
            std::string::npos)
      << t.error().message;
}

TEST(VciBtp, RejectsRawValuesOutsideTheCapabilityRanges) {
  auto np = ixxat::decode_btp({ixxat::kBtModeRaw, 2000, 13, 2, 1, 0}, ixxat::kFdNominalRange,
                              ixxat::Phase::nominal);
  ASSERT_FALSE(np);
  EXPECT_EQ(np.error().code, ModelErrc::timing_out_of_range);
  EXPECT_EQ(np.error().message, "nominal (sSdr) CANBTP prescaler = 2000 is outside 1..1024");
  auto ts1 = ixxat::decode_btp({ixxat::kBtModeRaw, 1, 40, 2, 1, 0}, ixxat::kFdDataRange,
                               ixxat::Phase::data);
  ASSERT_FALSE(ts1);
  EXPECT_EQ(ts1.error().message, "data (sFdr) CANBTP wTS1 (raw) = 40 is outside 1..32");
  auto ts2 = ixxat::decode_btp({ixxat::kBtModeRaw, 10, 13, 1, 1, 0}, ixxat::kFdNominalRange,
                               ixxat::Phase::nominal);
  ASSERT_FALSE(ts2);
  EXPECT_EQ(ts2.error().message, "nominal (sSdr) CANBTP wTS2 = 1 is outside 2..128");
}

TEST(VciBtp, RejectsSjwAboveAPhaseSegmentAndUnknownModeBits) {
  auto sjw = ixxat::decode_btp({ixxat::kBtModeRaw, 10, 13, 2, 3, 0}, ixxat::kFdNominalRange,
                               ixxat::Phase::nominal);
  ASSERT_FALSE(sjw);
  EXPECT_EQ(sjw.error().code, ModelErrc::timing_rule_violated);
  auto mode =
      ixxat::decode_btp({0x10, 500000, 14, 2, 1, 0}, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  ASSERT_FALSE(mode);
  EXPECT_NE(mode.error().message.find("dwMode = 0x10"), std::string::npos);
}

TEST(VciBtp, AControllerWithoutFastDataHasNoDataPhase) {
  auto t = ixxat::decode_btp({0, 2000000, 30, 10, 1, 0}, ixxat::BtpRange{}, ixxat::Phase::data);
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error().message, "the controller has no data (sFdr) phase timing");
}

}  // namespace
}  // namespace canemu::model

namespace canemu::model {
namespace {

TEST(VciTimingFor, UsesTheSmallestPrescalerWithTheSamplePointAskedFor) {
  const auto t = ixxat::timing_for(500'000, 800, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->prescaler, 1u);
  EXPECT_EQ(t->tseg1, 127u);
  EXPECT_EQ(t->tseg2, 32u);
  EXPECT_EQ(t->sjw, 4u);
  EXPECT_EQ(t->sample_point_permille(), 800u);
}

TEST(VciTimingFor, DataPhaseRatesComeFromTheDataRanges) {
  const auto t = ixxat::timing_for(2'000'000, 800, ixxat::kFdDataRange, ixxat::Phase::data);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->bit_rate(), (BitRate{2'000'000, 1}));
  EXPECT_EQ(t->prescaler, 1u);  // 40 quanta: 1 + 31 + 8
  EXPECT_EQ(t->tseg1, 31u);
  EXPECT_EQ(t->tseg2, 8u);
}

TEST(VciTimingFor, FindsNothingWhenTheClockCannotMakeTheRate) {
  EXPECT_FALSE(ixxat::timing_for(3, 800, ixxat::kFdNominalRange, ixxat::Phase::nominal));
  EXPECT_FALSE(ixxat::timing_for(0, 800, ixxat::kFdNominalRange, ixxat::Phase::nominal));
}

}  // namespace
}  // namespace canemu::model
