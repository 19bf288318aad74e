#include "canemu/firmware_model/adapters/sorcus/slcan_eeprom.hpp"

#include <fmt/format.h>

#include "canemu/firmware_model/adapters/sorcus/bit_params.hpp"
#include "sorcus/sl64_types.h"

namespace canemu::model::sorcus {

EepromWords slcan_eeprom_defaults() {
  EepromWords w{};
  w[0] = 0x534C;  // "SL"
  w[1] = 0x0040;  // type 40h = 64
  w[2] = 0x0002;  // revision B
  w[3] = 0x0001;  // SORCUS
  w[4] = 0x0005;  // RTS status
  w[5] = 0x0021;  // DTR status
  w[SL064_EEPROM_CLOCK] = 0x0010;
  w[SL064_EEPROM_MODE] = 0x0007;
  w[SL064_EEPROM_TQ] = 0x09C4;  // 2500 ns
  w[SL064_EEPROM_TSEG1] = 0x0010;
  w[SL064_EEPROM_TSEG2] = 0x0003;
  w[SL064_EEPROM_SJW] = 0x0002;
  w[SL064_EEPROM_SAMPLES] = 0x0001;
  return w;
}

tl::expected<SlcanSettings, EepromProblem> slcan_settings(const EepromWords& w) {
  auto range = [](std::string why) {
    return tl::unexpected(EepromProblem{SL064_DIAG_EEPROM_RANGE, std::move(why)});
  };
  // Decision: word 12 is read as BCD MHz, and 0010h (10 MHz) is the only value SL64TASK knows.
  if (w[SL064_EEPROM_CLOCK] != 0x0010) {
    return tl::unexpected(EepromProblem{
        SL064_DIAG_EEPROM_CLOCK,
        fmt::format("EEPROM word 12 (clock) is {:04X}h, but the SL-CANi's is 0010h (10 MHz)",
                    w[SL064_EEPROM_CLOCK])});
  }
  if ((w[SL064_EEPROM_MODE] & 0x7) != 0x7) {
    return range(fmt::format("EEPROM word 13 (mode) is {:04X}h, but its bits 0..2 are always 1",
                             w[SL064_EEPROM_MODE]));
  }
  if (w[SL064_EEPROM_ID_FORMAT] > 1) {
    return range(
        fmt::format("EEPROM word 14 (identifier format) is {:04X}h, but only 0 (11 bit) "
                    "or 1 (29 bit) are defined",
                    w[SL064_EEPROM_ID_FORMAT]));
  }
  const SorcusTiming t{w[SL064_EEPROM_TQ], w[SL064_EEPROM_TSEG1], w[SL064_EEPROM_TSEG2],
                       w[SL064_EEPROM_SJW], w[SL064_EEPROM_SAMPLES]};
  auto timing = decode_sorcus(kSlCani, t);
  if (!timing) {
    return range("EEPROM words 15..19 (bit timing): " + timing.error().message);
  }
  SlcanSettings s;
  s.timing = *timing;
  s.extended = w[SL064_EEPROM_ID_FORMAT] == 1;
  s.termination = (w[SL064_EEPROM_MODE] & SL064_EEPROM_TERMINATION) != 0;
  return s;
}

}  // namespace canemu::model::sorcus
