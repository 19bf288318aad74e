#include "canemu/firmware_model/bit_timing_decoders.hpp"

#include <fmt/format.h>

namespace canemu::model {

namespace {

tl::unexpected<ModelError> out_of_range(std::string_view what, uint64_t value, uint64_t lo,
                                        uint64_t hi) {
  return model_error(ModelErrc::timing_out_of_range,
                     fmt::format("{} = {} is outside {}..{}", what, value, lo, hi));
}

tl::unexpected<ModelError> rule(std::string text) {
  return model_error(ModelErrc::timing_rule_violated, std::move(text));
}

}  // namespace

namespace sja1000 {

BitTiming timing_from_btr(uint8_t btr0, uint8_t btr1, uint32_t oscillator_hz) {
  BitTiming t;
  t.clock_hz = oscillator_hz;
  t.prescaler = 2u * ((btr0 & 0x3Fu) + 1u);
  t.sjw = ((btr0 >> 6) & 0x03u) + 1u;
  t.tseg1 = (btr1 & 0x0Fu) + 1u;
  t.tseg2 = ((btr1 >> 4) & 0x07u) + 1u;
  t.samples = (btr1 & 0x80u) ? 3 : 1;
  return t;
}

Result<BitTiming> decode_btr(uint8_t btr0, uint8_t btr1, uint32_t oscillator_hz) {
  const BitTiming t = timing_from_btr(btr0, btr1, oscillator_hz);
  const auto where = fmt::format("BTR0=0x{:02X} BTR1=0x{:02X}", btr0, btr1);
  if (t.quanta_per_bit() < 8) {
    return rule(fmt::format("{}: 1 + TSEG1 + TSEG2 = {} quanta, but a bit needs at least 8", where,
                            t.quanta_per_bit()));
  }
  if (t.tseg2 < 2) {
    return rule(
        fmt::format("{}: TSEG2 = {} quantum, but it must cover the 2-quantum "
                    "information processing time",
                    where, t.tseg2));
  }
  if (t.sjw > t.tseg2) {
    return rule(
        fmt::format("{}: SJW = {} exceeds TSEG2 = {} (rule SJW <= TSEG2)", where, t.sjw, t.tseg2));
  }
  return t;
}

}  // namespace sja1000

namespace i82527 {

Result<BitTiming> decode_sorcus(const SorcusDevice& device, const SorcusTiming& timing) {
  const uint32_t period_ns = 1'000'000'000u / device.clock_hz;
  if (timing.tq_ns < device.tq_min_ns || timing.tq_ns > device.tq_max_ns) {
    return out_of_range(fmt::format("{} Tq (ns)", device.name), timing.tq_ns, device.tq_min_ns,
                        device.tq_max_ns);
  }
  if (timing.tq_ns % period_ns != 0) {
    return rule(
        fmt::format("{}: Tq = {} ns is not a multiple of the {} ns controller clock "
                    "period",
                    device.name, timing.tq_ns, period_ns));
  }
  if (timing.tseg1 < 3 || timing.tseg1 > 16) {
    return out_of_range(fmt::format("{} Tseg1", device.name), timing.tseg1, 3, 16);
  }
  if (timing.tseg2 < 2 || timing.tseg2 > 8) {
    return out_of_range(fmt::format("{} Tseg2", device.name), timing.tseg2, 2, 8);
  }
  if (timing.sjw < 1 || timing.sjw > 4) {
    return out_of_range(fmt::format("{} Tsjw", device.name), timing.sjw, 1, 4);
  }
  if (timing.samples != 1 && timing.samples != 3) {
    return rule(fmt::format("{}: samples per bit = {}, but only 1 or 3 are possible", device.name,
                            timing.samples));
  }
  if (timing.tseg1 + timing.tseg2 < 7) {
    return rule(fmt::format("{}: Tseg1 + Tseg2 = {} + {} = {}, but the rule is Tseg1 + Tseg2 >= 7",
                            device.name, timing.tseg1, timing.tseg2, timing.tseg1 + timing.tseg2));
  }
  if (timing.tseg2 < timing.sjw) {
    return rule(fmt::format("{}: Tseg2 = {} is less than Tsjw = {} (rule Tseg2 >= Tsjw)",
                            device.name, timing.tseg2, timing.sjw));
  }
  BitTiming t;
  t.clock_hz = device.clock_hz;
  t.prescaler = timing.tq_ns / period_ns;
  t.tseg1 = timing.tseg1;
  t.tseg2 = timing.tseg2;
  t.sjw = timing.sjw;
  t.samples = static_cast<uint8_t>(timing.samples);
  return t;
}

}  // namespace i82527

namespace vci {

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
    return rule(
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
    return rule(
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
      return out_of_range(fmt::format("{} CANBTP {}", name, f.label), f.value, f.lo, f.hi);
    }
  }
  if (raw->sjw > raw->ts2 || raw->sjw > raw->ts1) {
    return rule(
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

}  // namespace vci

}  // namespace canemu::model
