// What the daemon's tests share: a configuration or a scenario read from its text (that must
// read, or must not and gives its errors), a scenario applied to a running simulation, and the
// text of an error a simulation returns.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon::daemon_test {

// The text of the error a simulation's call returned (add_bridge, a bridge's restart and the
// like), as a person reads it; empty if it succeeded.
std::string error_text(const auto& result) {
  return result ? std::string() : result.error().what();
}

// The configuration `text` describes; a failure of the test (and an empty configuration) if it
// does not read.
inline Config config_of(std::string_view text, const std::string& file = "t.toml") {
  auto c = parse_config(text, file);
  if (!c) {
    ADD_FAILURE() << file << ": " << c.error().front();
    return Config{};
  }
  return std::move(*c);
}

// The errors of a configuration text that must not read, in the order they are given.
inline std::vector<std::string> config_errors(std::string_view text,
                                              const std::string& file = "t.toml") {
  auto c = parse_config(text, file);
  EXPECT_FALSE(c.has_value()) << file << " was read without an error";
  return c ? std::vector<std::string>{} : c.error();
}

// The errors of a fault scenario text that must not read.
inline std::vector<std::string> scenario_errors(std::string_view text,
                                                const std::string& file = "s.toml") {
  auto s = parse_scenario(text, file);
  EXPECT_FALSE(s.has_value()) << file << " was read without an error";
  return s ? std::vector<std::string>{} : s.error();
}

// Reads the fault scenario `text` and applies it to `sim` now; both must succeed.
inline void apply_scenario(Simulation& sim, std::string_view text,
                           const std::string& file = "s.toml") {
  auto s = parse_scenario(text, file);
  ASSERT_TRUE(s) << s.error().front();
  auto applied = sim.scenarios().apply(*s, sim.scheduler().now());
  ASSERT_TRUE(applied) << applied.error().front();
}

// The errors of applying the fault scenario `text` (which must read) to `sim` now; none if it
// applies, which fails the test.
inline std::vector<std::string> scenario_refusal(Simulation& sim, std::string_view text,
                                                 const std::string& file = "s.toml") {
  auto s = parse_scenario(text, file);
  EXPECT_TRUE(s) << (s ? "" : s.error().front());
  if (!s) {
    return {};
  }
  auto applied = sim.scenarios().apply(*s, sim.scheduler().now());
  EXPECT_FALSE(applied) << file << " was applied";
  return applied ? std::vector<std::string>{} : applied.error();
}

}  // namespace canemu::daemon::daemon_test
