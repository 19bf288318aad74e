#include "canemu/firmware_model/adapters/ixxat/line_init.hpp"

#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model::ixxat {

namespace {

constexpr uint8_t kKnownOpModes =
    CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME | CAN_OPMODE_LISTONLY;

Btp to_btp(const CANBTP& b) {
  return Btp{b.dwMode, b.dwBPS, b.wTS1, b.wTS2, b.wSJW, b.wTDO};
}

uint32_t features(bool fd) {
  uint32_t f = CAN_FEATURE_STDANDEXT | CAN_FEATURE_RMTFRAME | CAN_FEATURE_ERRFRAME |
               CAN_FEATURE_BUSLOAD | CAN_FEATURE_IDFILTER | CAN_FEATURE_LISTONLY |
               CAN_FEATURE_SCHEDULER | CAN_FEATURE_DELAYEDTX | CAN_FEATURE_SINGLESHOT |
               CAN_FEATURE_HIGHPRIOR;
  if (fd) {
    f |= CAN_FEATURE_EXTDATA | CAN_FEATURE_FASTDATA | CAN_FEATURE_ISOFRAME;
  }
  return f;
}

CANBTP to_canbtp(const Btp& b) {
  CANBTP c{};
  c.dwMode = b.mode;
  c.dwBPS = b.bps;
  c.wTS1 = b.ts1;
  c.wTS2 = b.ts2;
  c.wSJW = b.sjw;
  c.wTDO = b.tdo;
  return c;
}

}  // namespace

tl::expected<HostedNodeSettings, HRESULT> line_settings(const LineInit& init, bool fd_controller,
                                                        bool low_speed) {
  const auto invalid = tl::unexpected(VCI_E_INVALIDARG);
  HostedNodeSettings s;
  const uint8_t known_op = kKnownOpModes | (low_speed ? CAN_OPMODE_LOWSPEED : 0);
  if ((init.op_mode & ~known_op) != 0) {
    // Hardware bit-rate detection is not emulated; low speed needs a low-speed bus.
    return invalid;
  }
  const bool fd = fd_controller;
  s.listen_only = (init.op_mode & CAN_OPMODE_LISTONLY) != 0;
  if (!init.v2) {
    s.btr0 = init.btr0;
    s.btr1 = init.btr1;
    if (fd) {
      auto t = sja1000::decode_btr(init.btr0, init.btr1);
      if (!t) {
        return invalid;
      }
      s.nominal = *t;
      s.data = *t;
    }
    s.fd = false;
    return s;
  }
  if (!valid_filter_mode(init.sf_mode) || !valid_filter_mode(init.ef_mode)) {
    return invalid;
  }
  const uint8_t known_ex = fd ? (CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA) : 0;
  if ((init.ex_mode & ~known_ex) != 0) {
    return invalid;  // FD modes on a classic controller; non-ISO frames are not emulated
  }
  const BtpRange& range = fd ? kFdNominalRange : kSja1000BtpRange;
  auto nominal = decode_btp(to_btp(init.sdr), range, Phase::nominal);
  if (!nominal) {
    return invalid;
  }
  s.nominal = *nominal;
  s.data = *nominal;
  if (!fd) {
    auto raw = to_raw(to_btp(init.sdr), range, Phase::nominal);
    if (!raw) {
      return invalid;
    }
    s.btr0 = static_cast<uint8_t>(((raw->sjw - 1) << 6) | (raw->bps - 1));
    s.btr1 = static_cast<uint8_t>(((raw->mode & kBtModeTsm) != 0 ? 0x80 : 0) |
                                  ((raw->ts2 - 1) << 4) | (raw->ts1 - 1));
  }
  if ((init.ex_mode & CAN_EXMODE_FASTDATA) != 0) {
    auto data = decode_btp(to_btp(init.fdr), kFdDataRange, Phase::data);
    if (!data) {
      return invalid;
    }
    s.data = *data;
  }
  s.fd = (init.ex_mode & (CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA)) != 0;
  return s;
}

// The raw CANBTP of an SJA1000 timing: the prescaler counts the chip's 8 MHz CAN clock (half the
// oscillator), so BRP + 1.
CANBTP btp_of_btr(uint8_t btr0, uint8_t btr1) {
  const BitTiming t = sja1000::timing_from_btr(btr0, btr1);
  CANBTP b{};
  b.dwMode = CAN_BTMODE_RAW | (t.samples == 3 ? CAN_BTMODE_TSM : 0);
  b.dwBPS = t.prescaler / 2;
  b.wTS1 = static_cast<UINT16>(t.tseg1);
  b.wTS2 = static_cast<UINT16>(t.tseg2);
  b.wSJW = static_cast<UINT16>(t.sjw);
  return b;
}

CANCAPABILITIES capabilities(bool fd, bool low_speed, const Clocks& clocks) {
  CANCAPABILITIES c{};
  c.wCtrlType = fd ? CAN_CTRL_IFICFD : CAN_CTRL_SJA1000;
  c.wBusCoupling = low_speed ? CAN_BUSC_LOWSPEED : CAN_BUSC_HIGHSPEED;
  c.dwFeatures = features(fd);
  c.dwClockFreq = clocks.clock_hz;
  c.dwTscDivisor = clocks.tsc_divisor;
  c.dwCmsDivisor = clocks.cms_divisor;
  c.dwCmsMaxTicks = clocks.cms_max_ticks;
  c.dwDtxDivisor = clocks.dtx_divisor;
  c.dwDtxMaxTicks = clocks.dtx_max_ticks;
  return c;
}

CANCAPABILITIES2 capabilities2(bool fd, bool low_speed, const Clocks& clocks) {
  CANCAPABILITIES2 c{};
  c.wCtrlType = fd ? CAN_CTRL_IFICFD : CAN_CTRL_SJA1000;
  c.wBusCoupling = low_speed ? CAN_BUSC_LOWSPEED : CAN_BUSC_HIGHSPEED;
  c.dwFeatures = features(fd);
  const BtpRange& nominal = fd ? kFdNominalRange : kSja1000BtpRange;
  c.dwCanClkFreq = nominal.clock_hz;
  c.sSdrRangeMin = to_canbtp(nominal.min);
  c.sSdrRangeMax = to_canbtp(nominal.max);
  if (fd) {
    c.sFdrRangeMin = to_canbtp(kFdDataRange.min);
    c.sFdrRangeMax = to_canbtp(kFdDataRange.max);
  }
  c.dwTscClkFreq = clocks.clock_hz;
  c.dwTscDivisor = clocks.tsc_divisor;
  c.dwCmsClkFreq = clocks.clock_hz;
  c.dwCmsDivisor = clocks.cms_divisor;
  c.dwCmsMaxTicks = clocks.cms_max_ticks;
  c.dwDtxClkFreq = clocks.clock_hz;
  c.dwDtxDivisor = clocks.dtx_divisor;
  c.dwDtxMaxTicks = clocks.dtx_max_ticks;
  return c;
}

}  // namespace canemu::model::ixxat
