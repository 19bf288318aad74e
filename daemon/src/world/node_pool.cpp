#include "canemu/daemon/world/node_pool.hpp"

#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

namespace canemu::daemon {

void NodePool::add_bus(model::CanBus& bus, bool fd, Maker make) {
  buses_.push_back(BusNodes{&bus, fd, std::move(make), {}});
}

void NodePool::add_lin_bus() {
  buses_.push_back(BusNodes{nullptr, false, {}, {}});
}

model::HostedNode& NodePool::spare(std::size_t bus) {
  BusNodes& b = buses_[bus];
  for (auto& node : b.nodes) {
    if (node->reusable()) {
      return *node;
    }
  }
  if (b.make) {
    b.nodes.push_back(b.make(*b.bus));
  } else if (b.fd) {
    b.nodes.push_back(std::make_unique<model::CanFdNode>(scheduler_, *b.bus));
  } else {
    b.nodes.push_back(std::make_unique<model::Sja1000Node>(scheduler_, *b.bus));
  }
  return *b.nodes.back();
}

}  // namespace canemu::daemon
