// The world's simulated CAN nodes ([[can_node]], docs/restbus.md): started from the
// configuration on spare nodes of their buses, loaded, found and removed by name at run time.
#include <algorithm>

#include <fmt/format.h>

#include "canemu/daemon/world/simulation.hpp"
#include "world/named_nodes.hpp"

namespace canemu::daemon {

using namespace canemu::model;

Result<> Simulation::add_can_node(const CanNodeConfig& n) {
  const std::size_t bus = *bus_index(n.bus);
  const auto timing = bus_timing(bus);
  if (!timing) {
    return fail(Errc::bad_bit_timing,
                fmt::format("can_node {}: no controller runs {} at {} bit/s", n.name, n.bus,
                            config_.buses[bus].bitrate),
                place(n.line));
  }
  auto ecu = restbus::CanEcu::start(n, nodes_.spare(bus), *timing);
  if (!ecu) {
    return fail(ecu.error().code, ecu.error().text, place(n.line));
  }
  can_nodes_.push_back(SimulatedCanNode{bus, std::move(*ecu)});
  return {};
}

tl::expected<std::vector<std::string>, std::vector<std::string>> Simulation::load_can_nodes(
    std::string_view text, const std::string& source) {
  auto configs = parse_can_nodes(text, source, config_.buses);
  if (!configs) {
    return tl::unexpected(configs.error());
  }
  // Everything that could refuse a node is asked before any node changes.
  std::vector<std::string> errors;
  for (const CanNodeConfig& n : *configs) {
    if (!bus_timing(*bus_index(n.bus))) {
      errors.push_back(fmt::format("{}:{}: can_node {}: no controller runs {} at {} bit/s", source,
                                   n.line, n.name, n.bus,
                                   config_.buses[*bus_index(n.bus)].bitrate));
    } else if (auto ok = restbus::CanEcu::check(n); !ok) {
      errors.push_back(fmt::format("{}:{}: {}", source, n.line, ok.error().text));
    }
  }
  // A bus's message names and identifiers stay unique: against the nodes this load keeps.
  for (const SimulatedCanNode& old : can_nodes_) {
    const std::string& bus = config_.buses[old.bus].name;
    const bool replaced = std::any_of(
        configs->begin(), configs->end(),
        [&](const CanNodeConfig& c) { return c.bus == bus && c.name == old.ecu->name(); });
    if (replaced) {
      continue;
    }
    for (const CanNodeConfig& n : *configs) {
      if (n.bus != bus) {
        continue;
      }
      for (const CanMessageConfig& m : n.messages) {
        for (const CanMessageConfig& o : old.ecu->config().messages) {
          if (o.name == m.name) {
            errors.push_back(fmt::format(
                "{}:{}: can_node {}: node {} sends a message named \"{}\" on \"{}\" already",
                source, n.line, n.name, old.ecu->name(), m.name, bus));
          } else if (o.id == m.id && o.extended == m.extended) {
            errors.push_back(fmt::format(
                "{}:{}: can_node {}: node {} sends identifier {:#x} on \"{}\" already (two "
                "senders of one identifier collide on the wire)",
                source, n.line, n.name, old.ecu->name(), m.id, bus));
          }
        }
      }
    }
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  std::vector<std::string> names;
  for (const CanNodeConfig& n : *configs) {
    const std::size_t bus = *bus_index(n.bus);
    // Replaced: the old node leaves the bus first (its node may carry the new one).
    std::erase_if(can_nodes_, [&](const SimulatedCanNode& old) {
      const bool replaced = old.bus == bus && old.ecu->name() == n.name;
      if (replaced) {
        can_node_gone(old);
      }
      return replaced;
    });
    auto ecu = restbus::CanEcu::start(n, nodes_.spare(bus), *bus_timing(bus));
    can_nodes_.push_back(SimulatedCanNode{bus, std::move(*ecu)});
    names.push_back(fmt::format("{}/{}", n.bus, n.name));
  }
  return names;
}

Result<std::vector<SimulatedCanNode>::iterator> Simulation::find_can_named(std::string_view name) {
  return find_named_node(
      can_nodes_, name, config_.buses, "CAN",
      [](const SimulatedCanNode& n) -> const std::string& { return n.ecu->name(); });
}

Result<restbus::CanEcu*> Simulation::can_node(std::string_view name) {
  auto found = find_can_named(name);
  if (!found) {
    return tl::unexpected(found.error());
  }
  return (*found)->ecu.get();
}

Result<restbus::CanEcu*> Simulation::can_message(std::string_view bus, std::string_view message) {
  const auto index = bus_index(bus);
  if (!index) {
    return fail(Errc::not_found, fmt::format("no bus is named \"{}\"", bus));
  }
  for (SimulatedCanNode& n : can_nodes_) {
    if (n.bus != *index) {
      continue;
    }
    for (const CanMessageConfig& m : n.ecu->config().messages) {
      if (m.name == message) {
        return n.ecu.get();
      }
    }
  }
  return fail(
      Errc::not_found,
      fmt::format("no simulated CAN node sends a message named \"{}\" on {}", message, bus));
}

Result<> Simulation::remove_can_node(std::string_view name) {
  auto found = find_can_named(name);
  if (!found) {
    return tl::unexpected(found.error());
  }
  can_node_gone(**found);
  can_nodes_.erase(*found);
  return {};
}

void Simulation::can_node_gone(const SimulatedCanNode& n) {
  scenarios_.device_gone(
      fmt::format("simulated CAN node {}/{}", config_.buses[n.bus].name, n.ecu->name()), n.bus,
      n.ecu->node());
}

std::optional<ScenarioRunner::CanNodeRef> Simulation::find_can_node(std::string_view name) {
  auto found = find_can_named(name);
  if (!found) {
    return std::nullopt;
  }
  return ScenarioRunner::CanNodeRef{(*found)->bus, (*found)->ecu.get()};
}

std::optional<ScenarioRunner::CanNodeRef> Simulation::find_can_sender(std::string_view bus,
                                                                      std::string_view message) {
  auto ecu = can_message(bus, message);
  if (!ecu) {
    return std::nullopt;
  }
  return ScenarioRunner::CanNodeRef{*bus_index(bus), *ecu};
}

}  // namespace canemu::daemon
