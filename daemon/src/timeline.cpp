#include "canemu/daemon/timeline.hpp"

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
    return r;
  }
  const auto node = sim.devices().find_node(node_name);
  if (!node) {
    return TimelineError{ipc::ErrorCode::bad_argument,
                         fmt::format("no CAN node named \"{}\" (see canemu status)", node_name)};
  }
  if (!bus_name.empty() && sim.bus_index(bus_name) != node->bus) {
    return TimelineError{ipc::ErrorCode::bad_argument,
                         fmt::format("node \"{}\" is not on bus \"{}\"", node_name, bus_name)};
  }
  const model::CounterTimeline& t = sim.bus(node->bus).stats(node->id).timeline;
  auto r = std::make_unique<ipc::TimelineReply>(ipc::make_message<ipc::TimelineReply>(request_id));
  ipc::copy_name(r->node, node_name);
  r->now_ns = now.ns();
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
