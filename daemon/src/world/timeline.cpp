#include "canemu/daemon/world/timeline.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace canemu::daemon {

namespace {

ipc::WireCounterSample to_wire(const model::CounterSample& s) {
  ipc::WireCounterSample w;
  w.at_ns = s.at.ns();
  w.tec = s.tec;
  w.rec = s.rec;
  w.state = static_cast<uint8_t>(s.state);
  w.cause = static_cast<uint8_t>(s.cause);
  w.error = static_cast<uint8_t>(s.error);
  w.role = static_cast<uint8_t>(s.role);
  return w;
}

}  // namespace

TimelineAnswer answer_timeline(const Simulation& sim, const ipc::TimelineRequest& m,
                               uint32_t request_id) {
  const std::string bus_name = ipc::name_of(m.bus);
  const std::string node_name = ipc::name_of(m.node);
  const model::SimTime now = sim.scheduler().now();
  if (node_name.empty()) {
    const auto bus = sim.bus_index(bus_name);
    if (!bus) {
      return TimelineError{ipc::ErrorCode::no_such_bus,
                           fmt::format("no bus named \"{}\"", bus_name)};
    }
    const model::lin::LinBus* lin = sim.lin_bus(*bus);
    const auto bins = lin != nullptr ? lin->load_history(now) : sim.bus(*bus).bus_load_history(now);
    auto r = std::make_unique<ipc::LoadHistoryReply>(
        ipc::make_message<ipc::LoadHistoryReply>(request_id));
    ipc::copy_name(r->bus, bus_name);
    r->now_ns = now.ns();
    r->bin_ns = static_cast<uint32_t>(model::BusLoad::kBin.ns());
    r->total = static_cast<uint32_t>(bins.size());
    const std::size_t first = std::min<std::size_t>(m.first, bins.size());
    r->count = static_cast<uint32_t>(std::min(bins.size() - first, ipc::kMaxLoadBins));
    r->start_ns = first < bins.size() ? bins[first].start.ns() : now.ns();
    for (uint32_t k = 0; k < r->count; ++k) {
      r->busy_ns[k] = static_cast<uint32_t>(bins[first + k].busy.ns());
    }
    for (const GoneNodes::Node* g : sim.gone_nodes().on_bus(*bus)) {
      if (r->gone_count < ipc::kMaxGoneNodes) {
        ipc::copy_name(r->gone[r->gone_count++], g->name);
      }
    }
    return r;
  }
  // A device's node, else one whose ephemeral device has gone.
  const auto node = sim.devices().find_node(node_name);
  const GoneNodes::Node* gone = node ? nullptr : sim.gone_nodes().find(node_name);
  if (!node && gone == nullptr) {
    return TimelineError{ipc::ErrorCode::bad_argument,
                         fmt::format("no CAN node named \"{}\" (see canemu status)", node_name)};
  }
  const std::size_t bus = node ? node->bus : gone->bus;
  if (!bus_name.empty() && sim.bus_index(bus_name) != bus) {
    return TimelineError{ipc::ErrorCode::bad_argument,
                         fmt::format("node \"{}\" is not on bus \"{}\"", node_name, bus_name)};
  }
  const model::CounterTimeline& t = node ? sim.bus(bus).stats(node->id).timeline : gone->timeline;
  auto r = std::make_unique<ipc::TimelineReply>(ipc::make_message<ipc::TimelineReply>(request_id));
  ipc::copy_name(r->node, node_name);
  r->now_ns = now.ns();
  if (gone != nullptr) {
    r->gone = 1;
    r->gone_at_ns = gone->gone_at.ns();
  }
  r->total = static_cast<uint32_t>(t.samples().size());
  r->forgotten = t.forgotten();
  const std::size_t first = std::min<std::size_t>(m.first, t.samples().size());
  r->count = static_cast<uint32_t>(std::min(t.samples().size() - first, ipc::kMaxTimelineSamples));
  for (uint32_t k = 0; k < r->count; ++k) {
    r->samples[k] = to_wire(t.samples()[first + k]);
  }
  return r;
}

}  // namespace canemu::daemon
