// libFuzzer target: the configuration and fault-scenario loaders. Any text either loads into a
// configuration the daemon can build (or reject with errors) or is rejected with errors; the
// same text read as a scenario is either applied to the default simulation (which then runs a
// little) or rejected with errors; nothing may crash.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/world/simulation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace canemu::daemon;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto scenario = parse_scenario(text, "fuzz-scenario.toml");
  if (!scenario && scenario.error().empty()) {
    std::abort();
  }
  if (scenario) {
    auto sim = std::move(*Simulation::build(*load_default_config()));
    if (auto applied = sim->scenarios().apply(*scenario, canemu::model::SimTime{}); applied) {
      sim->scheduler().run_until(canemu::model::SimTime::from_ns(5'000'000));
    } else if (applied.error().empty()) {
      std::abort();
    }
  }
  auto config = parse_config(text, "fuzz.toml");
  if (!config) {
    if (config.error().empty()) {
      std::abort();  // a rejection always says why
    }
    return 0;
  }
  (void)summary(*config);
  if (config->buses.size() <= 16 && config->devices.size() <= 16) {
    (void)Simulation::build(*config);
  }
  return 0;
}
