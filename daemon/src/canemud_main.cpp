// canemud: parse the command line, load and check the configuration, build the simulation, run.
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include <sys/resource.h>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/distributed/distributed.hpp"
#include "canemu/daemon/loop/server.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace {

// The canemu command to suggest: when canemud is the program this build made (run from the build
// tree), the canemu beside it, written as canemud was started (`build/bin/canemud` from the
// source folder gives `build/bin/canemu`; a full path, a full path); else, and when it was
// found on the PATH, `canemu` (installed, or the build's bin folder on the PATH).
std::string canemu_command(const char* argv0) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec || self != fs::weakly_canonical(CANEMU_BUILD_CANEMUD, ec) || ec ||
      !fs::exists(CANEMU_BUILD_CANEMU, ec)) {
    return "canemu";
  }
  const std::string started = argv0 != nullptr ? argv0 : "";
  const std::size_t slash = started.rfind('/');
  if (slash == std::string::npos) {
    return "canemu";
  }
  return started.substr(0, slash + 1) + fs::path(CANEMU_BUILD_CANEMU).filename().string();
}

}  // namespace

// An exception out of main is a bug of canemud: it ends the process with its message.
int main(int argc, char** argv) {  // NOLINT(bugprone-exception-escape)
  using namespace canemu::daemon;
  CLI::App app{"canemud: emulated IXXAT and SORCUS CAN/LIN adapters"};
  std::string config_file;
  std::string check_file;
  std::string socket;
  std::string time;
  bool print_default = false;
  app.add_option("--config", config_file, "configuration file (default: the embedded one)");
  app.add_option("--check-config", check_file, "check FILE, print a summary and exit")
      ->option_text("FILE");
  app.add_option("--socket", socket,
                 "control socket (default: $CANEMU_SOCKET, $RUNTIME_DIRECTORY/canemud.sock, "
                 "/run/canemu/canemud.sock)");
  app.add_option("--time", time,
                 "time mode, overriding the configuration: realtime, stepped, "
                 "scaled:F");
  app.add_flag("--print-default-config", print_default,
               "print the embedded configuration (what canemud runs without --config) and exit");
  app.set_version_flag("--version", "canemud " CANEMU_VERSION, "print canemud's version and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // The parser's sentence, and exit 1 as for every other failure (not CLI11's own codes).
    app.exit(e);
    return 1;
  }

  if (print_default) {
    const std::string_view text = embedded_default_config();
    std::fwrite(text.data(), 1, text.size(), stdout);
    return std::fflush(stdout) == 0 ? 0 : 1;
  }
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
  std::optional<TimeSetting> time_override;
  if (!time.empty()) {
    auto t = parse_time_setting(time);
    if (!t) {
      std::fprintf(stderr, "canemud: --time: %s\n", t.error().c_str());
      return 1;
    }
    config->simulation.time = *t;
    time_override = *t;
  }
  auto sim = Simulation::build(*config, Distributed::open_remote);
  if (!sim) {
    for (const std::string& e : sim.error()) {
      std::fprintf(stderr, "%s\n", e.c_str());
    }
    return 1;
  }
  // Fault scenarios of the configuration, applied from time 0 (logged when canemud runs; a
  // check prints its report on stdout and logs warnings and errors only).
  if (checking) {
    log::set_max_level(log::Level::warning);
  }
  std::string scenarios;
  for (const std::string& scenario_file : config->scenario_files) {
    auto scenario = load_scenario_file(scenario_file);
    auto applied =
        scenario ? (*sim)->scenarios().apply(*scenario, canemu::model::SimTime{})
                 : tl::expected<void, std::vector<std::string>>(tl::unexpected(scenario.error()));
    if (!applied) {
      for (const std::string& e : applied.error()) {
        std::fprintf(stderr, "%s\n", e.c_str());
      }
      std::fprintf(stderr, "canemud: scenario %s rejected; nothing of it applied\n",
                   scenario_file.c_str());
      return 1;
    }
    scenarios += fmt::format("  scenario \"{}\" ({}): {} fault{}\n", scenario->name, scenario_file,
                             scenario->faults.size(), scenario->faults.size() == 1 ? "" : "s");
  }
  if (checking) {
    std::fputs(summary(*config).c_str(), stdout);
    std::fputs(scenarios.c_str(), stdout);
    std::fputs("configuration OK\n", stdout);
    return 0;
  }
  // Each client holds descriptors for its rings and doorbells: take all the hard limit allows
  // (systemd's LimitNOFILE= sets it), not the soft 1024 that a few clients would exhaust.
  if (rlimit nofile{};
      ::getrlimit(RLIMIT_NOFILE, &nofile) == 0 && nofile.rlim_cur < nofile.rlim_max) {
    nofile.rlim_cur = nofile.rlim_max;
    if (::setrlimit(RLIMIT_NOFILE, &nofile) != 0) {
      log::warning("cannot raise the descriptor limit to {}", nofile.rlim_max);
    }
  }
  Server server(**sim, ServerOptions{canemu::ipc::socket_path(socket), config->simulation.time,
                                     config_file, time_override});
  if (auto opened = server.open(); !opened) {
    log::error("{}", opened.error().message);
    return 1;
  }
  std::fputs(summary(*config).c_str(), stderr);
  std::fputs(scenarios.c_str(), stderr);
  log::info("listening on {}", server.socket_path());
  log::info("try: CANEMU_SOCKET={} {} status", server.socket_path(), canemu_command(argv[0]));
  return server.run();
}
