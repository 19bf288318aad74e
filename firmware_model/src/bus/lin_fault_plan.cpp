#include "canemu/firmware_model/bus/lin_fault_plan.hpp"

namespace canemu::model::lin {

FrameFaults LinFaultPlan::faults_for(SimTime at, uint8_t id, LinNodeId commander) {
  FrameFaults f;
  for (std::size_t i = 0; i < rules_.size(); ++i) {
    LinFaultRule& r = rules_[i];
    if (!r.enabled || at < r.from || (r.until && at >= *r.until) ||
        (r.commander && *r.commander != commander) || (r.id && *r.id != id)) {
      continue;
    }
    ++r.seen;
    if (r.seen <= r.skip || (r.count && r.hits >= *r.count)) {
      continue;
    }
    ++r.hits;
    switch (r.effect) {
      case LinEffect::header_bit_error:
        f.header_bit_error = true;
        break;
      case LinEffect::response_bit_error:
        f.response_bit_error = true;
        break;
      case LinEffect::checksum_error:
        f.checksum_error = true;
        break;
      case LinEffect::parity_error:
        f.parity_error = true;
        break;
      case LinEffect::no_response:
        f.no_response = true;
        break;
      case LinEffect::sync_error:
        f.sync_error = true;
        break;
      case LinEffect::short_break:
        f.short_break = true;
        break;
      case LinEffect::responder_off:
        f.silent = r.responder;
        break;
    }
    if (on_hit) {
      on_hit(i, at, id);
    }
  }
  return f;
}

}  // namespace canemu::model::lin
