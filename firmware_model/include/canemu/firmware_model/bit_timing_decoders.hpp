// Decoders from each emulated device's bit-timing registers or API values to a BitTiming.
//
// Each decoder applies the ranges and rules of its device and names the rule a value breaks.
//   - SJA1000 BTR0/BTR1 (IXXAT devices, 16 MHz oscillator).
//   - Intel 82527 as the SORCUS drivers expose it: tq in ns plus tseg1, tseg2, sjw and samples per
//     bit, with the device's clock (X-CAN-2i: 8 MHz / 125 ns, SL-CANi: 10 MHz / 100 ns).
//   - VCI CANBTP (CANINITLINE2), in bit/s form and raw (prescaler) form, for the nominal and the
//     data phase, against the controller's capability ranges (CANCAPABILITIES2).
#pragma once

#include <cstdint>
#include <string_view>

#include "canemu/firmware_model/bit_timing.hpp"
#include "canemu/firmware_model/model_error.hpp"

namespace canemu::model {

namespace sja1000 {

inline constexpr uint32_t kIxxatOscillatorHz = 16'000'000;

// SJA1000 datasheet 6.5.1/6.5.2: BTR0 = SJW-1 [7:6] | BRP-1 [5:0]; BTR1 = SAM [7] |
// TSEG2-1 [6:4] | TSEG1-1 [3:0]; tq = 2 * BRP / f_osc. Rules beyond the register widths:
// 8..25 quanta per bit (ISO 11898-1), TSEG2 >= 2 (information processing time), SJW <= TSEG2.
Result<BitTiming> decode_btr(uint8_t btr0, uint8_t btr1,
                             uint32_t oscillator_hz = kIxxatOscillatorHz);

// What the chip does with any register values, valid or not: the chip model runs with it, and
// the bus decides whether anybody can decode such a node.
BitTiming timing_from_btr(uint8_t btr0, uint8_t btr1, uint32_t oscillator_hz = kIxxatOscillatorHz);

}  // namespace sja1000

namespace i82527 {

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

}  // namespace i82527

namespace vci {

inline constexpr uint32_t kBtModeRaw = 0x00000001;  // CAN_BTMODE_RAW
inline constexpr uint32_t kBtModeTsm = 0x00000002;  // CAN_BTMODE_TSM (triple sampling)

// The numbers of a CANBTP.
struct Btp {
  uint32_t mode = 0;
  uint32_t bps = 0;  // bit/s, or the prescaler in raw mode
  uint16_t ts1 = 0;  // bit/s form: sync + prop + phase 1; raw form: prop + phase 1
  uint16_t ts2 = 0;
  uint16_t sjw = 0;
  uint16_t tdo = 0;
};

// A controller's CANCAPABILITIES2 view of one phase: clock and raw ranges.
struct BtpRange {
  uint32_t clock_hz = 0;
  Btp min;
  Btp max;
};

enum class Phase { nominal, data };

// Ranges of the emulated IXXAT CAN FD controller (80 MHz). Decision recorded in
// docs/wire-model.md; the VCI device model reports them in CANCAPABILITIES2.
inline constexpr BtpRange kFdNominalRange{
    80'000'000, {kBtModeRaw, 1, 1, 2, 1, 0}, {kBtModeRaw, 1024, 256, 128, 128, 0}};
inline constexpr BtpRange kFdDataRange{
    80'000'000, {kBtModeRaw, 1, 1, 1, 1, 0}, {kBtModeRaw, 32, 32, 16, 16, 255}};

// Decodes a CANBTP. The bit/s form is converted to the raw form the controller would be
// programmed with (prescaler = clock / (bps * (ts1 + ts2)), which must be a whole number), and
// both forms must then lie within `range`, with sjw <= ts2 and sjw <= ts1.
Result<BitTiming> decode_btp(const Btp& btp, const BtpRange& range, Phase phase);

// The raw form decode_btp() converts a bit/s CANBTP to; raw values pass through unchanged.
Result<Btp> to_raw(const Btp& btp, const BtpRange& range, Phase phase);

}  // namespace vci

}  // namespace canemu::model
