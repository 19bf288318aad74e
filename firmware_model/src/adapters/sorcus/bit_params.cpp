#include "canemu/firmware_model/adapters/sorcus/bit_params.hpp"

#include <fmt/format.h>

#include "bus/timing_errors.hpp"

namespace canemu::model::sorcus {

Result<BitTiming> decode_sorcus(const SorcusDevice& device, const SorcusTiming& timing) {
  const uint32_t period_ns = 1'000'000'000u / device.clock_hz;
  if (timing.tq_ns < device.tq_min_ns || timing.tq_ns > device.tq_max_ns) {
    return timing_out_of_range(fmt::format("{} Tq (ns)", device.name), timing.tq_ns,
                               device.tq_min_ns, device.tq_max_ns);
  }
  if (timing.tq_ns % period_ns != 0) {
    return timing_rule(
        fmt::format("{}: Tq = {} ns is not a multiple of the {} ns controller clock "
                    "period",
                    device.name, timing.tq_ns, period_ns));
  }
  if (timing.tseg1 < 3 || timing.tseg1 > 16) {
    return timing_out_of_range(fmt::format("{} Tseg1", device.name), timing.tseg1, 3, 16);
  }
  if (timing.tseg2 < 2 || timing.tseg2 > 8) {
    return timing_out_of_range(fmt::format("{} Tseg2", device.name), timing.tseg2, 2, 8);
  }
  if (timing.sjw < 1 || timing.sjw > 4) {
    return timing_out_of_range(fmt::format("{} Tsjw", device.name), timing.sjw, 1, 4);
  }
  if (timing.samples != 1 && timing.samples != 3) {
    return timing_rule(fmt::format("{}: samples per bit = {}, but only 1 or 3 are possible",
                                   device.name, timing.samples));
  }
  if (timing.tseg1 + timing.tseg2 < 7) {
    return timing_rule(
        fmt::format("{}: Tseg1 + Tseg2 = {} + {} = {}, but the rule is Tseg1 + Tseg2 >= 7",
                    device.name, timing.tseg1, timing.tseg2, timing.tseg1 + timing.tseg2));
  }
  if (timing.tseg2 < timing.sjw) {
    return timing_rule(fmt::format("{}: Tseg2 = {} is less than Tsjw = {} (rule Tseg2 >= Tsjw)",
                                   device.name, timing.tseg2, timing.sjw));
  }
  BitTiming t;
  t.clock_hz = device.clock_hz;
  t.prescaler = timing.tq_ns / period_ns;
  t.tseg1 = timing.tseg1;
  t.tseg2 = timing.tseg2;
  t.sjw = timing.sjw;
  t.samples = static_cast<uint8_t>(timing.samples);
  return t;
}

}  // namespace canemu::model::sorcus
