#include "bus/timing_errors.hpp"

#include <fmt/format.h>

namespace canemu::model {

tl::unexpected<ModelError> timing_out_of_range(std::string_view what, uint64_t value, uint64_t lo,
                                               uint64_t hi) {
  return model_error(ModelErrc::timing_out_of_range,
                     fmt::format("{} = {} is outside {}..{}", what, value, lo, hi));
}

tl::unexpected<ModelError> timing_rule(std::string text) {
  return model_error(ModelErrc::timing_rule_violated, std::move(text));
}

}  // namespace canemu::model
