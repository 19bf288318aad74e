#include "canemu/firmware_model/chips/sja1000/btr.hpp"

#include <fmt/format.h>

#include "bus/timing_errors.hpp"

namespace canemu::model::sja1000 {

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
    return timing_rule(fmt::format("{}: 1 + TSEG1 + TSEG2 = {} quanta, but a bit needs at least 8",
                                   where, t.quanta_per_bit()));
  }
  if (t.tseg2 < 2) {
    return timing_rule(
        fmt::format("{}: TSEG2 = {} quantum, but it must cover the 2-quantum "
                    "information processing time",
                    where, t.tseg2));
  }
  if (t.sjw > t.tseg2) {
    return timing_rule(
        fmt::format("{}: SJW = {} exceeds TSEG2 = {} (rule SJW <= TSEG2)", where, t.sjw, t.tseg2));
  }
  return t;
}

std::optional<Btr> btr_for(uint32_t bitrate, uint32_t sample_point_permille,
                           uint32_t oscillator_hz) {
  std::optional<Btr> best;
  uint32_t best_error = UINT32_MAX;
  if (bitrate == 0 || oscillator_hz == 0) {
    return best;
  }
  // A bit lasts 2 (BRP + 1) (TSEG1 + TSEG2 + 3) oscillator periods: only a prescaler that
  // divides the oscillator into a whole number of quanta per bit can give the rate, and then
  // each TSEG2 leaves one TSEG1. Same candidates, in the same order, as trying all 7,168 values.
  for (uint8_t brp = 0; brp < 64; ++brp) {
    const uint64_t per_quantum = uint64_t{bitrate} * 2u * (brp + 1u);
    if (oscillator_hz % per_quantum != 0) {
      continue;
    }
    const uint64_t quanta = oscillator_hz / per_quantum;
    for (uint8_t t2 = 1; t2 < 8; ++t2) {
      if (quanta < t2 + 3u || quanta - t2 - 3u > 15u) {
        continue;
      }
      const auto t1 = static_cast<uint8_t>(quanta - t2 - 3u);
      const Btr btr{brp, static_cast<uint8_t>((t2 << 4) | t1)};
      // The rules only for the values that give the rate (their error texts cost a formatting).
      auto t = decode_btr(btr.btr0, btr.btr1, oscillator_hz);
      if (!t) {
        continue;
      }
      const uint32_t point = t->sample_point_permille();
      const uint32_t error = point > sample_point_permille ? point - sample_point_permille
                                                           : sample_point_permille - point;
      if (error < best_error) {
        best_error = error;
        best = btr;
      }
    }
  }
  return best;
}

}  // namespace canemu::model::sja1000
