// SJA1000 bit timing registers BTR0/BTR1 -> BitTiming (the IXXAT devices run the chip from a
// 16 MHz oscillator). Each decoder names the rule a value breaks.
#pragma once

#include <cstdint>
#include <optional>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/sim/model_error.hpp"

namespace canemu::model::sja1000 {

inline constexpr uint32_t kIxxatOscillatorHz = 16'000'000;

// SJA1000 datasheet 6.5.1/6.5.2: BTR0 = SJW-1 [7:6] | BRP-1 [5:0]; BTR1 = SAM [7] |
// TSEG2-1 [6:4] | TSEG1-1 [3:0]; tq = 2 * BRP / f_osc. Rules beyond the register widths:
// 8..25 quanta per bit (ISO 11898-1), TSEG2 >= 2 (information processing time), SJW <= TSEG2.
Result<BitTiming> decode_btr(uint8_t btr0, uint8_t btr1,
                             uint32_t oscillator_hz = kIxxatOscillatorHz);

// What the chip does with any register values, valid or not: the chip model runs with it, and
// the bus decides whether anybody can decode such a node.
BitTiming timing_from_btr(uint8_t btr0, uint8_t btr1, uint32_t oscillator_hz = kIxxatOscillatorHz);

struct Btr {
  uint8_t btr0 = 0;
  uint8_t btr1 = 0;
  friend bool operator==(const Btr&, const Btr&) = default;
};

// The valid register values that give exactly `bitrate`, with the sample point closest to
// `sample_point_permille` (ties: the smallest prescaler, then the shortest TSEG2, then the
// shortest TSEG1); nothing if no values give that rate exactly. SJW is 1.
std::optional<Btr> btr_for(uint32_t bitrate, uint32_t sample_point_permille,
                           uint32_t oscillator_hz = kIxxatOscillatorHz);

}  // namespace canemu::model::sja1000
