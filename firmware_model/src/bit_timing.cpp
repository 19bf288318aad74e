#include "canemu/firmware_model/bit_timing.hpp"

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
  // qa * pa / fa + qb * pb / fb seconds = (qa * pa * fb + qb * pb * fa) / (fa * fb).
  const u128 num = u128{qa} * a.prescaler * b.clock_hz + u128{qb} * b.prescaler * a.clock_hz;
  const u128 den = u128{a.clock_hz} * b.clock_hz;
  return SimDuration(static_cast<int64_t>((num * kNsPerSecond + den / 2) / den));
}

Compatibility check_compatibility(const NodeTiming& tx, const NodeTiming& rx,
                                  bool bit_rate_switch) {
  Compatibility c;
  const double f_tx = effective_rate(tx.nominal, tx.oscillator_ppm);
  const double f_rx = effective_rate(rx.nominal, rx.oscillator_ppm);
  c.mismatch = f_rx > 0 ? std::fabs(f_tx - f_rx) / f_rx : 1.0;
  c.tolerance = 2.0 * rx.nominal.oscillator_tolerance();
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
  const double d_tx = effective_rate(tx.data, tx.oscillator_ppm);
  const double d_rx = effective_rate(rx.data, rx.oscillator_ppm);
  c.mismatch = d_rx > 0 ? std::fabs(d_tx - d_rx) / d_rx : 1.0;
  c.tolerance = 2.0 * data_phase_tolerance(rx.nominal, rx.data);
  c.ok = c.mismatch <= c.tolerance;
  return c;
}

}  // namespace canemu::model
