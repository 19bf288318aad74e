#include "canemu/firmware_model/sim/model_error.hpp"

namespace canemu::model {

std::string_view to_string(ModelErrc code) {
  switch (code) {
    case ModelErrc::invalid_identifier:
      return "invalid_identifier";
    case ModelErrc::invalid_dlc:
      return "invalid_dlc";
    case ModelErrc::invalid_flags:
      return "invalid_flags";
    case ModelErrc::data_length_mismatch:
      return "data_length_mismatch";
    case ModelErrc::timing_out_of_range:
      return "timing_out_of_range";
    case ModelErrc::timing_rule_violated:
      return "timing_rule_violated";
    case ModelErrc::timing_not_realizable:
      return "timing_not_realizable";
  }
  return "unknown";
}

}  // namespace canemu::model
