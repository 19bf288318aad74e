// The world's simulated LIN nodes by name ("NODE" or "BUS/NODE"): loaded, switched on and off,
// put on a schedule and removed at run time (`canemu lin`, fault scenarios).
#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "world/named_nodes.hpp"

namespace canemu::daemon {

using namespace canemu::model;

std::optional<ScenarioRunner::LinNodeRef> Simulation::find_lin_node(std::string_view name) const {
  for (const DeviceRegistry::Configured& d : devices_.configured()) {
    for (const DeviceRegistry::LinController& c : d.lin) {
      if (c.name == name) {
        return ScenarioRunner::LinNodeRef{c.bus, c.line->controller().node()};
      }
    }
  }
  for (const DeviceRegistry::LinEphemeral& e : devices_.lin_ephemeral()) {
    if (e.name == name || e.name + ":0" == name) {
      return ScenarioRunner::LinNodeRef{e.bus, e.line->controller().node()};
    }
  }
  // Simulated nodes: "BUS/NAME", or a NAME only one bus has.
  const auto [bus, node] = split_node_name(name);
  std::optional<ScenarioRunner::LinNodeRef> found;
  for (const SimulatedLinNode& n : lin_nodes_) {
    if (n.name == node && (bus.empty() || config_.buses[n.bus].name == bus)) {
      if (found) {
        return std::nullopt;  // on several buses
      }
      found = ScenarioRunner::LinNodeRef{n.bus, n.ecu->node()};
    }
  }
  return found;
}

// Names are scoped by bus: `name` is "BUS/NAME", or a NAME that only one bus has.
Result<std::vector<SimulatedLinNode>::iterator> Simulation::find_lin_named(std::string_view name) {
  return find_named_node(lin_nodes_, name, config_.buses, "LIN",
                         [](const SimulatedLinNode& n) -> const std::string& { return n.name; });
}

tl::expected<std::vector<std::string>, std::vector<std::string>> Simulation::load_lin_nodes(
    std::string_view text, const std::string& source) {
  auto configs = parse_lin_nodes(text, source, config_.buses);
  if (!configs) {
    return tl::unexpected(configs.error());
  }
  std::vector<std::string> errors;
  for (const LinNodeConfig& n : *configs) {
    if (n.schedule.empty()) {
      continue;
    }
    // A bus has one commander: another node (not one this load replaces) running a schedule
    // there is a conflict.
    for (const SimulatedLinNode& other : lin_nodes_) {
      const bool replaced =
          std::any_of(configs->begin(), configs->end(), [&](const LinNodeConfig& c) {
            return c.name == other.name && c.bus == config_.buses[other.bus].name;
          });
      if (!replaced && config_.buses[other.bus].name == n.bus &&
          !other.ecu->running_schedule().empty()) {
        errors.push_back(fmt::format(
            "{}:{}: lin_node {}: {} is the commander of {} already (running {}); stop its "
            "schedule first",
            source, n.line, n.name, other.name, n.bus, other.ecu->running_schedule()));
      }
    }
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  std::vector<std::string> names;
  for (const LinNodeConfig& n : *configs) {
    // Names are scoped by bus: a node of this name on another bus stays.
    const std::size_t bus = *bus_index(n.bus);
    std::erase_if(lin_nodes_, [&](const SimulatedLinNode& old) {
      return old.name == n.name && old.bus == bus;  // replaced: it leaves the bus first
    });
    lin_nodes_.push_back(make_lin_node(n, bus, *buses_[bus].lin, config_.buses[bus].bitrate));
    names.push_back(fmt::format("{}/{}", n.bus, n.name));
  }
  return names;
}

Result<> Simulation::power_lin_node(const std::string& name, bool on) {
  auto found = find_lin_named(name);
  if (!found) {
    return tl::unexpected(found.error());
  }
  auto it = *found;
  it->ecu->set_powered(on);
  return {};
}

Result<> Simulation::run_lin_schedule(const std::string& name, const std::string& table) {
  auto found = find_lin_named(name);
  if (!found) {
    return tl::unexpected(found.error());
  }
  auto it = *found;
  if (table.empty()) {
    it->ecu->stop_schedule();
    return {};
  }
  for (const SimulatedLinNode& other : lin_nodes_) {
    if (&other != &*it && other.bus == it->bus && !other.ecu->running_schedule().empty()) {
      return fail(
          Errc::bad_argument,
          fmt::format("{} is the commander of {} already (running {}); stop its schedule first",
                      other.name, config_.buses[it->bus].name, other.ecu->running_schedule()));
    }
  }
  if (!it->ecu->run_schedule(table)) {
    return fail(Errc::not_found,
                fmt::format("node {} has no schedule table named \"{}\"", name, table));
  }
  return {};
}

Result<> Simulation::remove_lin_node(const std::string& name) {
  auto found = find_lin_named(name);
  if (!found) {
    return tl::unexpected(found.error());
  }
  auto it = *found;
  lin_nodes_.erase(it);
  return {};
}

}  // namespace canemu::daemon
