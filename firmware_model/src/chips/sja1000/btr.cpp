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

}  // namespace canemu::model::sja1000
