// VCI CANBTP (CANINITLINE2), in bit/s form and raw (prescaler) form, for the nominal and the data
// phase, against the controller's capability ranges (CANCAPABILITIES2) -> BitTiming.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

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

// The most a bit/s CANBTP's rate may be missed by: 5000 ppm (0.5 %) of the rate asked for.
inline constexpr uint32_t kMaxRateErrorPpm = 5000;

// What a bit/s CANBTP is converted to: the nearest timing the controller can run (the rule is
// in docs/vci.md, "Bit timing in bit/s form"). In the bit/s form wTS1 (sync + prop + phase 1),
// wTS2, wSJW and wTDO are weights of one bit, Qbit = wTS1 + wTS2 of them: 8/2 and 80/20 both
// ask for the sample point at 80 %. Among the prescalers and quanta per bit within `range`,
// the conversion takes, in this order of precedence,
//   1. the rate closest to dwBPS,
//   2. then the sample point closest to wTS1 / Qbit (within one number of quanta, the later of
//      two sample points equally close),
//   3. then the number of quanta closest to Qbit (a request the clock makes exactly is taken
//      as it is),
//   4. then the larger number of quanta (the smaller prescaler).
// wSJW and wTDO keep their share of the bit: round(w * quanta / Qbit), halves up; SJW at least
// 1 and at most both phase segments and the range's maximum. Refused: a rate missed by more
// than kMaxRateErrorPpm, a TDO outside the range, wSJW above wTS2 or not below wTS1.
struct BtpConversion {
  Btp raw;             // the raw form the controller is programmed with (CAN_BTMODE_RAW)
  Btp shown;           // the same timing in bit/s form (the line status): dwBPS the rate rounded
                       // to the nearest bit/s, wTS1 = 1 + raw TS1, wTS2, wSJW, wTDO in quanta
  BitRate rate;        // the exact rate taken
  bool exact = false;  // the request's own rate, quanta, SJW and TDO: nothing approximated
};
Result<BtpConversion> convert_btp(const Btp& btp, const BtpRange& range, Phase phase);

// Decodes a CANBTP. The bit/s form is converted by convert_btp(); the raw form must lie within
// `range`, with sjw <= ts2 and sjw <= ts1.
Result<BitTiming> decode_btp(const Btp& btp, const BtpRange& range, Phase phase);

// The raw form decode_btp() converts a bit/s CANBTP to; raw values pass through unchanged.
Result<Btp> to_raw(const Btp& btp, const BtpRange& range, Phase phase);

// One line for a log: the bit/s CANBTP `btp` and what it was converted to.
std::string describe_conversion(const Btp& btp, const BtpConversion& c, const BtpRange& range,
                                Phase phase);

// The raw timing of a controller with `range` for `bitrate` in one phase, with the sample point
// closest to `sample_point_permille` (SJW up to 4); nothing if the clock cannot make the rate
// exactly within the ranges.
std::optional<BitTiming> timing_for(uint32_t bitrate, uint32_t sample_point_permille,
                                    const BtpRange& range, Phase phase);

}  // namespace canemu::model::ixxat
