// The nodes made for ephemeral devices, per bus, kept for the next device: a node is never
// removed from its bus (node ids stay valid, and a stopped node costs nothing on the wire), so a
// bus has as many pooled nodes as it carried ephemeral devices at once.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::daemon {

class NodePool {
 public:
  explicit NodePool(model::SimScheduler& scheduler) : scheduler_(scheduler) {}

  // Makes a node for a bus whose controllers run elsewhere (another daemon's bus).
  using Maker = std::function<std::unique_ptr<model::HostedNode>(model::CanBus&)>;
  // Bus number `bus_count()` from now on: its nodes are CAN FD controllers when `fd`, else
  // SJA1000s; or, when `make` is given, what it makes. The bus must outlive the pool.
  void add_bus(model::CanBus& bus, bool fd, Maker make = {});
  // Bus number `bus_count()` from now on is a LIN bus: no CAN nodes, spare() is not for it.
  void add_lin_bus();
  std::size_t bus_count() const { return buses_.size(); }

  // A stopped node on bus `bus`, ready to start: one an earlier device left that is reusable()
  // (stopped, unclaimed, no frame of it on the wire), else a new one.
  model::HostedNode& spare(std::size_t bus);
  // The nodes made for bus `bus` so far, in use or not.
  std::size_t node_count(std::size_t bus) const { return buses_[bus].nodes.size(); }

 private:
  struct BusNodes {
    model::CanBus* bus;
    bool fd;
    Maker make;
    std::vector<std::unique_ptr<model::HostedNode>> nodes;
  };
  model::SimScheduler& scheduler_;
  std::vector<BusNodes> buses_;
};

}  // namespace canemu::daemon
