// The configuration in a few lines, as canemud logs it at start and `canemud --check` prints it.
#include <fmt/format.h>

#include "canemu/daemon/config/config.hpp"

namespace canemu::daemon {

std::string summary(const Config& cfg) {
  std::string s = fmt::format("config {}: time {}, seed {}\n", cfg.source,
                              to_string(cfg.simulation.time), cfg.simulation.seed);
  if (cfg.distributed.enabled) {
    s += fmt::format("  daemon {} in DDS domain {}, partition \"{}\"\n", cfg.distributed.name,
                     cfg.distributed.domain, cfg.distributed.partition);
  }
  for (const BusConfig& b : cfg.buses) {
    s += fmt::format("  bus {} ({}, {} bit/s", b.name, to_string(b.kind), b.bitrate);
    if (b.data_bitrate != 0) {
      s += fmt::format(", data {} bit/s", b.data_bitrate);
    }
    if (b.kind == BusKind::lin) {
      s += ")\n";  // a LIN node samples each bit once, in its middle
      continue;
    }
    s += fmt::format(", sample point {:.1f} %{}{})\n", b.sample_point / 10.0,
                     b.low_speed ? ", low-speed transceivers" : "",
                     cfg.remote(b) ? fmt::format(", simulated by daemon {}", b.owner) : "");
  }
  for (const DeviceConfig& d : cfg.devices) {
    s += fmt::format("  device {} ({}):", d.name, to_string(d.model));
    for (std::size_t i = 0; i < d.controllers.size(); ++i) {
      s += fmt::format(" {}:{} on {}", d.name, i, d.controllers[i]);
    }
    for (std::size_t i = 0; i < d.lin.size(); ++i) {
      s += fmt::format(" {}:{} on {} (LIN)", d.name, d.controllers.size() + i, d.lin[i]);
    }
    s += "\n";
  }
  for (const RecorderConfig& r : cfg.recorders) {
    s += fmt::format("  recorder of {} into {} ({})\n", r.bus, r.path, r.pcap ? "pcap" : "candump");
  }
  for (const BridgeConfig& b : cfg.bridges) {
    if (b.kind == "lcm") {
      s += fmt::format(
          "  bridge lcm of {} to {}*, {}{}\n", b.bus, b.channel_prefix, b.url,
          b.restart_ms != 0 ? fmt::format(", restart {} ms after bus-off", b.restart_ms) : "");
      continue;
    }
    if (b.kind == "dds") {
      s += fmt::format(
          "  bridge dds of {} to {}* in domain {}, partition {}{}{}\n", b.bus, b.channel_prefix,
          b.domain, b.partition, b.ros2 ? ", ROS 2 topics too" : "",
          b.restart_ms != 0 ? fmt::format(", restart {} ms after bus-off", b.restart_ms) : "");
      continue;
    }
    s += fmt::format(
        "  bridge {} of {} to {}{}{}\n", b.kind, b.bus, b.interface,
        b.error_frames ? " (error frames too)" : "",
        b.restart_ms != 0 ? fmt::format(", restart {} ms after bus-off", b.restart_ms) : "");
  }
  for (const LinNodeConfig& n : cfg.lin_nodes) {
    s += fmt::format("  lin node {} on {} ({}{})\n", n.name, n.bus,
                     n.schedule.empty() ? "responder" : "commander, schedule " + n.schedule,
                     n.powered ? "" : ", switched off");
  }
  for (const CanNodeConfig& n : cfg.can_nodes) {
    s += fmt::format("  can node {} on {} ({} message{}{})\n", n.name, n.bus, n.messages.size(),
                     n.messages.size() == 1 ? "" : "s", n.powered ? "" : ", switched off");
  }
  return s;
}

}  // namespace canemu::daemon
