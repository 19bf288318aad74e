// What the daemon's fuzz targets share: a configuration parsed once, and a fresh simulation of
// it for each input (nothing one input did can hide or cause another's crash).
#pragma once

#include <cstdlib>
#include <memory>
#include <string_view>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::fuzzing {

// `text` parsed as a configuration; a text that does not parse is the target's bug: abort.
inline daemon::Config parse_or_abort(std::string_view text) {
  auto parsed = daemon::parse_config(text, "fuzz.toml");
  if (!parsed) {
    std::abort();
  }
  return std::move(*parsed);
}

inline std::unique_ptr<daemon::Simulation> fresh_simulation(const daemon::Config& config) {
  auto sim = daemon::Simulation::build(config);
  if (!sim) {
    std::abort();
  }
  return std::move(*sim);
}

}  // namespace canemu::fuzzing
