#include "canemu/firmware_model/adapters/ixxat/btp.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "bus/timing_errors.hpp"

namespace canemu::model::ixxat {

namespace {

std::string_view phase_name(Phase phase) {
  return phase == Phase::nominal ? "nominal (sSdr)" : "data (sFdr)";
}

}  // namespace

namespace {

Result<void> check_mode(const Btp& btp, const BtpRange& range, Phase phase) {
  if (range.clock_hz == 0) {
    return model_error(ModelErrc::timing_not_realizable,
                       fmt::format("the controller has no {} phase timing", phase_name(phase)));
  }
  if (btp.mode & ~(kBtModeRaw | kBtModeTsm)) {
    return timing_rule(
        fmt::format("{} CANBTP dwMode = 0x{:X} has bits other than CAN_BTMODE_RAW and "
                    "CAN_BTMODE_TSM",
                    phase_name(phase), btp.mode));
  }
  return {};
}

// a / b rounded to the nearest whole number, halves up.
uint64_t round_div(uint128 a, uint128 b) {
  return static_cast<uint64_t>((2 * a + b) / (2 * b));
}

// |a - b| as an unsigned number.
uint128 distance(uint128 a, uint128 b) {
  return a > b ? a - b : b - a;
}

// One candidate of the search: prescaler, quanta per bit, raw TS1, and its two errors as
// fractions (num / den): the rate's in bit/s, the sample point's in parts of a bit.
struct Candidate {
  uint32_t prescaler = 0;
  uint32_t quanta = 0;
  uint32_t ts1 = 0;
  uint128 rate_num = 0, rate_den = 1;
  uint128 point_num = 0, point_den = 1;
};

// -1, 0, 1 as a / b is below, equal to, above c / d.
int compare(uint128 a, uint128 b, uint128 c, uint128 d) {
  const uint128 l = a * d;
  const uint128 r = c * b;
  return l < r ? -1 : l > r ? 1 : 0;
}

// Whether `c` goes before `best` by the rule of convert_btp() (btp.hpp).
bool better(const Candidate& c, const Candidate& best, uint64_t qbit) {
  if (int k = compare(c.rate_num, c.rate_den, best.rate_num, best.rate_den); k != 0) {
    return k < 0;
  }
  if (int k = compare(c.point_num, c.point_den, best.point_num, best.point_den); k != 0) {
    return k < 0;
  }
  const uint128 dc = distance(c.quanta, qbit);
  const uint128 db = distance(best.quanta, qbit);
  if (dc != db) {
    return dc < db;
  }
  return c.quanta > best.quanta;
}

std::string rate_text(const BitRate& r) {
  if (r.is_integral()) {
    return fmt::format("{}", r.num / r.den);
  }
  return fmt::format("{:.3f}", r.bps());
}

}  // namespace

Result<BtpConversion> convert_btp(const Btp& btp, const BtpRange& range, Phase phase) {
  if (auto ok = check_mode(btp, range, phase); !ok) {
    return tl::unexpected(ok.error());
  }
  const auto name = phase_name(phase);
  if (btp.mode & kBtModeRaw) {
    BtpConversion same{btp, btp, BitRate{}, true};
    const uint64_t per_bit = uint64_t{btp.bps} * (1u + btp.ts1 + btp.ts2);
    if (per_bit != 0) {
      BitTiming t;
      t.clock_hz = range.clock_hz;
      t.prescaler = btp.bps;
      t.tseg1 = btp.ts1;
      t.tseg2 = btp.ts2;
      same.rate = t.bit_rate();
    }
    return same;
  }
  // Bit/s form: ts1 counts the sync quantum, so Qbit = ts1 + ts2.
  if (btp.bps == 0 || btp.ts1 < 2 || btp.ts2 == 0) {
    return timing_rule(
        fmt::format("{} CANBTP {{dwBPS={}, wTS1={}, wTS2={}}}: the bit rate and wTS2 must "
                    "be non-zero and wTS1 must include the sync quantum (>= 2)",
                    name, btp.bps, btp.ts1, btp.ts2));
  }
  if (btp.sjw == 0 || btp.sjw > btp.ts2 || btp.sjw >= btp.ts1) {
    return timing_rule(fmt::format(
        "{} CANBTP {{wTS1={}, wTS2={}, wSJW={}}}: wSJW must be at least 1 and at most both "
        "phase segments (wTS2, and wTS1 without the sync quantum)",
        name, btp.ts1, btp.ts2, btp.sjw));
  }
  const uint64_t qbit = uint64_t{btp.ts1} + btp.ts2;
  const uint32_t q_min = 1u + range.min.ts1 + range.min.ts2;
  const uint32_t q_max = 1u + range.max.ts1 + range.max.ts2;
  std::optional<Candidate> best;
  for (uint32_t q = q_min; q <= q_max; ++q) {
    // Raw TS1 within the ranges, TS2 = q - 1 - TS1 within its own.
    const int64_t lo = std::max<int64_t>(range.min.ts1, int64_t{q} - 1 - range.max.ts2);
    const int64_t hi = std::min<int64_t>(range.max.ts1, int64_t{q} - 1 - range.min.ts2);
    if (lo > hi) {
      continue;
    }
    // The sample point's quantum: q * ts1 / Qbit, halves up (the later of two equally close).
    const int64_t at = static_cast<int64_t>(round_div(uint128{q} * btp.ts1, qbit));
    const auto ts1 = static_cast<uint32_t>(std::clamp<int64_t>(at - 1, lo, hi));
    // The prescalers either side of clock / (bps * q), within the range.
    const uint64_t per_bit = uint64_t{btp.bps} * q;
    const uint64_t below = range.clock_hz / per_bit;
    for (uint64_t p64 : {below, below + 1}) {
      const auto p = static_cast<uint32_t>(std::clamp<uint64_t>(p64, range.min.bps, range.max.bps));
      Candidate c;
      c.prescaler = p;
      c.quanta = q;
      c.ts1 = ts1;
      const uint128 clocks = uint128{p} * q;  // clock periods per bit
      c.rate_num = distance(range.clock_hz, uint128{btp.bps} * clocks);
      c.rate_den = clocks;
      c.point_num = distance(uint128{1u + ts1} * qbit, uint128{q} * btp.ts1);
      c.point_den = uint128{q} * qbit;
      if (!best || better(c, *best, qbit)) {
        best = c;
      }
    }
  }
  if (!best) {
    return model_error(ModelErrc::timing_not_realizable,
                       fmt::format("{} CANBTP: the controller has no timing", name));
  }
  BitTiming taken;
  taken.clock_hz = range.clock_hz;
  taken.prescaler = best->prescaler;
  taken.tseg1 = best->ts1;
  taken.tseg2 = best->quanta - 1 - best->ts1;
  const BitRate rate = taken.bit_rate();
  // Missed by more than kMaxRateErrorPpm: |clock - bps * clocks| / (bps * clocks).
  const uint128 clocks = uint128{best->prescaler} * best->quanta;
  if (distance(range.clock_hz, uint128{btp.bps} * clocks) * 1'000'000 >
      uint128{kMaxRateErrorPpm} * btp.bps * clocks) {
    return model_error(
        ModelErrc::timing_not_realizable,
        fmt::format("{} CANBTP {{dwBPS={}, wTS1={}, wTS2={}}}: the {} Hz controller clock gives "
                    "{} bit/s at best (prescaler {}, {} quanta), {:.3f} % off; more than {} % "
                    "is refused",
                    name, btp.bps, btp.ts1, btp.ts2, range.clock_hz, rate_text(rate),
                    best->prescaler, best->quanta, 100.0 * std::abs(rate.bps() - btp.bps) / btp.bps,
                    kMaxRateErrorPpm / 10000.0));
  }
  const uint32_t q = best->quanta;
  const uint32_t sjw_max = std::min<uint32_t>({taken.tseg1, taken.tseg2, uint32_t{range.max.sjw}});
  const uint32_t sjw =
      std::clamp<uint32_t>(static_cast<uint32_t>(round_div(uint128{btp.sjw} * q, qbit)),
                           std::max<uint32_t>(1, range.min.sjw), std::max<uint32_t>(1, sjw_max));
  const uint64_t tdo = round_div(uint128{btp.tdo} * q, qbit);
  if (tdo < range.min.tdo || tdo > range.max.tdo) {
    return model_error(
        ModelErrc::timing_out_of_range,
        fmt::format("{} CANBTP wTDO = {} (of Qbit {}) is {} of the {} quanta taken, outside {}..{}",
                    name, btp.tdo, qbit, tdo, q, range.min.tdo, range.max.tdo));
  }
  BtpConversion out;
  out.rate = rate;
  out.raw = Btp{btp.mode | kBtModeRaw,
                best->prescaler,
                static_cast<uint16_t>(taken.tseg1),
                static_cast<uint16_t>(taken.tseg2),
                static_cast<uint16_t>(sjw),
                static_cast<uint16_t>(tdo)};
  out.shown = Btp{btp.mode,
                  static_cast<uint32_t>(round_div(rate.num, rate.den)),
                  static_cast<uint16_t>(1 + taken.tseg1),
                  static_cast<uint16_t>(taken.tseg2),
                  static_cast<uint16_t>(sjw),
                  static_cast<uint16_t>(tdo)};
  out.exact = rate == BitRate{btp.bps, 1} && out.shown.ts1 == btp.ts1 && out.shown.ts2 == btp.ts2 &&
              out.shown.sjw == btp.sjw && out.shown.tdo == btp.tdo;
  return out;
}

Result<Btp> to_raw(const Btp& btp, const BtpRange& range, Phase phase) {
  auto c = convert_btp(btp, range, phase);
  if (!c) {
    return tl::unexpected(c.error());
  }
  return c->raw;
}

std::string describe_conversion(const Btp& btp, const BtpConversion& c, const BtpRange& range,
                                Phase phase) {
  const uint32_t quanta = 1u + c.raw.ts1 + c.raw.ts2;
  const uint32_t point = (2000u * (1u + c.raw.ts1) + quanta) / (2 * quanta);  // per mille
  std::string text = fmt::format(
      "{} CANBTP {{dwBPS={}, wTS1={}, wTS2={}, wSJW={}, wTDO={}}} taken as {} bit/s from the "
      "{} Hz clock: prescaler {}, {} quanta (TS1 {} with the sync quantum, TS2 {}), SJW {}",
      phase_name(phase), btp.bps, btp.ts1, btp.ts2, btp.sjw, btp.tdo, rate_text(c.rate),
      range.clock_hz, c.raw.bps, quanta, 1u + c.raw.ts1, c.raw.ts2, c.raw.sjw);
  if (phase == Phase::data) {
    text += fmt::format(", TDO {}", c.raw.tdo);
  }
  text += fmt::format(", sample point {}.{} %", point / 10, point % 10);
  return text;
}

Result<BitTiming> decode_btp(const Btp& btp, const BtpRange& range, Phase phase) {
  auto raw = to_raw(btp, range, phase);
  if (!raw) {
    return tl::unexpected(raw.error());
  }
  const auto name = phase_name(phase);
  struct Field {
    const char* label;
    uint32_t value, lo, hi;
  };
  const Field fields[] = {
      {"prescaler", raw->bps, range.min.bps, range.max.bps},
      {"wTS1 (raw)", raw->ts1, range.min.ts1, range.max.ts1},
      {"wTS2", raw->ts2, range.min.ts2, range.max.ts2},
      {"wSJW", raw->sjw, range.min.sjw, range.max.sjw},
      {"wTDO", raw->tdo, range.min.tdo, range.max.tdo},
  };
  for (const Field& f : fields) {
    if (f.value < f.lo || f.value > f.hi) {
      return timing_out_of_range(fmt::format("{} CANBTP {}", name, f.label), f.value, f.lo, f.hi);
    }
  }
  if (raw->sjw > raw->ts2 || raw->sjw > raw->ts1) {
    return timing_rule(
        fmt::format("{} CANBTP: wSJW = {} exceeds a phase segment (wTS1 raw = {}, "
                    "wTS2 = {}); the rule is SJW <= both",
                    name, raw->sjw, raw->ts1, raw->ts2));
  }
  BitTiming t;
  t.clock_hz = range.clock_hz;
  t.prescaler = raw->bps;
  t.tseg1 = raw->ts1;
  t.tseg2 = raw->ts2;
  t.sjw = raw->sjw;
  t.samples = (raw->mode & kBtModeTsm) ? 3 : 1;
  return t;
}

std::optional<BitTiming> timing_for(uint32_t bitrate, uint32_t sample_point_permille,
                                    const BtpRange& range, Phase phase) {
  std::optional<BitTiming> best;
  uint32_t best_error = UINT32_MAX;
  for (uint32_t prescaler = range.min.bps; prescaler <= range.max.bps; ++prescaler) {
    const uint64_t per_bit = uint64_t{bitrate} * prescaler;
    if (per_bit == 0 || range.clock_hz % per_bit != 0) {
      continue;
    }
    const uint64_t quanta = range.clock_hz / per_bit;
    if (quanta < 4 || quanta > 1u + range.max.ts1 + range.max.ts2) {
      continue;
    }
    const auto ts2 = static_cast<uint16_t>(
        std::max<uint64_t>(range.min.ts2, quanta - (quanta * sample_point_permille + 500) / 1000));
    const auto ts1 = static_cast<uint16_t>(quanta - 1 - ts2);
    auto t = decode_btp(
        Btp{kBtModeRaw, prescaler, ts1, ts2, static_cast<uint16_t>(std::min<uint16_t>(ts2, 4)), 0},
        range, phase);
    if (!t) {
      continue;
    }
    const uint32_t point = t->sample_point_permille();
    const uint32_t error = point > sample_point_permille ? point - sample_point_permille
                                                         : sample_point_permille - point;
    if (error < best_error) {
      best_error = error;
      best = *t;
    }
  }
  return best;
}

}  // namespace canemu::model::ixxat
