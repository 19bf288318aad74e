// canemu timeline: what happened on a bus over time, from canemud's records: the load in bins of
// 100 ms of simulated time and, per node, every change of its error counters and state with its
// cause, also of nodes whose ephemeral devices have gone (canemud keeps the newest of each bus).
// canemu plot: the same drawn by matplotlib (the canemu Python package's canemu.plot).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/firmware_model/bus/can_error.hpp"
#include "canemu/ipc/protocol.hpp"
#include "command.hpp"
#include "fault_table.hpp"
#include "python_tool.hpp"
#include "text_table.hpp"

namespace canemu::cli {

namespace {

struct NodeTimeline {
  std::string name;
  uint64_t forgotten = 0;
  bool gone = false;  // its ephemeral device went at gone_at_ns; canemud keeps its history
  int64_t gone_at_ns = 0;
  std::vector<ipc::WireCounterSample> samples;
};

struct Timeline {
  std::string bus;
  int64_t now_ns = 0;
  int64_t start_ns = 0;  // of the first load bin
  uint32_t bin_ns = 0;
  std::vector<uint32_t> busy_ns;
  std::vector<std::string> gone;  // nodes gone from the bus whose history is kept
  std::vector<NodeTimeline> nodes;
};

// An error about node `name`, with the nodes gone from the bus that it may have meant.
std::string unknown_node(const std::string& error, const std::string& name, const Timeline& t) {
  if (t.gone.empty() || std::find(t.gone.begin(), t.gone.end(), name) != t.gone.end()) {
    return error;
  }
  return fmt::format("{}; nodes gone from {}, their history kept: {}", error, t.bus,
                     fmt::join(t.gone, ", "));
}

// Every page of the load history of `bus` and of each node's timeline.
tl::expected<Timeline, std::string> fetch(client::Connection& c, const std::string& bus,
                                          std::vector<std::string> nodes) {
  Timeline t;
  t.bus = bus;
  for (uint32_t first = 0;;) {
    auto m = ipc::make_message<ipc::TimelineRequest>();
    ipc::copy_name(m.bus, bus);
    m.first = first;
    auto r = c.call<ipc::TimelineRequest, ipc::LoadHistoryReply>(m);
    if (!r) {
      return tl::unexpected(r.error().message);
    }
    if (first == 0) {
      t.start_ns = r->start_ns;
      t.now_ns = r->now_ns;
      t.bin_ns = r->bin_ns;
      for (uint32_t k = 0; k < std::min<std::size_t>(r->gone_count, ipc::kMaxGoneNodes); ++k) {
        t.gone.push_back(ipc::name_of(r->gone[k]));
      }
    }
    t.busy_ns.insert(t.busy_ns.end(), r->busy_ns, r->busy_ns + r->count);
    first += r->count;
    if (r->count == 0 || first >= r->total) {
      break;
    }
  }
  if (nodes.empty()) {  // every CAN node of the bus that canemu status lists, then gone ones
    auto s = client::fetch_status(c);
    if (!s) {
      return tl::unexpected(s.error().message);
    }
    for (const ipc::StatusNode& n : s->nodes) {
      if (n.bus < s->buses.size() && ipc::name_of(s->buses[n.bus].name) == bus &&
          static_cast<ipc::WireLinState>(n.lin) == ipc::WireLinState::none) {
        nodes.push_back(ipc::name_of(n.name));
      }
    }
    nodes.insert(nodes.end(), t.gone.begin(), t.gone.end());
  }
  for (const std::string& name : nodes) {
    NodeTimeline n;
    n.name = name;
    for (uint32_t first = 0;;) {
      auto m = ipc::make_message<ipc::TimelineRequest>();
      ipc::copy_name(m.bus, bus);
      ipc::copy_name(m.node, name);
      m.first = first;
      auto r = c.call<ipc::TimelineRequest, ipc::TimelineReply>(m);
      if (!r) {
        return tl::unexpected(unknown_node(r.error().message, name, t));
      }
      n.forgotten = r->forgotten;
      n.gone = r->gone != 0;
      n.gone_at_ns = r->gone_at_ns;
      n.samples.insert(n.samples.end(), r->samples, r->samples + r->count);
      first += r->count;
      if (r->count == 0 || first >= r->total) {
        break;
      }
    }
    t.nodes.push_back(std::move(n));
  }
  return t;
}

const char* cause_name(uint8_t cause) {
  switch (static_cast<ipc::WireCounterCause>(cause)) {
    case ipc::WireCounterCause::success:
      return "success";
    case ipc::WireCounterCause::error:
      return "error";
    case ipc::WireCounterCause::severe:
      return "severe";
    case ipc::WireCounterCause::recovered:
      return "recovered";
    case ipc::WireCounterCause::written:
      return "written";
  }
  return "?";
}

std::string error_name(uint8_t error) {
  return std::string(model::to_string(static_cast<model::CanErrorType>(error)));
}

const char* role_name(uint8_t role) {
  return role == 0 ? "transmitter" : "receiver";
}

// "bit error as transmitter", "good frame", ...
std::string cause_text(const ipc::WireCounterSample& s) {
  switch (static_cast<ipc::WireCounterCause>(s.cause)) {
    case ipc::WireCounterCause::success:
      return "good frame";
    case ipc::WireCounterCause::error:
      return fmt::format("{} error as {}", error_name(s.error), role_name(s.role));
    case ipc::WireCounterCause::severe:
      return fmt::format("dominant bits after the error flag, as {}", role_name(s.role));
    case ipc::WireCounterCause::recovered:
      return "bus-off recovery ended";
    case ipc::WireCounterCause::written:
      return "counters written";
  }
  return "?";
}

double seconds(int64_t ns) {
  return static_cast<double>(ns) / 1e9;
}

void print_text(const Timeline& t) {
  std::printf("bus %s: load per %.1f s of simulated time, up to %.9f s\n", t.bus.c_str(),
              seconds(t.bin_ns), seconds(t.now_ns));
  // Runs of bins with the same load, one line each.
  for (std::size_t k = 0; k < t.busy_ns.size();) {
    std::size_t end = k + 1;
    while (end < t.busy_ns.size() && t.busy_ns[end] == t.busy_ns[k]) {
      ++end;
    }
    const int64_t from = t.start_ns + static_cast<int64_t>(k) * t.bin_ns;
    const int64_t to = t.start_ns + static_cast<int64_t>(end) * t.bin_ns;
    std::printf("  %14.3f .. %14.3f s  %6.2f %%\n", seconds(from), seconds(to),
                100.0 * t.busy_ns[k] / t.bin_ns);
    k = end;
  }
  for (const NodeTimeline& n : t.nodes) {
    std::printf(
        "node %s%s: %zu change%s of its error counters%s\n", n.name.c_str(),
        n.gone ? fmt::format(" (gone at {:.9f} s)", seconds(n.gone_at_ns)).c_str() : "",
        n.samples.size(), n.samples.size() == 1 ? "" : "s",
        n.forgotten > 0 ? fmt::format(" ({} older ones forgotten)", n.forgotten).c_str() : "");
    if (n.samples.empty()) {
      continue;
    }
    using Align = TextTable::Align;
    TextTable table({{"time (s)", Align::left, 20},
                     {"TEC", Align::right, 5},
                     {"REC", Align::right, 5},
                     {"state", Align::left, 0, 2},
                     {"cause"}},
                    "  ");
    for (const ipc::WireCounterSample& s : n.samples) {
      table.add({fmt::format("{:.9f}", seconds(s.at_ns)), std::to_string(s.tec),
                 std::to_string(s.rec), error_state_name(s.state), cause_text(s)});
    }
    table.print();
  }
}

toml::table to_json(const Timeline& t) {
  toml::array busy;
  for (uint32_t b : t.busy_ns) {
    busy.push_back(static_cast<int64_t>(b));
  }
  toml::array nodes;
  for (const NodeTimeline& n : t.nodes) {
    toml::array samples;
    for (const ipc::WireCounterSample& s : n.samples) {
      toml::table row{{"at_ns", s.at_ns},
                      {"tec", static_cast<int64_t>(s.tec)},
                      {"rec", static_cast<int64_t>(s.rec)},
                      {"state", error_state_name(s.state)},
                      {"cause", cause_name(s.cause)}};
      if (static_cast<ipc::WireCounterCause>(s.cause) == ipc::WireCounterCause::error) {
        row.insert("error", error_name(s.error));
      }
      if (static_cast<ipc::WireCounterCause>(s.cause) == ipc::WireCounterCause::error ||
          static_cast<ipc::WireCounterCause>(s.cause) == ipc::WireCounterCause::severe) {
        row.insert("role", role_name(s.role));
      }
      samples.push_back(std::move(row));
    }
    toml::table node{{"name", n.name},
                     {"forgotten", static_cast<int64_t>(n.forgotten)},
                     {"samples", std::move(samples)}};
    if (n.gone) {
      node.insert("gone_at_ns", n.gone_at_ns);
    }
    nodes.push_back(std::move(node));
  }
  return toml::table{{"bus", t.bus},
                     {"now_ns", t.now_ns},
                     {"load", toml::table{{"start_ns", t.start_ns},
                                          {"bin_ns", static_cast<int64_t>(t.bin_ns)},
                                          {"busy_ns", std::move(busy)}}},
                     {"nodes", std::move(nodes)}};
}

struct Options {
  std::string bus;
  std::vector<std::string> nodes;
  bool json = false;
  std::string output;
  std::string title;
};

// The timeline from canemud at `socket`, asked as client `name`; the error's text on failure.
tl::expected<Timeline, std::string> ask(const std::string& socket, const char* name,
                                        const Options& o) {
  auto c = connect(socket, name);
  if (!c) {
    return tl::unexpected(c.error().message);
  }
  return fetch(*c, o.bus, o.nodes);
}

int run_timeline(const std::string& socket, const Options& o) {
  auto t = ask(socket, "canemu timeline", o);
  if (!t) {
    return fail(t.error());
  }
  if (o.json) {
    std::fputs((one_line_json(to_json(*t)) + "\n").c_str(), stdout);
  } else {
    print_text(*t);
  }
  return 0;
}

// canemu.plot's exit status when it refused with a message of its own.
constexpr int kPlotRefused = 2;

// The timeline as JSON into `python3 -m canemu.plot` (python_interpreter() chooses which).
int run_plot(const std::string& socket, const Options& o) {
  auto t = ask(socket, "canemu plot", o);
  if (!t) {
    return fail(t.error());
  }
  std::vector<std::string> args{"--output", o.output};
  if (!o.title.empty()) {
    args.insert(args.end(), {"--title", o.title});
  }
  const PythonRun run =
      run_python_module("canemu.plot", args, one_line_json(to_json(*t)) + "\n", false);
  if (!run.error.empty()) {
    return fail(fmt::format("plot: cannot run {}: {} (CANEMU_PYTHON names the interpreter)",
                            run.interpreter, run.error));
  }
  if (run.status == kPlotRefused) {
    return 1;  // canemu.plot has said why: the format, the folder, matplotlib, the file
  }
  if (run.status != 0) {
    return fail(fmt::format(
        "plot: {} -m canemu.plot ended with status {} (is the canemu Python package installed "
        "for that interpreter? CANEMU_PYTHON names another)",
        run.interpreter, run.status));
  }
  return 0;
}

}  // namespace

Command add_timeline(CLI::App& app, const std::string& socket) {
  auto* cmd = app.add_subcommand("timeline",
                                 "a bus's load and its nodes' error counters over simulated time");
  auto o = std::make_shared<Options>();
  cmd->add_option("bus", o->bus, "the CAN bus")->required();
  cmd->add_option("nodes", o->nodes, "nodes (DEVICE:N); default: every node on the bus");
  cmd->add_flag("--json", o->json, "one JSON object instead of tables");
  return {cmd, [&socket, o] { return run_timeline(socket, *o); }};
}

Command add_plot(CLI::App& app, const std::string& socket) {
  auto* cmd = app.add_subcommand(
      "plot", "draw a bus's load and its nodes' TEC and REC over time (PNG, SVG or PDF)");
  auto o = std::make_shared<Options>();
  cmd->add_option("bus", o->bus, "the CAN bus")->required();
  cmd->add_option("nodes", o->nodes, "nodes (DEVICE:N); default: every node on the bus");
  cmd->add_option("-o,--output", o->output, "the picture: FILE.png, FILE.svg or FILE.pdf")
      ->required();
  cmd->add_option("--title", o->title, "the picture's title (default: the bus)");
  return {cmd, [&socket, o] { return run_plot(socket, *o); }};
}

}  // namespace canemu::cli
