// The bit timing a SORCUS driver takes (XCAN_BITPARAMS, SL-CANi EEPROM words 15..19): tq in ns
// plus tseg1, tseg2, sjw and samples per bit, on the device's 82527 clock (X-CAN-2i: 8 MHz /
// 125 ns, SL-CANi: 10 MHz / 100 ns) -> BitTiming.
#pragma once

#include <cstdint>
#include <string_view>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/sim/model_error.hpp"

namespace canemu::model::sorcus {

// A SORCUS device's 82527 clock and the tq range its driver accepts.
struct SorcusDevice {
  std::string_view name;
  uint32_t clock_hz;
  uint32_t tq_min_ns;
  uint32_t tq_max_ns;
};

inline constexpr SorcusDevice kXCan2i{"X-CAN-2i", 8'000'000, 125, 8000};
inline constexpr SorcusDevice kSlCani{"SL-CANi", 10'000'000, 100, 6400};

// XCAN_BITPARAMS / SL-CANi EEPROM words 15..19.
struct SorcusTiming {
  uint32_t tq_ns = 0;
  uint32_t tseg1 = 0;    // t_SEG1 / t_Q, 3..16 (propagation included, as on the 82527)
  uint32_t tseg2 = 0;    // t_SEG2 / t_Q, 2..8
  uint32_t sjw = 0;      // t_SJW / t_Q, 1..4
  uint32_t samples = 1;  // 1 or 3
};

// Rules from the SORCUS manuals: tq a multiple of the clock period within the device's range,
// the field ranges above, tseg1 + tseg2 >= 7, tseg2 >= sjw. The t_PROP rules need a bus length
// and are not enforced (docs/wire-model.md).
Result<BitTiming> decode_sorcus(const SorcusDevice& device, const SorcusTiming& timing);

}  // namespace canemu::model::sorcus
