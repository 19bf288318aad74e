// Bit timing of a CAN controller as a value: the quantum clock, the prescaler and the segments.
//
// One bit is 1 (sync) + tseg1 (propagation + phase 1) + tseg2 (phase 2) time quanta; one time
// quantum is `prescaler` periods of `clock_hz`. The bit rate is kept as an exact fraction, so
// rates like 666 2/3 kbit/s or the 131.58 kbit/s of a mis-tabled SL-CANi row stay exact.
// Decoders for each device's register form live beside the device (chips/sja1000/btr.hpp,
// adapters/ixxat/btp.hpp, adapters/sorcus/bit_params.hpp); they validate and
// return a BitTiming. Durations are computed exactly and rounded once, to the nearest ns.
#pragma once

#include <cstdint>

#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model {

__extension__ typedef unsigned __int128 uint128;  // gcc's 128-bit integer, for exact products

// An exact rate in bit/s: num / den.
struct BitRate {
  uint64_t num = 0;
  uint64_t den = 1;

  constexpr double bps() const { return static_cast<double>(num) / static_cast<double>(den); }
  constexpr bool is_integral() const { return den != 0 && num % den == 0; }
  friend constexpr bool operator==(const BitRate& a, const BitRate& b) {
    return static_cast<uint128>(a.num) * b.den == static_cast<uint128>(b.num) * a.den;
  }
};

struct BitTiming {
  uint64_t clock_hz = 0;   // clock the prescaler divides (the controller's oscillator)
  uint32_t prescaler = 1;  // clock periods per time quantum
  uint32_t tseg1 = 0;      // propagation + phase segment 1, in quanta
  uint32_t tseg2 = 0;      // phase segment 2, in quanta
  uint32_t sjw = 1;        // resynchronisation jump width, in quanta
  uint8_t samples = 1;     // samples per bit: 1, or 3 (triple sampling)

  constexpr uint32_t quanta_per_bit() const { return 1 + tseg1 + tseg2; }
  BitRate bit_rate() const;  // reduced fraction
  // Sample point in per mille of the bit: (1 + tseg1) / quanta_per_bit.
  constexpr uint32_t sample_point_permille() const {
    return (1000 * (1 + tseg1) + quanta_per_bit() / 2) / quanta_per_bit();
  }
  // Length of one time quantum, rounded to the nearest picosecond (for display).
  uint64_t quantum_ps() const;
  // Exact duration of `bits` bits, rounded once to the nearest nanosecond.
  SimDuration bits_duration(uint64_t bits) const;

  // The largest oscillator tolerance df this timing survives (ISO 11898-1 conditions
  // df <= sjw / (20 * bit) and df <= min(ps1, ps2) / (2 * (13 * bit - ps2)), in quanta, with
  // tseg1 standing for phase segment 1). Two nodes whose rates differ by more than 2 * df of
  // the receiver cannot decode each other.
  double oscillator_tolerance() const;

  friend constexpr bool operator==(const BitTiming&, const BitTiming&) = default;
};

// Exact duration of `qa` quanta of `a` plus `qb` quanta of `b`, rounded once to the nearest ns.
// This is how a CAN FD frame with bit-rate switch is timed: part of it at the nominal quantum,
// part at the data quantum.
SimDuration quanta_duration(const BitTiming& a, uint64_t qa, const BitTiming& b, uint64_t qb);

// A node's timing as seen from the bus: nominal phase, optional data phase (CAN FD with bit-rate
// switch) and its oscillator's deviation from nominal in parts per million.
struct NodeTiming {
  BitTiming nominal;
  BitTiming data;  // meaningful only when has_data_phase
  bool has_data_phase = false;
  int32_t oscillator_ppm = 0;
};

struct Compatibility {
  bool ok = false;
  bool data_phase = false;  // which phase decided: false = nominal, true = data
  double mismatch = 0;      // relative difference of the two nodes' actual rates
  double tolerance = 0;     // 2 * df of the receiver for that phase
};

// The numbers compatibility depends on, computed once per timing: actual rates (with the
// oscillator offset) and tolerances of both phases.
struct TimingProfile {
  double rate = 0;       // bit/s, nominal phase
  double tolerance = 0;  // 2 * df, nominal phase
  double data_rate = 0;
  double data_tolerance = 0;
  bool has_data_phase = false;
};
TimingProfile timing_profile(const NodeTiming& t);
Compatibility check_compatibility(const TimingProfile& tx, const TimingProfile& rx,
                                  bool bit_rate_switch);

// Whether `rx` decodes what `tx` sends. The nominal rates must agree within the receiver's
// tolerance; when `bit_rate_switch` is set, the data rates as well (and the receiver must have
// a data phase). Sample points may differ: real nodes interoperate with different sample points.
Compatibility check_compatibility(const NodeTiming& tx, const NodeTiming& rx, bool bit_rate_switch);

}  // namespace canemu::model
