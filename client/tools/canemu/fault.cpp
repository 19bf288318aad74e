// canemu fault: load a scenario file, list the applied faults, clear a scenario, or inject one
// fault from the command line (docs/faults.md).
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"
#include "command.hpp"
#include "fault_inject.hpp"
#include "fault_table.hpp"

namespace canemu::cli {

namespace {

// The source name of a scenario that `fault inject` built.
const std::string kInjectSource = "<command line>";

// Sends a scenario's text; prints what was applied or every problem.
int load_scenario_text(const std::string& socket, const std::string& source,
                       const std::string& text) {
  if (text.size() > ipc::kMaxScenarioText) {
    return fail(fmt::format("{}: {} bytes; a scenario sent to canemud is at most {}", source,
                            text.size(), ipc::kMaxScenarioText));
  }
  auto c = connect(socket, "canemu fault");
  if (!c) {
    return fail(c.error().message);
  }
  auto m = std::make_unique<ipc::FaultLoadRequest>(ipc::make_message<ipc::FaultLoadRequest>());
  // A path too long for the request goes as its file name (canemud's default scenario name is
  // that anyway), and the errors get the whole path back.
  const std::string sent =
      source.size() < sizeof m->source ? source : std::filesystem::path(source).filename().string();
  ipc::copy_name(m->source, sent);
  m->length = static_cast<uint32_t>(text.size());
  std::memcpy(m->text, text.data(), text.size());
  auto r = c->call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(*m);
  if (!r) {
    return fail(r.error().message);
  }
  if (!r->applied) {
    std::string errors = ipc::name_of(r->errors);
    if (source == kInjectSource) {
      // The scenario was written from the options: its line numbers mean nothing to the user.
      errors = std::regex_replace(errors, std::regex(kInjectSource + ":[0-9]+(:[0-9]+)?: "), "");
    } else if (sent != source) {
      std::string whole;
      std::size_t at = 0;
      while (at < errors.size()) {
        const std::size_t end = std::min(errors.find('\n', at), errors.size());
        const std::string line = errors.substr(at, end - at);
        whole += line.rfind(sent + ":", 0) == 0 ? source + line.substr(sent.size()) : line;
        whole += end < errors.size() ? "\n" : "";
        at = end + 1;
      }
      errors = whole;
    }
    std::fputs(errors.c_str(), stderr);
    return fail("scenario rejected; nothing of it applied");
  }
  std::printf("scenario \"%s\": %u fault%s applied\n", ipc::name_of(r->name).c_str(), r->faults,
              r->faults == 1 ? "" : "s");
  return 0;
}

int run_load(const std::string& socket, const std::string& file) {
  auto text = ipc::read_text_file(file, kMaxTextFileBytes);
  if (!text) {
    return fail(text.error());
  }
  return load_scenario_text(socket, file, *text);
}

int run_list(const std::string& socket) {
  auto c = connect(socket, "canemu fault");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = fault_list(*c);
  if (!r) {
    return fail(r.error());
  }
  print_faults(*r);
  return 0;
}

int run_clear(const std::string& socket, const std::string& name) {
  auto c = connect(socket, "canemu fault");
  if (!c) {
    return fail(c.error().message);
  }
  auto m = ipc::make_message<ipc::FaultClearRequest>();
  ipc::copy_name(m.scenario, name == "all" ? std::string() : name);
  auto r = c->call<ipc::FaultClearRequest, ipc::FaultClearReply>(m);
  if (!r) {
    return fail(r.error().message);
  }
  std::printf("%u scenario%s cleared", r->cleared, r->cleared == 1 ? "" : "s");
  if (r->refused > 0) {
    std::printf("; %u left in force (other users' or the configuration's: an admin clears them)",
                r->refused);
  }
  std::printf("\n");
  return 0;
}

int run_inject(const std::string& socket, const InjectOptions& o) {
  auto text = inject_scenario(o);
  if (!text) {
    return fail(text.error());
  }
  return load_scenario_text(socket, kInjectSource, *text);
}

struct FaultOptions {
  std::string file;
  std::string name = "all";
  InjectOptions inject;
};

}  // namespace

Command add_fault(CLI::App& app, const std::string& socket) {
  auto* fault = app.add_subcommand("fault", "fault scenarios (docs/faults.md)");
  fault->require_subcommand(1);
  auto o = std::make_shared<FaultOptions>();
  auto* load = fault->add_subcommand("load", "apply a scenario file from now on");
  load->add_option("FILE", o->file, "scenario (TOML)")->required();
  auto* list = fault->add_subcommand("list", "every fault applied, with its hits and state");
  auto* clear = fault->add_subcommand("clear", "stop a scenario's faults (NAME or all)");
  clear->add_option("NAME", o->name, "scenario name, or all (default)");
  auto* inject = fault->add_subcommand("inject", "one fault from the command line");
  add_inject_options(*inject, o->inject);
  return {fault, [&socket, o, load, list, clear, inject] {
            if (*load) {
              return run_load(socket, o->file);
            }
            if (*list) {
              return run_list(socket);
            }
            if (*clear) {
              return run_clear(socket, o->name);
            }
            if (*inject) {
              return run_inject(socket, o->inject);
            }
            return 1;
          }};
}

}  // namespace canemu::cli
