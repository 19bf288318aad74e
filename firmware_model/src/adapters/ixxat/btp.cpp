#include "canemu/firmware_model/adapters/ixxat/btp.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "bus/timing_errors.hpp"

namespace canemu::model::ixxat {

namespace {

std::string_view phase_name(Phase phase) {
  return phase == Phase::nominal ? "nominal (sSdr)" : "data (sFdr)";
}

}  // namespace

Result<Btp> to_raw(const Btp& btp, const BtpRange& range, Phase phase) {
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
  if (btp.mode & kBtModeRaw) {
    return btp;
  }
  // Bit/s form: ts1 counts the sync quantum, so quanta per bit = ts1 + ts2.
  const uint64_t quanta = uint64_t{btp.ts1} + btp.ts2;
  if (btp.bps == 0 || btp.ts1 < 2 || btp.ts2 == 0) {
    return timing_rule(
        fmt::format("{} CANBTP {{dwBPS={}, wTS1={}, wTS2={}}}: the bit rate and wTS2 must "
                    "be non-zero and wTS1 must include the sync quantum (>= 2)",
                    phase_name(phase), btp.bps, btp.ts1, btp.ts2));
  }
  const uint64_t per_bit = uint64_t{btp.bps} * quanta;
  if (range.clock_hz % per_bit != 0) {
    return model_error(
        ModelErrc::timing_not_realizable,
        fmt::format("{} CANBTP {{dwBPS={}, wTS1={}, wTS2={}}}: the {} Hz controller clock is not a "
                    "whole multiple of {} bit/s x {} quanta, so no prescaler gives this timing",
                    phase_name(phase), btp.bps, btp.ts1, btp.ts2, range.clock_hz, btp.bps, quanta));
  }
  Btp raw = btp;
  raw.mode = btp.mode | kBtModeRaw;
  raw.bps = static_cast<uint32_t>(range.clock_hz / per_bit);
  raw.ts1 = static_cast<uint16_t>(btp.ts1 - 1);
  return raw;
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
