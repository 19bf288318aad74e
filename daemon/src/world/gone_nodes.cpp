#include "canemu/daemon/world/gone_nodes.hpp"

#include <algorithm>

namespace canemu::daemon {

void GoneNodes::keep(const std::string& device, std::size_t bus, model::SimTime at,
                     const model::CounterTimeline& timeline) {
  forget(device);
  nodes_.push_back(Node{device, device + ":0", bus, at, timeline});
  const auto on_this_bus = [bus](const Node& n) { return n.bus == bus; };
  if (static_cast<std::size_t>(std::count_if(nodes_.begin(), nodes_.end(), on_this_bus)) >
      kPerBus) {
    nodes_.erase(std::find_if(nodes_.begin(), nodes_.end(), on_this_bus));
  }
}

void GoneNodes::forget(std::string_view device) {
  std::erase_if(nodes_, [device](const Node& n) { return n.device == device; });
}

const GoneNodes::Node* GoneNodes::find(std::string_view name) const {
  for (const Node& n : nodes_) {
    if (n.name == name || n.device == name) {
      return &n;
    }
  }
  return nullptr;
}

std::vector<const GoneNodes::Node*> GoneNodes::on_bus(std::size_t bus) const {
  std::vector<const Node*> out;
  for (const Node& n : nodes_) {
    if (n.bus == bus) {
      out.push_back(&n);
    }
  }
  return out;
}

}  // namespace canemu::daemon
