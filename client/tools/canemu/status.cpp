// canemu status: buses with load, nodes with state and counters, devices, clients, faults,
// recorders, bridges and, with [distributed], the other daemons and the buses they simulate for
// this one, as tables or as one JSON object.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/ipc/protocol.hpp"
#include "capture_table.hpp"
#include "command.hpp"
#include "fault_table.hpp"
#include "text_table.hpp"

namespace canemu::cli {

namespace {

// A CAN node's error state, or "init" while its controller takes no part in bus traffic (not
// started; bus-off, which also stops an SJA1000, stays bus-off); a LIN controller's "online" or
// "offline".
std::string state_name(const ipc::StatusNode& n) {
  switch (static_cast<ipc::WireLinState>(n.lin)) {
    case ipc::WireLinState::none:
      break;
    case ipc::WireLinState::offline:
      return "offline";
    case ipc::WireLinState::online:
      return "online";
  }
  if (static_cast<ipc::WireNodeMode>(n.mode) == ipc::WireNodeMode::init &&
      static_cast<ipc::WireErrorState>(n.state) != ipc::WireErrorState::bus_off) {
    return "init";
  }
  return error_state_name(n.state);
}
std::string kind_name(uint8_t kind) {
  return std::string(ipc::to_string(static_cast<ipc::WireBusKind>(kind)));
}
std::string model_name(uint8_t model) {
  return std::string(ipc::to_string(static_cast<ipc::WireDeviceModel>(model)));
}

// A lateness: microseconds below a millisecond, then milliseconds.
std::string duration_text(int64_t ns) {
  if (ns < 1'000'000) {
    return fmt::format("{:.1f} us", static_cast<double>(ns) / 1e3);
  }
  return fmt::format("{:.2f} ms", static_cast<double>(ns) / 1e6);
}

// One window's events and wake-ups: "N events late p50 .., p99 .., max ..; wake-ups late
// p99 .., max .." or "no events".
std::string pacing_text(const ipc::WirePacingFigures& events,
                        const ipc::WirePacingFigures& wakeups) {
  if (events.count == 0) {
    return "no events";
  }
  return fmt::format("{} event{} late p50 {}, p99 {}, max {}; wake-ups late p99 {}, max {}",
                     events.count, events.count == 1 ? "" : "s", duration_text(events.p50_ns),
                     duration_text(events.p99_ns), duration_text(events.max_ns),
                     duration_text(wakeups.p99_ns), duration_text(wakeups.max_ns));
}

// Real and scaled time: how late events, wake-ups and the timer were (docs/daemon.md, "Pacing").
void print_pacing(const ipc::WirePacing& p) {
  std::printf("pacing, last second: %s; timer late p99 %s, spin %s (at most %s)\n",
              pacing_text(p.events_last, p.wakeups_last).c_str(),
              duration_text(p.timer_last.p99_ns).c_str(), duration_text(p.spin_ns).c_str(),
              duration_text(p.max_spin_ns).c_str());
  std::printf("pacing since start: %s\n", pacing_text(p.events, p.wakeups).c_str());
}

toml::table pacing_json(const ipc::WirePacing& p) {
  const auto figures = [](const ipc::WirePacingFigures& f) {
    return toml::table{{"count", static_cast<int64_t>(f.count)},
                       {"p50_ns", f.p50_ns},
                       {"p99_ns", f.p99_ns},
                       {"max_ns", f.max_ns}};
  };
  return toml::table{
      {"events", figures(p.events)},   {"events_last_second", figures(p.events_last)},
      {"wakeups", figures(p.wakeups)}, {"wakeups_last_second", figures(p.wakeups_last)},
      {"timer", figures(p.timer)},     {"timer_last_second", figures(p.timer_last)},
      {"spin_ns", p.spin_ns},          {"max_spin_ns", p.max_spin_ns}};
}

std::vector<std::string> device_buses(const ipc::DeviceEntry& d) {
  std::vector<std::string> buses;
  for (uint8_t k = 0; k < d.controller_count && k < ipc::kMaxDeviceControllers; ++k) {
    buses.push_back(ipc::name_of(d.buses[k]));
  }
  return buses;
}

// The bus names a peer listed, and how many more it simulates.
std::vector<std::string> peer_buses(const ipc::PeerEntry& p) {
  std::vector<std::string> buses;
  for (uint8_t k = 0; k < p.bus_count && k < ipc::kPeerBuses; ++k) {
    buses.push_back(ipc::printable_name_of(p.buses[k]));
  }
  return buses;
}
std::size_t more_buses(const ipc::PeerEntry& p) {
  const std::size_t listed = std::min<std::size_t>(p.bus_count, ipc::kPeerBuses);
  return p.bus_total > listed ? p.bus_total - listed : 0;
}

// "distributed" of the JSON: this daemon's place in the installation, its counters, the other
// daemons and its buses they simulate.
toml::table distributed_json(const client::PeerList& d) {
  const auto i64 = [](uint64_t v) { return static_cast<int64_t>(v); };
  toml::array peers;
  for (const ipc::PeerEntry& p : d.peers) {
    toml::array buses;
    for (const std::string& b : peer_buses(p)) {
      buses.push_back(b);
    }
    peers.push_back(toml::table{{"name", ipc::printable_name_of(p.name)},
                                {"version", ipc::printable_name_of(p.version)},
                                {"protocol", i64(p.protocol)},
                                {"state", ipc::printable_name_of(p.state)},
                                {"reason", ipc::printable_name_of(p.reason)},
                                {"time", ipc::printable_name_of(p.time)},
                                {"last_heard_ms", p.last_heard_ms},
                                {"buses", std::move(buses)},
                                {"bus_total", i64(p.bus_total)},
                                {"hosted_nodes", i64(p.hosted_nodes)},
                                {"via", p.linked != 0 ? "link" : "dds"}});
  }
  toml::array remote;
  for (const ipc::RemoteBusEntry& b : d.remote_buses) {
    remote.push_back(toml::table{{"bus", ipc::printable_name_of(b.bus)},
                                 {"owner", ipc::printable_name_of(b.owner)},
                                 {"state", ipc::printable_name_of(b.state)},
                                 {"reason", ipc::printable_name_of(b.reason)},
                                 {"nodes", i64(b.nodes)}});
  }
  const ipc::WireDistributedCounters& c = d.counters;
  toml::table by_reason;
  for (std::size_t k = 0; k < ipc::kNetDropReasons; ++k) {
    by_reason.insert(ipc::kNetDropNames[k], i64(c.by_reason[k]));
  }
  return toml::table{
      {"name", d.name},
      {"domain", i64(d.domain)},
      {"partition", d.partition},
      {"heartbeat_ms", i64(d.heartbeat_ms)},
      {"timeout_ms", i64(d.timeout_ms)},
      {"counters", toml::table{{"requests_sent", i64(c.requests_sent)},
                               {"requests_received", i64(c.requests_received)},
                               {"events_sent", i64(c.events_sent)},
                               {"events_received", i64(c.events_received)},
                               {"dropped", i64(c.dropped)},
                               {"rejected", i64(c.rejected)},
                               {"by_reason", std::move(by_reason)},
                               {"last_reason", ipc::printable_name_of(c.last_reason)},
                               {"late", i64(c.late)},
                               {"late_bound_ns", i64(c.late_bound_ns)},
                               {"late_max_ns", i64(c.late_max_ns)}}},
      {"peers", std::move(peers)},
      {"remote_buses", std::move(remote)}};
}

// One table row, without the blanks a last empty column leaves.
void print_row(std::string row) {
  row.erase(row.find_last_not_of(' ') + 1);
  std::puts(row.c_str());
}

// With [distributed]: a line of this daemon's place and counters, a DAEMON table of the other
// daemons, and a REMOTE BUS table of its buses they simulate (when it has any).
void print_distributed(const client::PeerList& d) {
  const ipc::WireDistributedCounters& c = d.counters;
  // late: beyond the bound in real and scaled time (any delay in stepped time), and the largest
  // delay seen.
  const std::string late =
      c.late_bound_ns > 0 ? fmt::format("late (> {}) {}, max {}", duration_text(c.late_bound_ns),
                                        c.late, duration_text(c.late_max_ns))
                          : fmt::format("late {}", c.late);
  std::puts(fmt::format("daemon {}, DDS domain {}, partition {}: requests sent {}, received {}; "
                        "events sent {}, received {}; dropped {}, rejected {}, {}",
                        d.name, d.domain, d.partition, c.requests_sent, c.requests_received,
                        c.events_sent, c.events_received, c.dropped, c.rejected, late)
                .c_str());
  if (const std::string last = ipc::printable_name_of(c.last_reason); !last.empty()) {
    std::puts(fmt::format("last dropped or rejected: {}", last).c_str());
  }
  const char* peer_row = "{:<14} {:<8} {:<5} {:<12} {:<12} {:>10} {:>6} {:<24} {}";
  print_row(fmt::format(fmt::runtime(peer_row), "DAEMON", "STATE", "VIA", "VERSION", "TIME",
                        "HEARD", "HOSTED", "BUSES", "REASON"));
  for (const ipc::PeerEntry& p : d.peers) {
    std::string buses;
    for (const std::string& b : peer_buses(p)) {
      buses += (buses.empty() ? "" : ",") + b;
    }
    if (const std::size_t more = more_buses(p); more > 0) {
      buses += fmt::format(",+{}", more);
    }
    print_row(fmt::format(fmt::runtime(peer_row), ipc::printable_name_of(p.name),
                          ipc::printable_name_of(p.state), p.linked != 0 ? "link" : "dds",
                          ipc::printable_name_of(p.version), ipc::printable_name_of(p.time),
                          fmt::format("{:.1f} s", static_cast<double>(p.last_heard_ms) / 1e3),
                          p.hosted_nodes, buses.empty() ? "-" : buses,
                          ipc::printable_name_of(p.reason)));
  }
  if (d.remote_buses.empty()) {
    return;
  }
  const char* bus_row = "{:<12} {:<14} {:<8} {:>6} {}";
  print_row(fmt::format(fmt::runtime(bus_row), "REMOTE BUS", "OWNER", "STATE", "NODES", "REASON"));
  for (const ipc::RemoteBusEntry& b : d.remote_buses) {
    print_row(fmt::format(fmt::runtime(bus_row), ipc::printable_name_of(b.bus),
                          ipc::printable_name_of(b.owner), ipc::printable_name_of(b.state), b.nodes,
                          ipc::printable_name_of(b.reason)));
  }
}

// toml++ writes the JSON (names escaped as JSON wants them), one line. "distributed" is there
// only when the daemon has [distributed] (TOML, and so toml++, has no null).
void print_json(const client::Connection& c, const client::Status& s, const std::string& mode,
                const client::DeviceList& devices, const std::vector<ipc::ClientEntry>& clients,
                const FaultList& faults, const std::vector<ipc::RecorderEntry>& recorders,
                const std::vector<ipc::BridgeEntry>& bridges, const client::PeerList& peers) {
  const auto i64 = [](uint64_t v) { return static_cast<int64_t>(v); };
  toml::array buses;
  for (const ipc::StatusBus& b : s.buses) {
    buses.push_back(toml::table{{"name", ipc::name_of(b.name)},
                                {"kind", kind_name(b.kind)},
                                {"transceiver", b.low_speed ? "low-speed" : "high-speed"},
                                {"bitrate", i64(b.bitrate)},
                                {"data_bitrate", i64(b.data_bitrate)},
                                {"load_percent", b.load_permille / 10.0},
                                {"frames", i64(b.frames)},
                                {"error_frames", i64(b.error_frames)}});
  }
  toml::array nodes;
  for (const ipc::StatusNode& n : s.nodes) {
    nodes.push_back(toml::table{{"name", ipc::name_of(n.name)},
                                {"bus", s.bus_name(n)},
                                {"state", state_name(n)},
                                {"tec", i64(n.tec)},
                                {"rec", i64(n.rec)},
                                {"frames_sent", i64(n.frames_sent)},
                                {"frames_received", i64(n.frames_received)},
                                {"errors", i64(n.errors)}});
  }
  toml::array device_list;
  for (const ipc::DeviceEntry& d : devices.devices) {
    // Controller (interface) N is the node NAME:N on the N-th bus.
    toml::array device_buses_json;
    toml::array device_nodes_json;
    const std::vector<std::string> on = device_buses(d);
    for (std::size_t k = 0; k < on.size(); ++k) {
      device_buses_json.push_back(on[k]);
      device_nodes_json.push_back(fmt::format("{}:{}", ipc::name_of(d.name), k));
    }
    device_list.push_back(toml::table{{"name", ipc::name_of(d.name)},
                                      {"model", model_name(d.model)},
                                      {"ephemeral", d.ephemeral != 0},
                                      {"owner_pid", i64(d.owner_pid)},
                                      {"buses", std::move(device_buses_json)},
                                      {"nodes", std::move(device_nodes_json)}});
  }
  toml::array client_list;
  for (const ipc::ClientEntry& e : clients) {
    client_list.push_back(toml::table{{"name", ipc::name_of(e.name)},
                                      {"pid", i64(e.pid)},
                                      {"uid", i64(e.uid)},
                                      {"channels", i64(e.channels)}});
  }
  toml::table all{{"server_pid", i64(c.server_pid())},
                  {"time_mode", mode},
                  {"time_scale", s.time_scale},
                  {"sim_time_ns", s.sim_time_ns},
                  {"clients", i64(s.client_count)},
                  {"ring_bytes", i64(s.ring_bytes)},
                  {"lag_ns", s.lag_ns},
                  {"achieved_scale", s.achieved_scale},
                  {"pacing", pacing_json(s.pacing)},
                  {"buses", std::move(buses)},
                  {"nodes", std::move(nodes)},
                  {"devices", std::move(device_list)},
                  {"client_list", std::move(client_list)},
                  {"faults", faults_array(faults)},
                  {"recorders", recorders_array(recorders)},
                  {"bridges", bridges_array(bridges)}};
  if (peers.enabled) {
    all.insert("distributed", distributed_json(peers));
  }
  std::fputs((one_line_json(all) + "\n").c_str(), stdout);
}

void print_tables(const client::Connection& c, const client::Status& s, const std::string& mode,
                  const client::DeviceList& devices, const std::vector<ipc::ClientEntry>& clients,
                  const FaultList& faults, const std::vector<ipc::RecorderEntry>& recorders,
                  const std::vector<ipc::BridgeEntry>& bridges, const client::PeerList& peers) {
  std::printf("canemud pid %u, time %s, simulated %.9f s, %u client%s\n", c.server_pid(),
              mode.c_str(), static_cast<double>(s.sim_time_ns) / 1e9, s.client_count,
              s.client_count == 1 ? "" : "s");
  if (s.lag_ns >= 1'000'000) {  // a millisecond or more: the simulation does not keep up
    std::printf("simulated time lags %.3f s behind (achieved %.1f x real time)\n",
                static_cast<double>(s.lag_ns) / 1e9, s.achieved_scale);
  }
  if (static_cast<ipc::WireTimeMode>(s.time_mode) != ipc::WireTimeMode::stepped) {
    print_pacing(s.pacing);
  }
  using Align = TextTable::Align;
  const auto n = [](uint64_t v) { return std::to_string(v); };
  TextTable bus_table({{"BUS", Align::left, 12},
                       {"KIND", Align::left, 7},
                       {"BITRATE", Align::right, 9},
                       {"DATA", Align::right, 9},
                       {"LOAD", Align::right, 7},
                       {"FRAMES", Align::right, 10},
                       {"ERRORS", Align::right, 8}});
  for (const ipc::StatusBus& b : s.buses) {
    bus_table.add({ipc::name_of(b.name), kind_name(b.kind) + (b.low_speed ? "-ls" : ""),
                   n(b.bitrate), n(b.data_bitrate), fmt::format("{:.1f}%", b.load_permille / 10.0),
                   n(b.frames), n(b.error_frames)});
  }
  bus_table.print();
  TextTable node_table({{"NODE", Align::left, 14},
                        {"BUS", Align::left, 12},
                        {"STATE", Align::left, 14},
                        {"TEC", Align::right, 4},
                        {"REC", Align::right, 4},
                        {"SENT", Align::right, 10},
                        {"RECEIVED", Align::right, 10},
                        {"ERRORS", Align::right, 8}});
  for (const ipc::StatusNode& node : s.nodes) {
    node_table.add({ipc::name_of(node.name), s.bus_name(node), state_name(node), n(node.tec),
                    n(node.rec), n(node.frames_sent), n(node.frames_received), n(node.errors)});
  }
  node_table.print();
  TextTable device_table({{"DEVICE", Align::left, 14},
                          {"MODEL", Align::left, 20},
                          {"OWNER", Align::left, 8},
                          {"BUSES"}});
  for (const ipc::DeviceEntry& d : devices.devices) {
    std::string buses;
    for (const std::string& b : device_buses(d)) {
      buses += (buses.empty() ? "" : " ") + b;
    }
    device_table.add({ipc::name_of(d.name), model_name(d.model),
                      d.ephemeral ? std::to_string(d.owner_pid) : "config", buses});
  }
  device_table.print();
  TextTable client_table({{"CLIENT", Align::left, 20},
                          {"PID", Align::right, 8},
                          {"UID", Align::right, 8},
                          {"CHANNELS", Align::right, 8}});
  for (const ipc::ClientEntry& e : clients) {
    client_table.add({ipc::name_of(e.name), n(e.pid), n(e.uid), n(e.channels)});
  }
  client_table.print();
  if (!faults.empty()) {
    print_faults(faults);
  }
  if (!recorders.empty()) {
    print_recorders(recorders);
  }
  if (!bridges.empty()) {
    print_bridges(bridges);
  }
  if (peers.enabled) {
    print_distributed(peers);
  }
}

int run_status(const std::string& socket, bool json) {
  auto c = connect(socket, "canemu status");
  if (!c) {
    return fail(c.error().message);
  }
  auto reply = client::fetch_status(*c);
  if (!reply) {
    return fail(reply.error().message);
  }
  auto devices = client::fetch_device_list(*c);
  auto clients = client::fetch_client_list(*c);
  if (!devices || !clients) {
    return fail(!devices ? devices.error().message : clients.error().message);
  }
  auto faults = fault_list(*c);
  if (!faults) {
    return fail(faults.error());
  }
  auto captures = capture_lists(*c);
  if (!captures) {
    return fail(captures.error());
  }
  auto peers = client::fetch_peer_list(*c);
  if (!peers) {
    return fail(peers.error().message);
  }
  const std::string mode(ipc::to_string(static_cast<ipc::WireTimeMode>(reply->time_mode)));
  if (json) {
    print_json(*c, *reply, mode, *devices, *clients, *faults, captures->recorders,
               captures->bridges, *peers);
  } else {
    print_tables(*c, *reply, mode, *devices, *clients, *faults, captures->recorders,
                 captures->bridges, *peers);
  }
  return 0;
}

}  // namespace

Command add_status(CLI::App& app, const std::string& socket) {
  auto* status = app.add_subcommand("status", "buses with load, nodes with state and counters");
  auto json = std::make_shared<bool>(false);
  status->add_flag("--json", *json, "one JSON object instead of tables");
  return {status, [&socket, json] { return run_status(socket, *json); }};
}

}  // namespace canemu::cli
