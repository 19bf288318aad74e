// How InitLine programs the controller, and the capabilities a line reports (line_init.hpp).
#include "canemu/firmware_model/adapters/ixxat/line_init.hpp"

#include <gtest/gtest.h>

#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model {
namespace {

using ixxat::LineInit;

LineInit v1(uint8_t btr0, uint8_t btr1, uint8_t op_mode = CAN_OPMODE_STANDARD) {
  LineInit i;
  i.op_mode = op_mode;
  i.btr0 = btr0;
  i.btr1 = btr1;
  return i;
}

LineInit v2(CANBTP sdr, uint8_t ex_mode = CAN_EXMODE_DISABLED) {
  LineInit i;
  i.v2 = true;
  i.ex_mode = ex_mode;
  i.sdr = sdr;
  return i;
}

TEST(LineInit, AV1InitHandsTheRegistersToAnSja1000AsTheyAre) {
  const auto s = ixxat::line_settings(v1(0x01, 0x1C, CAN_OPMODE_LISTONLY), false, false);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->btr0, 0x01);
  EXPECT_EQ(s->btr1, 0x1C);
  EXPECT_TRUE(s->listen_only);
  EXPECT_FALSE(s->fd);
}

TEST(LineInit, AV1InitOnTheFdControllerRunsTheRegistersTimingClassic) {
  // BTR0 0x00, BTR1 0x1C on 16 MHz: prescaler 2, 1 + 13 + 2 quanta, 500 kbit/s.
  const auto s = ixxat::line_settings(v1(0x00, 0x1C), true, false);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->nominal.prescaler, 2u);
  EXPECT_EQ(s->nominal.tseg1, 13u);
  EXPECT_EQ(s->nominal.tseg2, 2u);
  EXPECT_EQ(s->data.tseg1, 13u);
  EXPECT_FALSE(s->fd);
  // 1 + 1 + 1 quanta is no bit time.
  EXPECT_EQ(ixxat::line_settings(v1(0x00, 0x00), true, false).error(), VCI_E_INVALIDARG);
}

TEST(LineInit, AV2InitOnAnSja1000GivesItsBitTimingRegisters) {
  // 500 kbit/s in bit/s form, 14 + 2 quanta with the sync quantum, on the 8 MHz CAN clock:
  // prescaler 1, TSEG1 13, TSEG2 2: BTR0 0x00, BTR1 0x1C.
  const CANBTP b500 = CAN_BTP_500KB;
  const auto s = ixxat::line_settings(v2(b500), false, false);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->btr0, CAN_BT0_500KB);
  EXPECT_EQ(s->btr1, CAN_BT1_500KB);
  EXPECT_EQ(s->nominal.tseg1, 13u);
  EXPECT_EQ(s->nominal.tseg2, 2u);
  EXPECT_FALSE(s->fd);
}

TEST(LineInit, AV2InitOnTheFdControllerTakesBothTimingsAndTheFdModes) {
  const CANBTP sdr{0, 500'000, 14, 2, 1, 0};
  const CANBTP fdr{0, 2'000'000, 8, 2, 1, 0};
  LineInit i = v2(sdr, CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  i.fdr = fdr;
  const auto s = ixxat::line_settings(i, true, false);
  ASSERT_TRUE(s.has_value());
  // 80 MHz: 500 kbit/s is prescaler 10 with 16 quanta, 2 Mbit/s prescaler 4 with 10.
  EXPECT_EQ(s->nominal.prescaler, 10u);
  EXPECT_EQ(s->nominal.quanta_per_bit(), 16u);
  EXPECT_EQ(s->data.prescaler, 4u);
  EXPECT_EQ(s->data.quanta_per_bit(), 10u);
  EXPECT_TRUE(s->fd);
  // Without FASTDATA the data phase runs at the nominal rate.
  const auto slow = ixxat::line_settings(v2(sdr, CAN_EXMODE_EXTDATA), true, false);
  ASSERT_TRUE(slow.has_value());
  EXPECT_EQ(slow->data.prescaler, 10u);
  EXPECT_TRUE(slow->fd);
}

// CAN_OPMODE_AUTOBAUD: the timing fields are ignored (garbage is accepted), and the rates it tries
// run on both controllers through both interfaces, at exactly their bit times.
TEST(LineInit, AutobaudIgnoresTheTimingAndTriesTheCiaRatesFastestFirst) {
  const int64_t bit_ns[] = {1'000, 1'250, 2'000, 4'000, 8'000, 10'000, 20'000, 50'000, 100'000};
  for (const bool fd : {false, true}) {
    for (const bool use_v2 : {false, true}) {
      LineInit init = use_v2 ? v2(CANBTP{0, 300'000, 1, 0, 0, 0}) : v1(0xFF, 0xFF);
      init.op_mode = CAN_OPMODE_STANDARD | CAN_OPMODE_ERRFRAME | CAN_OPMODE_AUTOBAUD;
      const auto s = ixxat::line_settings(init, fd, false);
      ASSERT_TRUE(s.has_value()) << fd << use_v2;
      EXPECT_FALSE(s->listen_only);
      const auto table = ixxat::autobaud_candidates(init, fd);
      ASSERT_EQ(table.size(), 9u);
      for (std::size_t k = 0; k < table.size(); ++k) {
        EXPECT_EQ(table[k].op_mode, CAN_OPMODE_STANDARD | CAN_OPMODE_ERRFRAME);
        const auto e = ixxat::line_settings(table[k], fd, false);
        ASSERT_TRUE(e.has_value()) << fd << use_v2 << k;
        const BitTiming t = fd ? e->nominal : sja1000::timing_from_btr(e->btr0, e->btr1);
        EXPECT_EQ(t.bits_duration(1).ns(), bit_ns[k]) << fd << use_v2 << k;
      }
      // The controller starts with the first of them.
      EXPECT_EQ(s->btr0, ixxat::line_settings(table[0], fd, false)->btr0);
    }
  }
  EXPECT_EQ(ixxat::autobaud_candidates(v1(0, 0), false)[3].btr0, CAN_BT0_250KB);
  EXPECT_EQ(ixxat::autobaud_candidates(v1(0, 0), false)[3].btr1, CAN_BT1_250KB);
  const UINT32 bps = ixxat::autobaud_candidates(v2(CANBTP{}), true)[3].sdr.dwBPS;  // packed
  EXPECT_EQ(bps, 250'000u);
}

TEST(LineInit, ModesTheLineDoesNotHaveAreInvalidArguments) {
  const CANBTP b500 = CAN_BTP_500KB;
  // Low speed only on a low-speed bus.
  const LineInit low = v1(0x00, 0x1C, CAN_OPMODE_STANDARD | CAN_OPMODE_LOWSPEED);
  EXPECT_EQ(ixxat::line_settings(low, false, false).error(), VCI_E_INVALIDARG);
  EXPECT_TRUE(ixxat::line_settings(low, false, true).has_value());
  // Bit-rate detection with a fast data phase: its rate cannot be told from the traffic.
  LineInit autobaud_fast = v2(b500, CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  autobaud_fast.op_mode = CAN_OPMODE_STANDARD | CAN_OPMODE_AUTOBAUD;
  EXPECT_EQ(ixxat::line_settings(autobaud_fast, true, false).error(), VCI_E_INVALIDARG);
  // FD modes on a classic controller.
  EXPECT_EQ(ixxat::line_settings(v2(b500, CAN_EXMODE_EXTDATA), false, false).error(),
            VCI_E_INVALIDARG);
  // A filter mode that is none of LOCK, PASS, INCL, EXCL.
  LineInit bad_filter = v2(b500);
  bad_filter.sf_mode = 0x7F;
  EXPECT_EQ(ixxat::line_settings(bad_filter, false, false).error(), VCI_E_INVALIDARG);
  // 4 kbit/s is below the SJA1000's slowest rate (8 MHz / (64 x 25 quanta) = 5 kbit/s).
  EXPECT_EQ(ixxat::line_settings(v2({0, 4'000, 14, 2, 1, 0}), false, false).error(),
            VCI_E_INVALIDARG);
}

TEST(LineInit, TheRawCanbtpOfSja1000RegistersCountsTheEightMegahertzClock) {
  const CANBTP b = ixxat::btp_of_btr(0x41, 0x9C);  // SJW 2, BRP 1; SAM, TSEG2 2, TSEG1 13
  EXPECT_EQ(b.dwMode, static_cast<UINT32>(CAN_BTMODE_RAW | CAN_BTMODE_TSM));
  EXPECT_EQ(b.dwBPS, 2u);
  EXPECT_EQ(b.wTS1, 13);
  EXPECT_EQ(b.wTS2, 2);
  EXPECT_EQ(b.wSJW, 2);
  EXPECT_EQ(b.wTDO, 0);
}

TEST(LineInit, CapabilitiesNameTheControllerTheCouplingAndTheClocks) {
  ixxat::Clocks clocks;
  clocks.cms_divisor = 500;
  const CANCAPABILITIES c = ixxat::capabilities(false, true, clocks);
  EXPECT_EQ(c.wCtrlType, CAN_CTRL_SJA1000);
  EXPECT_EQ(c.wBusCoupling, CAN_BUSC_LOWSPEED);
  EXPECT_NE(c.dwFeatures & CAN_FEATURE_SCHEDULER, 0u);
  EXPECT_EQ(c.dwFeatures & CAN_FEATURE_EXTDATA, 0u);
  EXPECT_EQ(c.dwClockFreq, 1'000'000u);
  EXPECT_EQ(c.dwCmsDivisor, 500u);
  const CANCAPABILITIES2 classic = ixxat::capabilities2(false, false, clocks);
  EXPECT_EQ(classic.wBusCoupling, CAN_BUSC_HIGHSPEED);
  EXPECT_EQ(classic.dwCanClkFreq, 8'000'000u);
  EXPECT_EQ(classic.sSdrRangeMax.dwBPS, 64u);
  EXPECT_EQ(classic.sSdrRangeMax.wTS1, 16);
  EXPECT_EQ(classic.sFdrRangeMax.dwBPS, 0u);  // no data phase
  EXPECT_EQ(classic.dwCmsClkFreq, 1'000'000u);
  const CANCAPABILITIES2 fd = ixxat::capabilities2(true, false, clocks);
  EXPECT_EQ(fd.wCtrlType, CAN_CTRL_IFICFD);
  EXPECT_NE(fd.dwFeatures & CAN_FEATURE_FASTDATA, 0u);
  EXPECT_EQ(fd.dwCanClkFreq, 80'000'000u);
  EXPECT_EQ(fd.sSdrRangeMax.dwBPS, 1024u);
  EXPECT_EQ(fd.sFdrRangeMax.dwBPS, 32u);
  EXPECT_EQ(fd.sFdrRangeMax.wTDO, 255);
}

}  // namespace
}  // namespace canemu::model
