// The SL-CANi's serial EEPROM: 64 words with the manual's factory contents (digest §3.5), the
// writable ranges («Von den ersten 32 EEPROM-Worten dürfen nur die Worte 13 bis 19 verändert
// werden. Die Worte 32 bis 63 stehen zur freien Verfügung.»), and what SL64TASK reads from it
// at sl064_config_module: the clock (word 12), termination (word 13 bit 3), the identifier
// format (word 14 bit 0) and the bit timing (words 15..19, decoded at 10 MHz).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <tl/expected.hpp>

#include "canemu/firmware_model/bus/bit_timing.hpp"

namespace canemu::model::sorcus {

inline constexpr unsigned kEepromWords = 64;
using EepromWords = std::array<uint16_t, kEepromWords>;

// Word 0 "SL", type 40h, revision B, SORCUS, RTS 5, DTR 21h, clock 10 MHz (0010h), mode 7
// (no termination), 11-bit identifiers, 20 kbit/s (2500 ns, 16, 3, 2, 1).
EepromWords slcan_eeprom_defaults();

// Words a program may change: 13..19 and 32..63.
constexpr bool slcan_eeprom_writable(unsigned word) {
  return (word >= 13 && word <= 19) || (word >= 32 && word < kEepromWords);
}

// What SL64TASK takes from the EEPROM at sl064_config_module.
struct SlcanSettings {
  BitTiming timing;
  bool extended = false;
  bool termination = false;
  friend bool operator==(const SlcanSettings&, const SlcanSettings&) = default;
};

// The check at sl064_config_module: word 12 other than 0010h gives diagnosis 31h; words 13..19
// out of their ranges give 24h (word 13's bits 0..2 must be 1, word 14 is 0 or 1, 15..19 as
// SL064_EEPROM_* says and as the bit-timing rules require). `why` names the word.
struct EepromProblem {
  uint16_t diagnosis = 0;
  std::string why;
};
tl::expected<SlcanSettings, EepromProblem> slcan_settings(const EepromWords& words);

}  // namespace canemu::model::sorcus
