// canemu metrics: canemud's counters in the Prometheus text exposition format (version 0.0.4),
// for a node exporter's textfile collector or any scraper that runs a command.
#include <cstdio>
#include <string>
#include <utility>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/firmware_model/bus/can_error.hpp"
#include "canemu/ipc/protocol.hpp"
#include "capture_table.hpp"
#include "command.hpp"
#include "fault_table.hpp"

namespace canemu::cli {

namespace {

// A label value as the format wants it: backslash, double quote and line feed escaped.
std::string label(std::string_view value) {
  std::string out;
  for (char c : value) {
    if (c == '\\' || c == '"') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

class Exposition {
 public:
  // Starts metric family `name` with its help text and type.
  void family(const char* name, const char* type, const char* help) {
    text_ += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, help, name, type);
  }
  template <typename V>
  void sample(const char* name, const std::string& labels, V value) {
    text_ += labels.empty() ? fmt::format("{} {}\n", name, value)
                            : fmt::format("{}{{{}}} {}\n", name, labels, value);
  }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

bool is_lin(const ipc::StatusNode& n) {
  return static_cast<ipc::WireLinState>(n.lin) != ipc::WireLinState::none;
}

// Recorders and bridges: what they wrote and every frame they lost (docs/socketcan.md,
// docs/bridges.md). An LCM bridge's "interface" is lcm:PREFIX, a DDS bridge's dds:PREFIX.
void expose_captures(Exposition& e, const std::vector<ipc::RecorderEntry>& recorders,
                     const std::vector<ipc::BridgeEntry>& bridges) {
  const auto recorder_label = [&](const ipc::RecorderEntry& r) {
    return fmt::format("bus=\"{}\",path=\"{}\"", label(ipc::name_of(r.bus)),
                       label(ipc::name_of(r.path)));
  };
  e.family("canemu_recorder_frames_total", "counter", "Frames a recorder wrote to disk.");
  for (const ipc::RecorderEntry& r : recorders) {
    e.sample("canemu_recorder_frames_total", recorder_label(r), r.frames);
  }
  e.family("canemu_recorder_lost_total", "counter", "Frames a recorder's failed writes lost.");
  for (const ipc::RecorderEntry& r : recorders) {
    e.sample("canemu_recorder_lost_total", recorder_label(r), r.lost);
  }
  const auto bridge_label = [&](const ipc::BridgeEntry& b, std::string_view key,
                                std::string_view value) {
    const std::string interface =
        b.kind == ipc::kBridgeLcm   ? "lcm:" + ipc::name_of(b.channel_prefix)
        : b.kind == ipc::kBridgeDds ? "dds:" + ipc::name_of(b.channel_prefix)
                                    : ipc::name_of(b.interface);
    return fmt::format("bus=\"{}\",interface=\"{}\",{}=\"{}\"", label(ipc::name_of(b.bus)),
                       label(interface), key, value);
  };
  e.family("canemu_bridge_frames_total", "counter", "Frames a bridge passed on.");
  for (const ipc::BridgeEntry& b : bridges) {
    e.sample("canemu_bridge_frames_total", bridge_label(b, "direction", "to_interface"),
             b.to_interface);
    e.sample("canemu_bridge_frames_total", bridge_label(b, "direction", "from_interface"),
             b.from_interface);
  }
  e.family("canemu_bridge_dropped_total", "counter", "Frames a bridge could not pass.");
  for (const ipc::BridgeEntry& b : bridges) {
    for (const auto& [reason, count] :
         {std::pair<const char*, uint64_t>{"interface", b.to_interface_dropped},
          {"kernel", b.kernel_dropped},
          {"queue", b.queue_dropped},
          {"rejected", b.rejected},
          {"tx_failed", b.tx_failed}}) {
      e.sample("canemu_bridge_dropped_total", bridge_label(b, "reason", reason), count);
    }
  }
}

// [distributed]: messages to and from other daemons, what was lost or late, whether each other
// daemon is up and each remote bus attached. Nothing without [distributed].
void expose_distributed(Exposition& e, const client::PeerList& d) {
  if (!d.enabled) {
    return;
  }
  const ipc::WireDistributedCounters& c = d.counters;
  e.family("canemu_distributed_requests_total", "counter",
           "Requests sent to owners of this daemon's remote buses, and received from daemons "
           "with nodes on its buses.");
  e.sample("canemu_distributed_requests_total", "direction=\"sent\"", c.requests_sent);
  e.sample("canemu_distributed_requests_total", "direction=\"received\"", c.requests_received);
  e.family("canemu_distributed_events_total", "counter",
           "Controller events sent to and received from other daemons.");
  e.sample("canemu_distributed_events_total", "direction=\"sent\"", c.events_sent);
  e.sample("canemu_distributed_events_total", "direction=\"received\"", c.events_received);
  e.family("canemu_distributed_dropped_total", "counter",
           "Messages between daemons lost on the way, not taken by DDS, or for no node.");
  e.sample("canemu_distributed_dropped_total", "", c.dropped);
  e.family("canemu_distributed_rejected_total", "counter",
           "Frames of another daemon's node that its controller does not send (CAN FD on a "
           "classic bus).");
  e.sample("canemu_distributed_rejected_total", "", c.rejected);
  e.family("canemu_distributed_late_total", "counter",
           "Events placed more than 1 ms after their instant (stepped time: any delay).");
  e.sample("canemu_distributed_late_total", "", c.late);
  e.family("canemu_peer_up", "gauge",
           "1 while another daemon is heard and accepted, 0 when it is gone or refused.");
  for (const ipc::PeerEntry& p : d.peers) {
    e.sample("canemu_peer_up", fmt::format("daemon=\"{}\"", label(ipc::printable_name_of(p.name))),
             ipc::name_of(p.state) == "up" ? 1 : 0);
  }
  e.family("canemu_remote_bus_attached", "gauge",
           "1 while this daemon's bus simulated by another daemon is attached to it.");
  for (const ipc::RemoteBusEntry& b : d.remote_buses) {
    e.sample("canemu_remote_bus_attached",
             fmt::format("bus=\"{}\",owner=\"{}\"", label(ipc::printable_name_of(b.bus)),
                         label(ipc::printable_name_of(b.owner))),
             ipc::name_of(b.state) == "attached" ? 1 : 0);
  }
}

std::string expose(const client::Status& s, const FaultList& faults,
                   const std::vector<ipc::RecorderEntry>& recorders,
                   const std::vector<ipc::BridgeEntry>& bridges, const client::PeerList& peers) {
  Exposition e;
  e.family("canemu_sim_time_seconds", "gauge", "Simulated time.");
  e.sample("canemu_sim_time_seconds", "",
           fmt::format("{:.9f}", static_cast<double>(s.sim_time_ns) / 1e9));
  e.family("canemu_clients", "gauge", "Connected clients.");
  e.sample("canemu_clients", "", s.client_count);
  e.family("canemu_sim_lag_seconds", "gauge",
           "How far simulated time is behind real or scaled time (0 while canemud keeps up).");
  e.sample("canemu_sim_lag_seconds", "",
           fmt::format("{:.9f}", static_cast<double>(s.lag_ns) / 1e9));
  e.family("canemu_sim_achieved_scale", "gauge",
           "Simulated seconds per real second over the last second (real and scaled time).");
  e.sample("canemu_sim_achieved_scale", "", fmt::format("{:.3f}", s.achieved_scale));
  // A summary: quantiles and the count of measurements (no sum: canemud keeps none).
  e.family("canemu_pacing_lateness_seconds", "summary",
           "Real and scaled time: how late canemud ran simulated events, woke for its timer "
           "deadlines and saw its timer fire (what: events, wakeups, timer), since start or over "
           "the last second (window), as quantiles 0.5, 0.99 and 1 (the max); 0 in stepped time.");
  const auto lateness = [&](const char* what, const char* window, const ipc::WirePacingFigures& f) {
    const std::pair<const char*, int64_t> quantiles[] = {
        {"0.5", f.p50_ns}, {"0.99", f.p99_ns}, {"1", f.max_ns}};
    for (const auto& [q, ns] : quantiles) {
      e.sample("canemu_pacing_lateness_seconds",
               fmt::format("what=\"{}\",window=\"{}\",quantile=\"{}\"", what, window, q),
               fmt::format("{:.9f}", static_cast<double>(ns) / 1e9));
    }
    e.sample("canemu_pacing_lateness_seconds_count",
             fmt::format("what=\"{}\",window=\"{}\"", what, window), f.count);
  };
  lateness("events", "start", s.pacing.events);
  lateness("events", "last_second", s.pacing.events_last);
  lateness("wakeups", "start", s.pacing.wakeups);
  lateness("wakeups", "last_second", s.pacing.wakeups_last);
  lateness("timer", "start", s.pacing.timer);
  lateness("timer", "last_second", s.pacing.timer_last);
  e.family("canemu_pacing_measured_total", "counter",
           "Events, timer wake-ups and timer firings whose lateness was measured since start.");
  e.sample("canemu_pacing_measured_total", "what=\"events\"", s.pacing.events.count);
  e.sample("canemu_pacing_measured_total", "what=\"wakeups\"", s.pacing.wakeups.count);
  e.sample("canemu_pacing_measured_total", "what=\"timer\"", s.pacing.timer.count);
  e.family("canemu_pacing_spin_seconds", "gauge",
           "How early the loop's timer is armed before a deadline (at most simulation.spin_us).");
  e.sample("canemu_pacing_spin_seconds", "",
           fmt::format("{:.9f}", static_cast<double>(s.pacing.spin_ns) / 1e9));
  e.family("canemu_ring_bytes", "gauge", "Shared ring memory the clients' channels hold.");
  e.sample("canemu_ring_bytes", "", s.ring_bytes);

  const auto bus_label = [&](std::size_t i) {
    return fmt::format("bus=\"{}\"", label(ipc::name_of(s.buses[i].name)));
  };
  e.family("canemu_bus_bitrate_bits_per_second", "gauge", "Nominal bit rate of the bus.");
  for (std::size_t i = 0; i < s.buses.size(); ++i) {
    const std::string kind(ipc::to_string(static_cast<ipc::WireBusKind>(s.buses[i].kind)));
    e.sample("canemu_bus_bitrate_bits_per_second",
             fmt::format("{},kind=\"{}\"", bus_label(i), label(kind)), s.buses[i].bitrate);
  }
  e.family("canemu_bus_load_ratio", "gauge", "Share of the last second the bus was busy.");
  for (std::size_t i = 0; i < s.buses.size(); ++i) {
    e.sample("canemu_bus_load_ratio", bus_label(i),
             fmt::format("{:.3f}", s.buses[i].load_permille / 1000.0));
  }
  e.family("canemu_bus_frames_total", "counter", "Frames the bus carried.");
  for (std::size_t i = 0; i < s.buses.size(); ++i) {
    e.sample("canemu_bus_frames_total", bus_label(i), s.buses[i].frames);
  }
  e.family("canemu_bus_error_frames_total", "counter", "Error frames on the bus.");
  for (std::size_t i = 0; i < s.buses.size(); ++i) {
    e.sample("canemu_bus_error_frames_total", bus_label(i), s.buses[i].error_frames);
  }

  const auto node_label = [&](const ipc::StatusNode& n) {
    return fmt::format("node=\"{}\",bus=\"{}\"", label(ipc::name_of(n.name)), label(s.bus_name(n)));
  };
  e.family("canemu_node_error_state", "gauge",
           "1 for the node's fault confinement state, 0 for the others.");
  for (const ipc::StatusNode& n : s.nodes) {
    if (is_lin(n)) {
      continue;  // LIN nodes have no fault confinement: canemu_lin_node_online
    }
    for (uint8_t st = 0; st <= static_cast<uint8_t>(model::ErrorState::bus_off); ++st) {
      e.sample("canemu_node_error_state",
               fmt::format("{},state=\"{}\"", node_label(n),
                           model::to_string(static_cast<model::ErrorState>(st))),
               n.state == st ? 1 : 0);
    }
  }
  e.family("canemu_node_started", "gauge",
           "1 while a CAN node's controller takes part in bus traffic, 0 in its init mode.");
  for (const ipc::StatusNode& n : s.nodes) {
    if (!is_lin(n)) {
      e.sample("canemu_node_started", node_label(n),
               static_cast<ipc::WireNodeMode>(n.mode) == ipc::WireNodeMode::running ? 1 : 0);
    }
  }
  e.family("canemu_lin_node_online", "gauge", "1 while a LIN node takes part in the bus.");
  for (const ipc::StatusNode& n : s.nodes) {
    if (is_lin(n)) {
      e.sample("canemu_lin_node_online", node_label(n),
               static_cast<ipc::WireLinState>(n.lin) == ipc::WireLinState::online ? 1 : 0);
    }
  }
  // The per-node counters: one family each.
  struct NodeCounter {
    const char* name;
    const char* type;
    const char* help;
    uint64_t (*value)(const ipc::StatusNode&);
  };
  static constexpr NodeCounter kNodeCounters[] = {
      {"canemu_node_tec", "gauge", "Transmit error counter.",
       [](const ipc::StatusNode& n) -> uint64_t { return n.tec; }},
      {"canemu_node_rec", "gauge", "Receive error counter.",
       [](const ipc::StatusNode& n) -> uint64_t { return n.rec; }},
      {"canemu_node_frames_sent_total", "counter", "Frames the node sent.",
       [](const ipc::StatusNode& n) -> uint64_t { return n.frames_sent; }},
      {"canemu_node_frames_received_total", "counter", "Frames the node received.",
       [](const ipc::StatusNode& n) -> uint64_t { return n.frames_received; }},
      {"canemu_node_errors_total", "counter", "Errors the node detected or caused.",
       [](const ipc::StatusNode& n) -> uint64_t { return n.errors; }},
  };
  for (const NodeCounter& counter : kNodeCounters) {
    e.family(counter.name, counter.type, counter.help);
    for (const ipc::StatusNode& n : s.nodes) {
      e.sample(counter.name, node_label(n), counter.value(n));
    }
  }

  e.family("canemu_fault_hits_total", "counter",
           "Frames a fault hit, or times a timed fault fired.");
  for (const ipc::FaultEntry& f : faults) {
    e.sample("canemu_fault_hits_total",
             fmt::format("scenario=\"{}\",line=\"{}\",effect=\"{}\",target=\"{}\"",
                         label(ipc::name_of(f.scenario)), f.line, label(ipc::name_of(f.effect)),
                         label(ipc::name_of(f.target))),
             f.hits);
  }
  expose_captures(e, recorders, bridges);
  expose_distributed(e, peers);
  return e.text();
}

int run_metrics(const std::string& socket) {
  auto c = connect(socket, "canemu metrics");
  if (!c) {
    return fail(c.error().message);
  }
  auto status = client::fetch_status(*c);
  if (!status) {
    return fail(status.error().message);
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
  std::fputs(expose(*status, *faults, captures->recorders, captures->bridges, *peers).c_str(),
             stdout);
  return 0;
}

}  // namespace

Command add_metrics(CLI::App& app, const std::string& socket) {
  auto* metrics = app.add_subcommand("metrics", "canemud's counters in the Prometheus text format");
  return {metrics, [&socket] { return run_metrics(socket); }};
}

}  // namespace canemu::cli
