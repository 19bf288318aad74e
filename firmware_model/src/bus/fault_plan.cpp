#include "canemu/firmware_model/bus/fault_plan.hpp"

#include <algorithm>
#include <cmath>

namespace canemu::model {

FrameFault FaultPlan::on_frame(const FrameContext& ctx) {
  std::optional<FrameFault> chosen;
  std::size_t chosen_rule = 0;
  for (std::size_t i = 0; i < rules_.size(); ++i) {
    FaultRule& r = rules_[i];
    if (!r.enabled || ctx.sof < r.from || (r.until && ctx.sof >= *r.until)) {
      continue;
    }
    if (!r.match.matches(ctx.transmitter, ctx.frame)) {
      continue;
    }
    const uint64_t nth = r.seen++;
    if (nth < r.skip || (r.count && r.hits >= *r.count) || chosen) {
      continue;
    }
    // A draw only for rules that are not certain, so that certain rules leave the sequence
    // alone.
    if (r.probability < 1.0 && !(draw(r) < r.probability)) {
      continue;
    }
    if (r.bit_error_rate > 0) {
      // The first bit hit, from a geometric distribution: P(first hit = k) = (1 - p)^k p.
      const double u = draw(r);
      const double k = r.bit_error_rate >= 1.0
                           ? 0.0
                           : std::floor(std::log1p(-u) / std::log1p(-r.bit_error_rate));
      if (!(k < static_cast<double>(ctx.bits.length))) {
        continue;
      }
      r.hits++;
      chosen = FrameFault{CanErrorType::bit, static_cast<uint16_t>(k), false};
      chosen_rule = i;
      continue;
    }
    r.hits++;
    chosen = r.fault;
    chosen_rule = i;
  }
  if (!chosen) {
    return FrameFault{};
  }
  if (on_hit) {
    on_hit(ids_[chosen_rule], ctx, *chosen);
  }
  return *chosen;
}

std::size_t FaultPlan::index_of(std::size_t id) const {
  return static_cast<std::size_t>(std::lower_bound(ids_.begin(), ids_.end(), id) - ids_.begin());
}

bool FaultPlan::contains(std::size_t id) const {
  const std::size_t i = index_of(id);
  return i < ids_.size() && ids_[i] == id;
}

void FaultPlan::remove(std::size_t id) {
  if (!contains(id)) {
    return;
  }
  const auto i = static_cast<std::ptrdiff_t>(index_of(id));
  rules_.erase(rules_.begin() + i);
  ids_.erase(ids_.begin() + i);
  set_frames_wanted(!rules_.empty());
}

double FaultPlan::draw(FaultRule& rule) {
  uint64_t z = (rule.rng += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

}  // namespace canemu::model
