// What `canemu status` shows of buses across hosts: the other daemons, this daemon's remote buses
// and why one cannot be used, its remote nodes' statistics.
#ifdef CANEMU_HAVE_DDS

#include "remote_node.hpp"

namespace canemu::daemon {

std::string Distributed::Impl::bus_problem(const BusConfig& b) const {
  auto it = peers.find(b.owner);
  if (it == peers.end()) {
    return fmt::format("daemon {} not heard from", b.owner);
  }
  const Peer& p = it->second;
  auto owned = std::find_if(p.owned.begin(), p.owned.end(),
                            [&](const auto& o) { return o.first == b.name; });
  if (owned == p.owned.end()) {
    return fmt::format("daemon {} simulates no bus \"{}\"", b.owner, b.name);
  }
  const canemu_net_OwnedBus& o = owned->second;
  if (o.kind != wire_bus_kind(b.kind) || o.bitrate != b.bitrate ||
      o.data_bitrate != b.data_bitrate) {
    auto kind = [](uint8_t k) {
      return k == canemu_net_BUS_CAN_FD ? "can-fd" : k == canemu_net_BUS_LIN ? "lin" : "can";
    };
    return fmt::format(
        "daemon {} runs \"{}\" as {} at {}/{} bit/s; this daemon declares {} at {}/{} bit/s",
        b.owner, b.name, kind(o.kind), o.bitrate, o.data_bitrate, kind(wire_bus_kind(b.kind)),
        b.bitrate, b.data_bitrate);
  }
  return {};
}

std::vector<PeerStatus> Distributed::peers() const {
  std::vector<PeerStatus> out;
  const int64_t now = monotonic_ms();
  for (const auto& [name, p] : impl_->peers) {
    PeerStatus s;
    s.name = name;
    s.version = p.version;
    s.protocol = p.protocol;
    s.state = p.gone ? "gone" : !p.refused.empty() ? "refused" : "up";
    s.reason = p.gone ? p.gone_reason : p.refused;
    s.time = time_text(p.time_mode, p.scale);
    s.last_heard_ms = now - p.heard_ms;
    s.buses = p.buses;
    for (const auto& [key, h] : impl_->hosted) {
      s.hosted_nodes += key.first == name ? 1 : 0;
    }
    s.linked = impl_->linked(name);
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<RemoteBusStatus> Distributed::remote_buses() const {
  std::vector<RemoteBusStatus> out;
  const Simulation& sim = impl_->sim;
  for (std::size_t i = 0; i < sim.bus_count(); ++i) {
    const BusConfig& b = sim.bus_config(i);
    if (!sim.config().remote(b)) {
      continue;
    }
    RemoteBusStatus s;
    s.bus = b.name;
    s.owner = b.owner;
    auto it = impl_->peers.find(b.owner);
    if (it == impl_->peers.end() || it->second.gone) {
      s.state = "waiting";
      s.reason = it == impl_->peers.end() ? fmt::format("daemon {} not heard from", b.owner)
                                          : fmt::format("daemon {} is gone", b.owner);
    } else if (!it->second.refused.empty()) {
      s.state = "refused";
      s.reason = it->second.refused;
    } else if (std::string problem = impl_->bus_problem(b); !problem.empty()) {
      s.state = "refused";
      s.reason = problem;
    } else if (!it->second.welcomed) {
      s.state = "waiting";
      s.reason = fmt::format("daemon {} has not answered yet", b.owner);
    } else {
      s.state = "attached";
    }
    for (RemoteNode* n : impl_->nodes) {
      s.nodes += n->bus_name() == b.name && n->in_use() ? 1 : 0;
    }
    out.push_back(std::move(s));
  }
  return out;
}

const DistributedCounters& Distributed::counters() const {
  return impl_->counters;
}

const NodeStats* Distributed::remote_stats(std::size_t bus, NodeId node) const {
  for (const RemoteNode* n : impl_->nodes) {
    if (n->bus() == bus && n->node() == node) {
      return &n->stats();
    }
  }
  return nullptr;
}

}  // namespace canemu::daemon

#endif
