#include "canemu/firmware_model/fault_plan.hpp"

namespace canemu::model {

FrameFault FaultPlan::on_frame(const FrameContext& ctx) {
  std::optional<FrameFault> chosen;
  for (FaultRule& r : rules_) {
    if (ctx.sof < r.from || (r.until && ctx.sof >= *r.until)) {
      continue;
    }
    if (!r.match.matches(ctx.transmitter, ctx.frame)) {
      continue;
    }
    const uint64_t nth = r.seen++;
    if (nth < r.skip || (r.count && r.hits >= *r.count) || chosen) {
      continue;
    }
    r.hits++;
    chosen = r.fault;
  }
  return chosen.value_or(FrameFault{});
}

}  // namespace canemu::model
