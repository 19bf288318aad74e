// The simulated LIN nodes canemud runs itself ([[lin_node]], docs/lin.md "Simulated nodes"):
// one model::lin::LinEcu each on its bus's LinBus, with its response table and schedule tables,
// powered or switched off and running its schedule from the start as configured.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/config/lin_config.hpp"
#include "canemu/firmware_model/chips/lin/lin_ecu.hpp"

namespace canemu::daemon {

struct SimulatedLinNode {
  std::string name;
  std::size_t bus;  // index of the configuration's bus
  std::unique_ptr<model::lin::LinEcu> ecu;
};

// The node `config` on `bus` (index `bus_index`, at `bus_bitrate` unless the node has its own),
// as it starts: tables loaded, powered as configured, its schedule (if any) running from now.
SimulatedLinNode make_lin_node(const LinNodeConfig& config, std::size_t bus_index,
                               model::lin::LinBus& bus, uint32_t bus_bitrate);

}  // namespace canemu::daemon
