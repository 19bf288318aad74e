// canemu restbus: canemud's simulated CAN nodes at run time: load [[can_node]] tables or a DBC
// file (through the canemu Python package's DBC import), list them, switch one on or off,
// remove it. canemu signal: set or read a signal of a message a simulated node sends
// (docs/restbus.md).
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/can_nodes.hpp"
#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"
#include "command.hpp"
#include "python_tool.hpp"

namespace canemu::cli {

namespace {

struct RestbusOptions {
  std::string file;
  std::string bus;
  std::vector<std::string> real;
  std::vector<std::string> counters;
  std::vector<std::string> checksums;
  std::string node;
  std::string signal;  // MESSAGE.SIGNAL
  std::string value;
};

void print_nodes(const ipc::CanNodeReply& r) {
  std::printf("%-20s %-12s %-6s %9s %12s\n", "NODE", "BUS", "POWER", "MESSAGES", "FRAMES");
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::CanNodeEntry& e = r.nodes[i];
    std::printf("%-20s %-12s %-6s %9u %12llu\n", ipc::name_of(e.name).c_str(),
                ipc::name_of(e.bus).c_str(), e.powered ? "on" : "off", e.messages,
                static_cast<unsigned long long>(e.frames));
  }
  if (r.total > r.count) {
    std::printf("(%u more)\n", static_cast<unsigned>(r.total - r.count));
  }
}

// Sends the requests (a load's parts, or one request); the last reply, or an exit status.
tl::expected<std::unique_ptr<ipc::CanNodeReply>, int> call(client::Connection& c,
                                                           const client::CanNodeRequests& parts) {
  client::CanNodeOutcome r = client::call_can_nodes(c, parts);
  if (r.error) {
    return tl::unexpected(fail(r.error->message));
  }
  if (!r.reply) {
    std::fputs((r.refused + '\n').c_str(), stderr);
    return tl::unexpected(fail("nothing changed"));
  }
  return std::move(r.reply);
}

// The tables to load: the file itself (TOML), or what canemu.dbc makes of a DBC file.
tl::expected<std::string, std::string> tables_of(const RestbusOptions& o) {
  const bool dbc = o.file.size() > 4 && (o.file.substr(o.file.size() - 4) == ".dbc" ||
                                         o.file.substr(o.file.size() - 4) == ".DBC");
  if (!dbc) {
    if (!o.real.empty() || !o.bus.empty() || !o.counters.empty() || !o.checksums.empty()) {
      return tl::unexpected(
          std::string("--bus, --real, --counter and --checksum belong to a DBC file"));
    }
    return ipc::read_text_file(o.file, ipc::kMaxCanNodeLoad);
  }
  if (o.bus.empty()) {
    return tl::unexpected(std::string("a DBC file needs --bus (the CAN bus its nodes send on)"));
  }
  std::vector<std::string> args{o.file, "--bus", o.bus};
  for (const std::string& r : o.real) {
    args.insert(args.end(), {"--real", r});
  }
  for (const std::string& s : o.counters) {
    args.insert(args.end(), {"--counter", s});
  }
  for (const std::string& s : o.checksums) {
    args.insert(args.end(), {"--checksum", s});
  }
  const PythonRun run = run_python_module("canemu.dbc", args, "", true);
  if (run.status != 0) {
    return tl::unexpected(fmt::format(
        "{} -m canemu.dbc {} (it needs the canemu Python package and cantools; CANEMU_PYTHON "
        "names the interpreter)",
        run.interpreter, run.error.empty() ? "failed" : "cannot run: " + run.error));
  }
  return run.output;
}

int run(const std::string& socket, const client::CanNodeRequests& parts, bool list, bool value) {
  auto c = connect(socket, "canemu restbus");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = call(*c, parts);
  if (!r) {
    return r.error();
  }
  if (list) {
    print_nodes(**r);
  }
  if (value) {
    std::printf("%s\n", fmt::format("{}", (*r)->value).c_str());
  }
  return 0;
}

constexpr const char* kNodeHelp = "the node: NAME, or BUS/NAME when several buses have a NAME";

}  // namespace

Command add_restbus(CLI::App& app, const std::string& socket) {
  auto* restbus = app.add_subcommand("restbus", "canemud's simulated CAN nodes at run time");
  restbus->require_subcommand(1);
  auto o = std::make_shared<RestbusOptions>();
  auto* load = restbus->add_subcommand("load", "load [[can_node]] tables (TOML) or a DBC file");
  load->add_option("FILE", o->file, "FILE.toml or FILE.dbc")->required();
  load->add_option("--bus", o->bus, "DBC: the CAN bus its nodes send on");
  load->add_option("--real", o->real, "DBC: a node a real program plays (not simulated)");
  load->add_option("--counter", o->counters, "DBC: MESSAGE.SIGNAL is an alive counter");
  load->add_option("--checksum", o->checksums,
                   "DBC: MESSAGE.SIGNAL=crc8_sae_j1850[:DATA_ID]|xor8|sum8, a checksum");
  auto* list = restbus->add_subcommand("list", "the simulated CAN nodes");
  auto* on = restbus->add_subcommand("on", "switch a node on (its schedules start again)");
  on->add_option("NODE", o->node, kNodeHelp)->required();
  auto* off = restbus->add_subcommand("off", "switch a node off (it leaves the bus)");
  off->add_option("NODE", o->node, kNodeHelp)->required();
  auto* remove = restbus->add_subcommand("remove", "remove a node from its bus");
  remove->add_option("NODE", o->node, kNodeHelp)->required();
  return {restbus, [&socket, o, load, list, on, off, remove] {
            if (load->parsed()) {
              auto text = tables_of(*o);
              if (!text) {
                return fail(text.error());
              }
              return run(socket, client::can_node_load_requests(*text, o->file), true, false);
            }
            client::CanNodeRequests parts;
            parts.push_back(client::can_node_request(list->parsed()     ? ipc::CanNodeOp::list
                                                     : remove->parsed() ? ipc::CanNodeOp::remove
                                                                        : ipc::CanNodeOp::power));
            if (std::string e = client::name_can_node(*parts[0], o->node); !e.empty()) {
              return fail(e);
            }
            parts[0]->on = on->parsed() ? 1 : 0;
            return run(socket, parts, list->parsed(), false);
          }};
}

Command add_signal(CLI::App& app, const std::string& socket) {
  auto* signal = app.add_subcommand("signal", "a signal of a simulated CAN node's message");
  signal->require_subcommand(1);
  auto o = std::make_shared<RestbusOptions>();
  auto* set = signal->add_subcommand(
      "set",
      "set a signal's physical value (its next frame carries it; an on-change message "
      "goes at once)");
  set->add_option("BUS", o->bus, "the CAN bus")->required();
  set->add_option("MESSAGE.SIGNAL", o->signal, "the DBC message and signal")->required();
  set->add_option("VALUE", o->value, "the physical value (the DBC's units)")->required();
  auto* get = signal->add_subcommand("get", "a signal's physical value now");
  get->add_option("BUS", o->bus, "the CAN bus")->required();
  get->add_option("MESSAGE.SIGNAL", o->signal, "the DBC message and signal")->required();
  return {signal, [&socket, o, set] {
            client::CanNodeRequests parts;
            parts.push_back(client::can_node_request(set->parsed() ? ipc::CanNodeOp::set_signal
                                                                   : ipc::CanNodeOp::get_signal));
            if (std::string e = client::name_signal(*parts[0], o->bus, o->signal); !e.empty()) {
              return fail(e);
            }
            if (set->parsed()) {
              double v = 0;
              const char* end = o->value.data() + o->value.size();
              const auto [p, ec] = std::from_chars(o->value.data(), end, v);
              if (ec != std::errc{} || p != end) {
                return fail(fmt::format("\"{}\" is not a number", o->value));
              }
              parts[0]->value = v;
            }
            return run(socket, parts, false, !set->parsed());
          }};
}

}  // namespace canemu::cli
