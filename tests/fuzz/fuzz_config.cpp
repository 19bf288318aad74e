// libFuzzer target: the configuration loader. Any text either loads into a configuration the
// daemon can build (or reject with errors) or is rejected with errors; nothing may crash.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "canemu/daemon/config.hpp"
#include "canemu/daemon/simulation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace canemu::daemon;
  const std::string text(reinterpret_cast<const char*>(data), size);
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
