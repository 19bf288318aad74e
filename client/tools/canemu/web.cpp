// canemu web: a live page of canemud's buses, nodes, ID tables and faults, and /metrics for
// Prometheus, served over HTTP by the canemu Python package's canemu.web (aiohttp). It is a
// client of the control socket like every other command: canemud itself opens no TCP port.
// This file checks that canemud answers (so that the usual connect errors are the ones shown),
// then becomes `python3 -m canemu.web` (docs/web.md).
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "command.hpp"
#include "python_tool.hpp"

namespace canemu::cli {

namespace {

struct Options {
  std::string listen = "127.0.0.1:8047";
  bool allow_control = false;
  unsigned interval_ms = 250;
  bool no_frames = false;
  std::vector<std::string> dbc;  // [BUS=]FILE
};

int run_web(const std::string& socket, const Options& o) {
  {
    auto c = connect(socket, "canemu web");
    if (!c) {
      return fail(c.error().message);
    }
  }
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) {
    return fail(fmt::format("web: cannot find this program's own path: {}", ec.message()));
  }
  std::vector<std::string> args{"--canemu", self.string(), "--listen",
                                o.listen,   "--interval",  std::to_string(o.interval_ms)};
  if (!socket.empty()) {
    args.insert(args.end(), {"--socket", socket});
  }
  if (o.allow_control) {
    args.emplace_back("--allow-control");
  }
  if (o.no_frames) {
    args.emplace_back("--no-frames");
  }
  for (const std::string& d : o.dbc) {
    args.insert(args.end(), {"--dbc", d});
  }
  const std::string why = exec_python_module("canemu.web", args);
  return fail(fmt::format("web: cannot run {} (CANEMU_PYTHON names the interpreter)", why));
}

}  // namespace

Command add_web(CLI::App& app, const std::string& socket) {
  auto* cmd = app.add_subcommand(
      "web", "serve a live page of buses, nodes, ID tables and faults, and /metrics, over HTTP");
  auto o = std::make_shared<Options>();
  cmd->add_option("--listen", o->listen,
                  "HOST:PORT to serve on (default 127.0.0.1:8047; anyone who reaches it sees "
                  "every bus: docs/web.md)");
  cmd->add_flag("--allow-control", o->allow_control,
                "let the page inject faults, step time and unplug nodes (read-only without it)");
  cmd->add_option("--interval", o->interval_ms,
                  "milliseconds between two looks at canemud's status (default 250)")
      ->check(CLI::Range(50u, 10000u));
  cmd->add_flag("--no-frames", o->no_frames,
                "no ID tables: open no listen-only channel on the buses");
  cmd->add_option("--dbc", o->dbc,
                  "[BUS=]FILE: decode the ID tables' frames with this DBC (on BUS only, or on "
                  "every bus); may be given several times")
      ->allow_extra_args(false);
  return {cmd, [&socket, o] { return run_web(socket, *o); }};
}

}  // namespace canemu::cli
