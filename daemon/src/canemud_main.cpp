// canemud: parse the command line, load and check the configuration, run.
#include <cstdio>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/daemon/config.hpp"

int main(int argc, char** argv) {
  using namespace canemu::daemon;
  CLI::App app{"canemud: emulated IXXAT and SORCUS CAN/LIN adapters"};
  std::string config_file;
  std::string check_file;
  app.add_option("--config", config_file, "configuration file (default: the embedded one)");
  app.add_option("--check-config", check_file, "check FILE, print a summary and exit")
      ->option_text("FILE");
  CLI11_PARSE(app, argc, argv);

  const bool checking = !check_file.empty();
  const std::string& file = checking ? check_file : config_file;
  auto config = file.empty() ? load_default_config() : load_config_file(file);
  if (!config) {
    for (const std::string& e : config.error()) {
      std::fprintf(stderr, "%s\n", e.c_str());
    }
    std::fprintf(stderr, "canemud: configuration rejected (%zu error%s)\n", config.error().size(),
                 config.error().size() == 1 ? "" : "s");
    return 1;
  }
  if (checking) {
    std::fputs(summary(*config).c_str(), stdout);
    std::fputs("configuration OK\n", stdout);
    return 0;
  }
  std::fputs(summary(*config).c_str(), stderr);
  std::fprintf(stderr, "canemud: the daemon's event loop is not part of this build yet\n");
  return 2;
}
