#include "canemu/firmware_model/bus/bit_timing.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace canemu::model {

namespace {

using u128 = uint128;

constexpr uint64_t kNsPerSecond = 1'000'000'000;
constexpr uint64_t kPsPerSecond = 1'000'000'000'000;

// Relative tolerance of the data phase of a CAN FD node (ISO 11898-1:2015, 11.3.2.2 condition
// for the switch back to the nominal rate), written in time units so that nominal and data
// quanta of different length are consistent: min(ps1_d, ps2_d) * tq_d over
// 2 * ((6 * data bit - ps2_d * tq_d) + 7 * nominal bit).
double data_phase_tolerance(const BitTiming& nominal, const BitTiming& data) {
  const double tq_d = static_cast<double>(data.prescaler) / static_cast<double>(data.clock_hz);
  const double tq_n =
      static_cast<double>(nominal.prescaler) / static_cast<double>(nominal.clock_hz);
  const double dbt = data.quanta_per_bit() * tq_d;
  const double nbt = nominal.quanta_per_bit() * tq_n;
  const double df_sjw = data.sjw / (20.0 * data.quanta_per_bit());
  const double df_switch = std::min(data.tseg1, data.tseg2) * tq_d /
                           (2.0 * ((6.0 * dbt - data.tseg2 * tq_d) + 7.0 * nbt));
  return std::min(df_sjw, df_switch);
}

double effective_rate(const BitTiming& t, int32_t ppm) {
  return t.bit_rate().bps() * (1.0 + ppm * 1e-6);
}

}  // namespace

BitRate BitTiming::bit_rate() const {
  const uint64_t den = static_cast<uint64_t>(prescaler) * quanta_per_bit();
  const uint64_t g = std::gcd(clock_hz, den);
  return g == 0 ? BitRate{0, 1} : BitRate{clock_hz / g, den / g};
}

uint64_t BitTiming::quantum_ps() const {
  if (clock_hz == 0) {
    return 0;
  }
  return static_cast<uint64_t>((u128{prescaler} * kPsPerSecond + clock_hz / 2) / clock_hz);
}

SimDuration BitTiming::bits_duration(uint64_t bits) const {
  return quanta_duration(*this, bits * quanta_per_bit(), *this, 0);
}

double BitTiming::oscillator_tolerance() const {
  const double nq = quanta_per_bit();
  const double df_sjw = sjw / (20.0 * nq);
  const double df_phase = std::min(tseg1, tseg2) / (2.0 * (13.0 * nq - tseg2));
  return std::min(df_sjw, df_phase);
}

SimDuration quanta_duration(const BitTiming& a, uint64_t qa, const BitTiming& b, uint64_t qb) {
  if (a.clock_hz == 0 || b.clock_hz == 0) {
    return SimDuration(0);
  }
  if (qb == 0 && qa < (uint64_t{1} << 32) && qa * a.prescaler < (uint64_t{1} << 32)) {
    // One timing and a product that fits 64 bits (frames, intermissions): no 128-bit division.
    const uint64_t quanta_ps = qa * a.prescaler;  // < 2^32, times 10^9 < 2^62
    return SimDuration(
        static_cast<int64_t>((quanta_ps * kNsPerSecond + a.clock_hz / 2) / a.clock_hz));
  }
  // qa * pa / fa + qb * pb / fb seconds = (qa * pa * fb + qb * pb * fa) / (fa * fb).
  const u128 num = u128{qa} * a.prescaler * b.clock_hz + u128{qb} * b.prescaler * a.clock_hz;
  const u128 den = u128{a.clock_hz} * b.clock_hz;
  return SimDuration(static_cast<int64_t>((num * kNsPerSecond + den / 2) / den));
}

TimingProfile timing_profile(const NodeTiming& t) {
  TimingProfile p;
  p.rate = effective_rate(t.nominal, t.oscillator_ppm);
  p.tolerance = 2.0 * t.nominal.oscillator_tolerance();
  p.has_data_phase = t.has_data_phase;
  if (t.has_data_phase) {
    p.data_rate = effective_rate(t.data, t.oscillator_ppm);
    p.data_tolerance = 2.0 * data_phase_tolerance(t.nominal, t.data);
  }
  return p;
}

Compatibility check_compatibility(const TimingProfile& tx, const TimingProfile& rx,
                                  bool bit_rate_switch) {
  Compatibility c;
  c.mismatch = rx.rate > 0 ? std::fabs(tx.rate - rx.rate) / rx.rate : 1.0;
  c.tolerance = rx.tolerance;
  c.ok = c.mismatch <= c.tolerance;
  if (!c.ok || !bit_rate_switch) {
    return c;
  }
  c.data_phase = true;
  if (!tx.has_data_phase || !rx.has_data_phase) {
    c.ok = false;
    c.mismatch = 1.0;
    c.tolerance = 0.0;
    return c;
  }
  c.mismatch = rx.data_rate > 0 ? std::fabs(tx.data_rate - rx.data_rate) / rx.data_rate : 1.0;
  c.tolerance = rx.data_tolerance;
  c.ok = c.mismatch <= c.tolerance;
  return c;
}

Compatibility check_compatibility(const NodeTiming& tx, const NodeTiming& rx,
                                  bool bit_rate_switch) {
  return check_compatibility(timing_profile(tx), timing_profile(rx), bit_rate_switch);
}

}  // namespace canemu::model
