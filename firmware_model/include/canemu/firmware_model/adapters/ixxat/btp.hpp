// VCI CANBTP (CANINITLINE2), in bit/s form and raw (prescaler) form, for the nominal and the data
// phase, against the controller's capability ranges (CANCAPABILITIES2) -> BitTiming.
#pragma once

#include <cstdint>
#include <optional>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/sim/model_error.hpp"

namespace canemu::model::ixxat {

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

// The raw timing of a controller with `range` for `bitrate` in one phase, with the sample point
// closest to `sample_point_permille` (SJW up to 4); nothing if the clock cannot make the rate
// exactly within the ranges.
std::optional<BitTiming> timing_for(uint32_t bitrate, uint32_t sample_point_permille,
                                    const BtpRange& range, Phase phase);

}  // namespace canemu::model::ixxat
