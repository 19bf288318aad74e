// canemu lin: canemud's simulated LIN nodes at run time: load [[lin_node]] tables or an LDF
// file (through the canemu Python package's LDF import), list them, switch one on or off, run or
// stop its schedule table, remove it (docs/lin.md, "Simulated nodes at run time").
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"
#include "command.hpp"
#include "python_tool.hpp"

namespace canemu::cli {

namespace {

struct LinOptions {
  std::string file;
  std::string bus;
  std::vector<std::string> real;
  std::string schedule;
  std::string node;
  std::string table;
  bool stop = false;
};

void print_nodes(const ipc::LinNodeReply& r) {
  std::printf("%-16s %-12s %-8s %-16s %10s %10s\n", "NODE", "BUS", "POWER", "SCHEDULE", "HEADERS",
              "RESPONSES");
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::LinNodeEntry& e = r.nodes[i];
    const std::string schedule = ipc::name_of(e.schedule);
    std::printf("%-16s %-12s %-8s %-16s %10llu %10llu\n", ipc::name_of(e.name).c_str(),
                ipc::name_of(e.bus).c_str(), e.powered ? "on" : "off",
                schedule.empty() ? "-" : schedule.c_str(),
                static_cast<unsigned long long>(e.headers),
                static_cast<unsigned long long>(e.responses));
  }
}

int request(const std::string& socket, ipc::LinNodeRequest& m, bool list) {
  auto c = connect(socket, "canemu lin");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = c->call<ipc::LinNodeRequest, ipc::LinNodeReply>(m);
  if (!r) {
    return fail(r.error().message);
  }
  if (!r->ok) {
    const std::string errors = ipc::name_of(r->errors);
    std::fputs((errors.ends_with('\n') ? errors : errors + '\n').c_str(), stderr);
    return fail("nothing changed");
  }
  if (list) {
    print_nodes(*r);
  }
  return 0;
}

// The tables to load: the file itself (TOML), or what canemu.ldf makes of an LDF file.
tl::expected<std::string, std::string> tables_of(const LinOptions& o) {
  const bool ldf = o.file.size() > 4 && o.file.substr(o.file.size() - 4) == ".ldf";
  if (!ldf) {
    if (!o.real.empty() || !o.schedule.empty() || !o.bus.empty()) {
      return tl::unexpected(std::string("--bus, --real and --schedule belong to an LDF file"));
    }
    return ipc::read_text_file(o.file, kMaxTextFileBytes);
  }
  if (o.bus.empty()) {
    return tl::unexpected(std::string("an LDF file needs --bus (the LIN bus its cluster runs on)"));
  }
  std::vector<std::string> args{o.file, "--bus", o.bus};
  for (const std::string& r : o.real) {
    args.insert(args.end(), {"--real", r});
  }
  if (!o.schedule.empty()) {
    args.insert(args.end(), {"--schedule", o.schedule});
  }
  const PythonRun run = run_python_module("canemu.ldf", args, "", true);
  if (run.status != 0) {
    return tl::unexpected(fmt::format(
        "{} -m canemu.ldf {} (it needs the canemu Python package and ldfparser; CANEMU_PYTHON "
        "names the interpreter)",
        run.interpreter, run.error.empty() ? "failed" : "cannot run: " + run.error));
  }
  return run.output;
}

}  // namespace

// Names are scoped by bus (two clusters may each have a "bcm").
constexpr const char* kNodeHelp = "the node: NAME, or BUS/NAME when several buses have a NAME";

Command add_lin(CLI::App& app, const std::string& socket) {
  auto* lin = app.add_subcommand("lin", "canemud's simulated LIN nodes at run time");
  lin->require_subcommand(1);
  auto o = std::make_shared<LinOptions>();
  auto* load = lin->add_subcommand("load", "load [[lin_node]] tables (TOML) or an LDF file");
  load->add_option("FILE", o->file, "FILE.toml or FILE.ldf")->required();
  load->add_option("--bus", o->bus, "LDF: the LIN bus its cluster runs on");
  load->add_option("--real", o->real, "LDF: a node a real program plays (not simulated)");
  load->add_option("--schedule", o->schedule, "LDF: the master's schedule table to run");
  auto* list = lin->add_subcommand("list", "the simulated LIN nodes");
  auto* on = lin->add_subcommand("on", "switch a node on");
  on->add_option("NODE", o->node, kNodeHelp)->required();
  auto* off = lin->add_subcommand("off", "switch a node off (it answers nothing, sends nothing)");
  off->add_option("NODE", o->node, kNodeHelp)->required();
  auto* schedule = lin->add_subcommand("schedule", "run a commander's schedule table, or --stop");
  schedule->add_option("NODE", o->node, kNodeHelp)->required();
  schedule->add_option("TABLE", o->table, "the table to run from its first slot, now");
  schedule->add_flag("--stop", o->stop, "stop the schedule");
  auto* remove = lin->add_subcommand("remove", "remove a node from its bus");
  remove->add_option("NODE", o->node, kNodeHelp)->required();
  return {lin, [&socket, o, load, list, on, off, schedule, remove] {
            auto m =
                std::make_unique<ipc::LinNodeRequest>(ipc::make_message<ipc::LinNodeRequest>());
            if (o->node.size() >= sizeof m->name) {
              return fail(fmt::format("{}: a node is named in at most {} characters", o->node,
                                      sizeof m->name - 1));
            }
            ipc::copy_name(m->name, o->node);
            if (load->parsed()) {
              auto text = tables_of(*o);
              if (!text) {
                return fail(text.error());
              }
              if (text->size() > sizeof m->text) {
                return fail(fmt::format("{}: {} bytes of tables; at most {} go at once", o->file,
                                        text->size(), sizeof m->text));
              }
              m->op = static_cast<uint8_t>(ipc::LinNodeOp::load);
              m->length = static_cast<uint32_t>(text->size());
              std::copy(text->begin(), text->end(), m->text);
              ipc::copy_name(m->source, o->file);
            } else if (on->parsed() || off->parsed()) {
              m->op = static_cast<uint8_t>(ipc::LinNodeOp::power);
              m->on = on->parsed() ? 1 : 0;
            } else if (schedule->parsed()) {
              if (o->stop == !o->table.empty()) {
                return fail("canemu lin schedule NODE TABLE, or NODE --stop");
              }
              m->op = static_cast<uint8_t>(ipc::LinNodeOp::schedule);
              ipc::copy_name(m->table, o->table);
            } else if (remove->parsed()) {
              m->op = static_cast<uint8_t>(ipc::LinNodeOp::remove);
            }
            return request(socket, *m, list->parsed() || load->parsed());
          }};
}

}  // namespace canemu::cli
