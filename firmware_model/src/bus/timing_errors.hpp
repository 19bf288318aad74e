// The two error shapes every bit-timing decoder reports (a value outside its range, a rule
// broken), shared by the decoders of each device. Private to firmware_model.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "canemu/firmware_model/sim/model_error.hpp"

namespace canemu::model {

tl::unexpected<ModelError> timing_out_of_range(std::string_view what, uint64_t value, uint64_t lo,
                                               uint64_t hi);
tl::unexpected<ModelError> timing_rule(std::string text);

}  // namespace canemu::model
