// A configuration read again (SIGHUP): what may change while canemud runs is applied, the
// rest is refused with the reason, each in the reload's report.
#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon {

using namespace canemu::model;

namespace {

bool same(const BusConfig& a, const BusConfig& b) {
  return a.name == b.name && a.kind == b.kind && a.bitrate == b.bitrate &&
         a.sample_point == b.sample_point && a.data_bitrate == b.data_bitrate && a.owner == b.owner;
}

bool same(const DistributedConfig& a, const DistributedConfig& b) {
  return a.enabled == b.enabled && a.name == b.name && a.domain == b.domain &&
         a.partition == b.partition && a.heartbeat_ms == b.heartbeat_ms &&
         a.timeout_ms == b.timeout_ms && a.local_link == b.local_link;
}

bool same(const DeviceConfig& a, const DeviceConfig& b) {
  return a.name == b.name && a.model == b.model && a.controllers == b.controllers &&
         a.lin == b.lin && a.mdd_version == b.mdd_version && a.buffer_load_ns == b.buffer_load_ns &&
         a.slot == b.slot && a.eeprom == b.eeprom;
}

bool same(const std::vector<RecorderConfig>& a, const std::vector<RecorderConfig>& b) {
  const auto key = [](const RecorderConfig& r) {
    return std::tie(r.bus, r.path, r.pcap, r.max_size, r.max_files, r.errors);
  };
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [&](const auto& x, const auto& y) { return key(x) == key(y); });
}

template <class T>
const T* find_named(const std::vector<T>& items, const std::string& name) {
  for (const T& item : items) {
    if (item.name == name) {
      return &item;
    }
  }
  return nullptr;
}

}  // namespace

ReloadReport Simulation::reload(const Config& fresh) {
  ReloadReport r;
  // What cannot change while the simulation runs.
  if (fresh.simulation.time.mode != config_.simulation.time.mode ||
      fresh.simulation.time.scale != config_.simulation.time.scale) {
    r.refused.push_back(fmt::format("simulation.time: stays {} (a restart changes it)",
                                    to_string(config_.simulation.time)));
  }
  if (fresh.simulation.seed != config_.simulation.seed) {
    r.refused.push_back(
        fmt::format("simulation.seed: stays {} (a restart changes it)", config_.simulation.seed));
  }
  if (!same(fresh.distributed, config_.distributed)) {
    r.refused.push_back("distributed: stays as it was (a restart changes it)");
  }
  for (const BusConfig& old : config_.buses) {
    const BusConfig* now = find_named(fresh.buses, old.name);
    if (now == nullptr) {
      r.refused.push_back(
          fmt::format("bus {}: still there (buses are removed by a restart)", old.name));
    } else if (!same(old, *now)) {
      r.refused.push_back(
          fmt::format("bus {}: keeps its settings ({} at {} bit/s; a restart changes them)",
                      old.name, to_string(old.kind), old.bitrate));
    }
  }
  for (const DeviceConfig& old : config_.devices) {
    const DeviceConfig* now = find_named(fresh.devices, old.name);
    if (now == nullptr) {
      r.refused.push_back(
          fmt::format("device {}: still there (devices are removed by a restart)", old.name));
    } else if (!same(old, *now)) {
      r.refused.push_back(
          fmt::format("device {}: keeps its settings (a restart changes them)", old.name));
    }
  }
  const auto bridge_key = [](const BridgeConfig& b) {
    return std::tie(b.kind, b.bus, b.interface, b.error_frames, b.restart_ms, b.url,
                    b.channel_prefix);
  };
  if (!std::equal(fresh.bridges.begin(), fresh.bridges.end(), config_.bridges.begin(),
                  config_.bridges.end(),
                  [&](const auto& x, const auto& y) { return bridge_key(x) == bridge_key(y); })) {
    r.refused.push_back(
        "bridges: stay as they are (canemu bridge add|remove changes them while running)");
  }
  if (!same(fresh.recorders, config_.recorders)) {
    r.refused.push_back("recorders: stay as they are (a restart changes them)");
  }
  // What can: new buses and devices, the security lists, the wake-up tuning.
  for (const BusConfig& b : fresh.buses) {
    if (find_named(config_.buses, b.name) == nullptr) {
      if (!b.owner.empty() && b.owner != config_.distributed.name && !config_.distributed.enabled) {
        r.refused.push_back(fmt::format(
            "bus {}: not added (daemon {} simulates it, and [distributed] needs a restart)", b.name,
            b.owner));
        continue;
      }
      if (config_.remote(b) && config_.simulation.time.mode == TimeMode::stepped) {
        r.refused.push_back(fmt::format(
            "bus {}: not added (in stepped time the remote buses, whose owner's steps are this "
            "daemon's, are set at start)",
            b.name));
        continue;
      }
      config_.buses.push_back(b);
      add_bus(b);
      r.applied.push_back(
          fmt::format("bus {}: added ({} at {} bit/s)", b.name, to_string(b.kind), b.bitrate));
    }
  }
  for (const DeviceConfig& d : fresh.devices) {
    if (find_named(config_.devices, d.name) != nullptr) {
      continue;
    }
    if (devices_.exists(d.name)) {
      r.refused.push_back(fmt::format("device {}: an ephemeral device has that name", d.name));
    } else if (auto added = add_device(d); !added) {
      r.refused.push_back(added.error().what());
    } else {
      config_.devices.push_back(d);
      devices_.announce(ipc::NotificationKind::device_added, d.name);
      r.applied.push_back(fmt::format("device {}: added", d.name));
    }
  }
  const bool same_lin_nodes =
      fresh.lin_nodes.size() == config_.lin_nodes.size() &&
      std::equal(fresh.lin_nodes.begin(), fresh.lin_nodes.end(), config_.lin_nodes.begin(),
                 [](const LinNodeConfig& a, const LinNodeConfig& b) { return a.same_as(b); });
  if (!same_lin_nodes) {
    r.refused.push_back(
        "lin_node: the simulated LIN nodes stay as they are (a restart changes them)");
  }
  const bool same_can_nodes =
      fresh.can_nodes.size() == config_.can_nodes.size() &&
      std::equal(fresh.can_nodes.begin(), fresh.can_nodes.end(), config_.can_nodes.begin(),
                 [](const CanNodeConfig& a, const CanNodeConfig& b) { return a.same_as(b); });
  if (!same_can_nodes) {
    r.refused.push_back(
        "can_node: the simulated CAN nodes stay as they are (a restart changes them)");
  }
  if (fresh.security.allowed_users != config_.security.allowed_users ||
      fresh.security.allowed_groups != config_.security.allowed_groups) {
    config_.security = fresh.security;
    r.applied.push_back("security: allowed users and groups replaced");
  }
  if (fresh.simulation.batch_us != config_.simulation.batch_us ||
      fresh.simulation.batch_max_us != config_.simulation.batch_max_us ||
      fresh.simulation.spin_us != config_.simulation.spin_us) {
    config_.simulation.batch_us = fresh.simulation.batch_us;
    config_.simulation.batch_max_us = fresh.simulation.batch_max_us;
    config_.simulation.spin_us = fresh.simulation.spin_us;
    r.applied.push_back(fmt::format("simulation: batch_us {}, batch_max_us {}, spin_us {}",
                                    config_.simulation.batch_us, config_.simulation.batch_max_us,
                                    config_.simulation.spin_us));
  }
  if (fresh.simulation.cpu_latency_us != config_.simulation.cpu_latency_us) {
    config_.simulation.cpu_latency_us = fresh.simulation.cpu_latency_us;
    const auto& bound = config_.simulation.cpu_latency_us;
    r.applied.push_back(bound ? fmt::format("simulation: cpu_latency_us {}", *bound)
                              : std::string("simulation: cpu_latency_us removed"));
  }
  return r;
}

}  // namespace canemu::daemon
