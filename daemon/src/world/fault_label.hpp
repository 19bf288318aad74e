// How the log names a fault of a scenario: its scenario, line and effect.
#pragma once

#include <string>
#include <string_view>

#include <fmt/format.h>

#include "canemu/daemon/config/scenario.hpp"

namespace canemu::daemon {

inline std::string fault_label(std::string_view scenario, const FaultSpec& f) {
  return fmt::format("scenario \"{}\" line {}: {}", scenario, f.line, to_string(f.effect));
}

}  // namespace canemu::daemon
