// canemu time step: advance canemud's simulated time (stepped mode).
#include <cstdio>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"
#include "command.hpp"

namespace canemu::cli {

namespace {

int run_step(const std::string& socket, const std::string& duration) {
  const auto ns = parse_positive_duration(duration);
  if (!ns) {
    return fail(fmt::format("'{}' is not a duration (examples: 150ns, 20us, 10ms, 2s)", duration));
  }
  auto c = connect(socket, "canemu time");
  if (!c) {
    return fail(c.error().message);
  }
  auto reply = step_time(*c, *ns);
  if (!reply) {
    return fail(reply.error().message);
  }
  std::printf("simulated time %.9f s (%llu events)\n",
              static_cast<double>(reply->sim_time_ns) / 1e9,
              static_cast<unsigned long long>(reply->events_run));
  // Across hosts: the step ran, but without the followers it let go (they are gone).
  if (const std::string note = ipc::printable(ipc::name_of(reply->note)); !note.empty()) {
    std::printf("%s\n", note.c_str());
  }
  return 0;
}

}  // namespace

Command add_time(CLI::App& app, const std::string& socket) {
  auto* time = app.add_subcommand("time", "simulated time (stepped mode)");
  time->require_subcommand(1);
  auto* step = time->add_subcommand("step", "advance simulated time, e.g. 'time step 10ms'");
  auto duration = std::make_shared<std::string>();
  step->add_option("DURATION", *duration, "150ns, 20us, 10ms, 2s")->required();
  return {time, [&socket, duration] { return run_step(socket, *duration); }};
}

}  // namespace canemu::cli
