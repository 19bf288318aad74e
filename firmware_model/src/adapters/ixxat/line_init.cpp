#include "canemu/firmware_model/adapters/ixxat/line_init.hpp"

#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model::ixxat {

namespace {

constexpr uint8_t kKnownOpModes = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME |
                                  CAN_OPMODE_LISTONLY | CAN_OPMODE_AUTOBAUD;

// The rates CAN_OPMODE_AUTOBAUD tries, fastest first (CiA 301's): the SJA1000's bus timing
// registers, and the CAN FD controller's nominal timing in bit/s form (80 MHz: 16 quanta with the
// sample point at 87.5 %, 800 kbit/s 20 quanta at 85 %).
struct AutobaudRate {
  uint8_t btr0;
  uint8_t btr1;
  CANBTP fd;
};
constexpr AutobaudRate kAutobaudRates[] = {
    {CAN_BT0_1000KB, CAN_BT1_1000KB, {0, 1'000'000, 14, 2, 1, 0}},
    {CAN_BT0_800KB, CAN_BT1_800KB, {0, 800'000, 17, 3, 1, 0}},
    {CAN_BT0_500KB, CAN_BT1_500KB, {0, 500'000, 14, 2, 1, 0}},
    {CAN_BT0_250KB, CAN_BT1_250KB, {0, 250'000, 14, 2, 1, 0}},
    {CAN_BT0_125KB, CAN_BT1_125KB, {0, 125'000, 14, 2, 1, 0}},
    {CAN_BT0_100KB, CAN_BT1_100KB, {0, 100'000, 14, 2, 1, 0}},
    {CAN_BT0_50KB, CAN_BT1_50KB, {0, 50'000, 14, 2, 1, 0}},
    {CAN_BT0_20KB, CAN_BT1_20KB, {0, 20'000, 14, 2, 1, 0}},
    {CAN_BT0_10KB, CAN_BT1_10KB, {0, 10'000, 14, 2, 1, 0}},
};

Btp to_btp(const CANBTP& b) {
  return Btp{b.dwMode, b.dwBPS, b.wTS1, b.wTS2, b.wSJW, b.wTDO};
}

uint32_t features(bool fd) {
  uint32_t f = CAN_FEATURE_STDANDEXT | CAN_FEATURE_RMTFRAME | CAN_FEATURE_ERRFRAME |
               CAN_FEATURE_BUSLOAD | CAN_FEATURE_IDFILTER | CAN_FEATURE_LISTONLY |
               CAN_FEATURE_SCHEDULER | CAN_FEATURE_DELAYEDTX | CAN_FEATURE_SINGLESHOT |
               CAN_FEATURE_HIGHPRIOR | CAN_FEATURE_AUTOBAUD;
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

std::vector<LineInit> autobaud_candidates(const LineInit& init, bool fd_controller) {
  std::vector<LineInit> out;
  for (const AutobaudRate& r : kAutobaudRates) {
    LineInit c = init;
    c.op_mode = static_cast<uint8_t>(init.op_mode & ~CAN_OPMODE_AUTOBAUD);
    c.btr0 = 0;
    c.btr1 = 0;
    c.sdr = CANBTP{};
    c.fdr = CANBTP{};
    if (!init.v2) {
      c.btr0 = r.btr0;
      c.btr1 = r.btr1;
    } else if (fd_controller) {
      c.sdr = r.fd;
    } else {
      c.sdr = btp_of_btr(r.btr0, r.btr1);
    }
    out.push_back(c);
  }
  return out;
}

tl::expected<HostedNodeSettings, HRESULT> line_settings(const LineInit& init, bool fd_controller,
                                                        bool low_speed) {
  const auto invalid = tl::unexpected(VCI_E_INVALIDARG);
  HostedNodeSettings s;
  const uint8_t known_op = kKnownOpModes | (low_speed ? CAN_OPMODE_LOWSPEED : 0);
  if ((init.op_mode & ~known_op) != 0) {
    return invalid;  // low speed needs a low-speed bus
  }
  if ((init.op_mode & CAN_OPMODE_AUTOBAUD) != 0) {
    // The timing fields are ignored: the controller starts with the first rate it will try.
    // The data-phase rate cannot be told from the traffic's arbitration phase: no FASTDATA.
    if (init.v2 && (init.ex_mode & CAN_EXMODE_FASTDATA) != 0) {
      return invalid;
    }
    if (init.v2 && (!valid_filter_mode(init.sf_mode) || !valid_filter_mode(init.ef_mode))) {
      return invalid;
    }
    return line_settings(autobaud_candidates(init, fd_controller).front(), fd_controller,
                         low_speed);
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

namespace {

// The phases of a v2 init the controller is programmed with: the nominal one always, the data
// one with CAN_EXMODE_FASTDATA.
template <class F>
void each_phase(const LineInit& init, bool fd_controller, F&& f) {
  f(init.sdr, fd_controller ? kFdNominalRange : kSja1000BtpRange, Phase::nominal);
  if (fd_controller && (init.ex_mode & CAN_EXMODE_FASTDATA) != 0) {
    f(init.fdr, kFdDataRange, Phase::data);
  }
}

}  // namespace

LineTimings shown_timings(const LineInit& init, bool fd_controller) {
  LineTimings shown{init.sdr, init.fdr};
  each_phase(init, fd_controller, [&](const CANBTP& b, const BtpRange& range, Phase phase) {
    if (auto c = convert_btp(to_btp(b), range, phase)) {
      (phase == Phase::nominal ? shown.sdr : shown.fdr) = to_canbtp(c->shown);
    }
  });
  return shown;
}

std::vector<std::string> timing_conversions(const LineInit& init, bool fd_controller) {
  std::vector<std::string> lines;
  if (!init.v2 || (init.op_mode & CAN_OPMODE_AUTOBAUD) != 0) {
    return lines;
  }
  each_phase(init, fd_controller, [&](const CANBTP& b, const BtpRange& range, Phase phase) {
    auto c = convert_btp(to_btp(b), range, phase);
    if (c && !c->exact) {
      lines.push_back(describe_conversion(to_btp(b), *c, range, phase));
    }
  });
  return lines;
}

std::optional<std::string> timing_error(const LineInit& init, bool fd_controller) {
  std::optional<std::string> why;
  if (!init.v2 || (init.op_mode & CAN_OPMODE_AUTOBAUD) != 0) {
    return why;
  }
  each_phase(init, fd_controller, [&](const CANBTP& b, const BtpRange& range, Phase phase) {
    if (auto t = decode_btp(to_btp(b), range, phase); !t && !why) {
      why = t.error().message;
    }
  });
  return why;
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
