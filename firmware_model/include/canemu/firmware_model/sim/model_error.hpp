// Errors of the firmware model's validating factories (frames, bit timing).
//
// The model reports misprogramming of running hardware as events and status bits, as silicon
// does; this type is only for building values (a frame, a decoded bit timing) from numbers that
// do not describe a valid one. Every error carries a message that names what is wrong.
#pragma once

#include <string>
#include <string_view>

#include <tl/expected.hpp>

namespace canemu::model {

enum class ModelErrc {
  invalid_identifier,
  invalid_dlc,
  invalid_flags,
  data_length_mismatch,
  timing_out_of_range,
  timing_rule_violated,
  timing_not_realizable,
};

std::string_view to_string(ModelErrc code);

struct ModelError {
  ModelErrc code;
  std::string message;

  friend bool operator==(const ModelError&, const ModelError&) = default;
};

// One alias, so that moving to std::expected later is a one-line change.
template <class T>
using Result = tl::expected<T, ModelError>;

inline tl::unexpected<ModelError> model_error(ModelErrc code, std::string message) {
  return tl::unexpected<ModelError>(ModelError{code, std::move(message)});
}

}  // namespace canemu::model
