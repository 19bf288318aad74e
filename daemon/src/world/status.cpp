#include "canemu/daemon/world/status.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon {

using namespace canemu::model;

std::string bridge_node_name(const Bridge& b) {
  switch (b.kind()) {
    case BridgeKind::lcm:
      return "lcm:" + b.options().bus;
    case BridgeKind::dds:
      return "dds:" + b.options().bus;
    case BridgeKind::socketcan:
      break;
  }
  return "socketcan:" + b.options().interface;
}

void fill_status(const Simulation& sim, ipc::StatusReply& r, std::size_t first_bus,
                 std::size_t first_node) {
  const SimTime now = sim.scheduler().now();
  r.sim_time_ns = now.ns();
  r.bus_total = static_cast<uint16_t>(sim.bus_count());
  r.first_bus = static_cast<uint16_t>(first_bus);
  r.first_node = static_cast<uint16_t>(first_node);
  r.generation = sim.devices().generation();
  r.bus_count = 0;  // the reply may be filled again
  r.node_count = 0;
  const std::size_t last_bus = std::min(sim.bus_count(), first_bus + ipc::kStatusPageBuses);
  for (std::size_t i = first_bus; i < last_bus; ++i) {
    const BusConfig& c = sim.bus_config(i);
    ipc::StatusBus& s = r.buses[r.bus_count++];
    ipc::copy_name(s.name, c.name);
    s.kind = static_cast<uint8_t>(c.kind);
    s.low_speed = c.low_speed ? 1 : 0;
    s.bitrate = c.bitrate;
    s.data_bitrate = c.data_bitrate;
    if (const lin::LinBus* lin = sim.lin_bus(i)) {
      // A LIN bus: frames whole, frames with an error, and its load over the last second.
      const lin::LinBusStats& st = lin->stats();
      s.frames = st.frames;
      s.error_frames = st.errors;
      s.load_permille = static_cast<uint32_t>(std::lround(lin->load_percent(now) * 10));
      continue;
    }
    const CanBus& b = sim.bus(i);
    s.load_permille = static_cast<uint32_t>(std::lround(b.bus_load_percent(now) * 10));
    s.frames = b.frames_on_bus();
    s.error_frames = b.error_frames_on_bus();
  }
  // Every node counts towards node_total; the page holds those from first_node on.
  std::size_t index = 0;
  auto next_slot = [&]() -> ipc::StatusNode* {
    const std::size_t i = index++;
    if (i < first_node || r.node_count == ipc::kStatusPageNodes) {
      return nullptr;
    }
    return &r.nodes[r.node_count++];
  };
  // `started`: the controller takes part in bus traffic (out of its reset or init mode).
  auto add_controller = [&](const std::string& name, std::size_t bus, CanController& controller,
                            NodeId id, bool started) {
    ipc::StatusNode* s = next_slot();
    if (s == nullptr) {
      return;
    }
    ipc::copy_name(s->name, name);
    s->bus = static_cast<uint16_t>(bus);
    FaultConfinement& fc = controller.confinement();
    s->state = static_cast<uint8_t>(fc.state());
    s->mode = static_cast<uint8_t>(started ? ipc::WireNodeMode::running : ipc::WireNodeMode::init);
    s->tec = fc.tec();
    s->rec = fc.rec();
    const RemoteBuses* d = sim.remote();
    const NodeStats* remote = d != nullptr ? d->remote_stats(bus, id) : nullptr;
    const NodeStats& st = remote != nullptr ? *remote : sim.bus(bus).stats(id);
    s->frames_sent = st.frames_sent;
    s->frames_received = st.frames_received;
    s->errors = st.errors_as_transmitter.total() + st.errors_as_receiver.total();
  };
  // A node its driver runs: started while the driver has it on the bus (the controller of a
  // node on another daemon's bus is there, not here).
  auto add_node = [&](const std::string& name, std::size_t bus, HostedNode& node) {
    add_controller(name, bus, node.controller(), node.node(), node.running());
  };
  // A LIN controller: online or offline, and what it did (no error counters).
  auto add_lin = [&](const std::string& name, std::size_t bus, const ixxat::LinLine& line) {
    ipc::StatusNode* s = next_slot();
    if (s == nullptr) {
      return;
    }
    ipc::copy_name(s->name, name);
    s->bus = static_cast<uint16_t>(bus);
    s->lin = static_cast<uint8_t>(line.online() ? ipc::WireLinState::online
                                                : ipc::WireLinState::offline);
    s->frames_sent = line.stats().frames_sent;
    s->frames_received = line.stats().frames_received;
    s->errors = line.stats().errors;
  };
  const DeviceRegistry& devices = sim.devices();
  for (const DeviceRegistry::Configured& d : devices.configured()) {
    for (const DeviceRegistry::Controller& c : d.controllers) {
      add_node(c.name, c.bus, *c.node);
    }
    for (const DeviceRegistry::LinController& c : d.lin) {
      add_lin(c.name, c.bus, *c.line);
    }
  }
  for (const DeviceRegistry::Ephemeral& e : devices.ephemeral()) {
    add_node(e.name + ":0", e.bus, *e.node);
  }
  for (const DeviceRegistry::LinEphemeral& e : devices.lin_ephemeral()) {
    add_lin(e.name + ":0", e.bus, *e.line);
  }
  // Bridges' nodes, by what they join: "socketcan:vcan0", "lcm:can0", "dds:can0".
  for (const auto& b : sim.bridges()) {
    add_node(bridge_node_name(*b), b->bus(), b->node());
  }
  // Simulated CAN nodes by their names: running while powered.
  for (const SimulatedCanNode& n : sim.can_nodes()) {
    add_node(n.ecu->name(), n.bus, n.ecu->node());
  }
  // Simulated LIN nodes: powered (online) or switched off; sent: headers and responses.
  for (const SimulatedLinNode& l : sim.lin_nodes()) {
    ipc::StatusNode* s = next_slot();
    if (s == nullptr) {
      continue;
    }
    ipc::copy_name(s->name, l.name);
    s->bus = static_cast<uint16_t>(l.bus);
    s->lin = static_cast<uint8_t>(l.ecu->powered() ? ipc::WireLinState::online
                                                   : ipc::WireLinState::offline);
    const lin::EcuCounters& c = l.ecu->counters();
    s->frames_sent = c.headers + c.responses;
    s->frames_received = c.frames;
    s->errors = c.errors;
  }
  // X-CAN-2i interfaces: the 82527's counters are the model's (the chip shows them to nobody
  // else).
  for (const DeviceRegistry::Xcan& x : devices.xcan()) {
    for (unsigned i = 0; i < x.buses.size(); ++i) {
      model::I82527& chip = x.device->module().chip(i);
      add_controller(fmt::format("{}:{}", x.config.name, i), x.buses[i], chip, chip.node(),
                     chip.participating());
    }
  }
  // SL-CANi interfaces, the same way.
  for (const DeviceRegistry::Slcan& s : devices.slcan()) {
    model::I82527& chip = s.device->module().chip();
    add_controller(s.config.name + ":0", s.bus, chip, chip.node(), chip.participating());
  }
  r.node_total = static_cast<uint16_t>(index);
}

void fill_device_list(const Simulation& sim, ipc::DeviceListReply& r, std::size_t first) {
  const DeviceRegistry& devices = sim.devices();
  r.generation = devices.generation();
  r.first = static_cast<uint16_t>(first);
  r.count = 0;  // the reply may be filled again
  // Every device counts towards total; the page holds those from `first` on.
  std::size_t index = 0;
  auto next_slot = [&]() -> ipc::DeviceEntry* {
    const std::size_t i = index++;
    if (i < first || r.count == ipc::kDevicePage) {
      return nullptr;
    }
    return &r.devices[r.count++];
  };
  for (const DeviceRegistry::Configured& d : devices.configured()) {
    ipc::DeviceEntry* slot = next_slot();
    if (slot == nullptr) {
      continue;
    }
    const DeviceConfig& c = d.config;
    ipc::DeviceEntry& e = *slot;
    ipc::copy_name(e.name, c.name);
    e.model = static_cast<uint8_t>(c.model == DeviceModel::ixxat_usb_to_can
                                       ? ipc::WireDeviceModel::ixxat_usb_to_can
                                       : ipc::WireDeviceModel::ixxat_usb_to_can_fd);
    std::vector<std::string> buses = c.controllers;
    buses.insert(buses.end(), c.lin.begin(), c.lin.end());
    e.controller_count =
        static_cast<uint8_t>(std::min<std::size_t>(buses.size(), ipc::kMaxDeviceControllers));
    for (std::size_t k = 0; k < e.controller_count; ++k) {
      ipc::copy_name(e.buses[k], buses[k]);
      const auto kind = k >= c.controllers.size() ? ipc::WireControllerKind::lin
                        : c.model == DeviceModel::ixxat_usb_to_can
                            ? ipc::WireControllerKind::can
                            : ipc::WireControllerKind::can_fd;
      e.controller_fd[k] = static_cast<uint8_t>(kind);
    }
    e.vci_id = d.vci_id;
    if (!d.controllers.empty() && d.controllers[0].line) {
      e.epoch_ns = d.controllers[0].line->epoch().ns();
    }
    ipc::copy_name(e.hardware_id, hardware_id(c.name));
  }
  // X-CAN-2i modules: no VCI object id (the VCI's device list leaves them out); their
  // interfaces are the nodes NAME:0 and NAME:1.
  for (const DeviceRegistry::Xcan& x : devices.xcan()) {
    ipc::DeviceEntry* slot = next_slot();
    if (slot == nullptr) {
      continue;
    }
    ipc::DeviceEntry& e = *slot;
    ipc::copy_name(e.name, x.config.name);
    e.model = static_cast<uint8_t>(ipc::WireDeviceModel::sorcus_x_can_2i);
    e.controller_count = static_cast<uint8_t>(x.config.controllers.size());
    for (std::size_t k = 0; k < x.config.controllers.size() && k < ipc::kMaxDeviceControllers;
         ++k) {
      ipc::copy_name(e.buses[k], x.config.controllers[k]);
    }
  }
  // SL-CANi S-Links: no VCI object id either; the one controller is the node NAME:0.
  for (const DeviceRegistry::Slcan& x : devices.slcan()) {
    ipc::DeviceEntry* slot = next_slot();
    if (slot == nullptr) {
      continue;
    }
    ipc::DeviceEntry& e = *slot;
    ipc::copy_name(e.name, x.config.name);
    e.model = static_cast<uint8_t>(ipc::WireDeviceModel::sorcus_sl_cani);
    e.controller_count = 1;
    ipc::copy_name(e.buses[0], sim.bus_config(x.bus).name);
  }
  // An ephemeral device's entry: one controller on `bus`, of the client `owner_pid`; a VCI
  // adapter when `vci_id` is set.
  auto add_ephemeral = [&](const std::string& name, std::size_t bus, uint32_t owner_pid,
                           uint64_t vci_id, SimTime epoch) -> ipc::DeviceEntry* {
    ipc::DeviceEntry* slot = next_slot();
    if (slot == nullptr) {
      return nullptr;
    }
    ipc::DeviceEntry& e = *slot;
    ipc::copy_name(e.name, name);
    e.model = static_cast<uint8_t>(vci_id != 0 ? ipc::WireDeviceModel::ixxat_usb_to_can
                                               : ipc::WireDeviceModel::ephemeral);
    e.controller_count = 1;
    e.ephemeral = 1;
    e.owner_pid = owner_pid;
    ipc::copy_name(e.buses[0], sim.bus_config(bus).name);
    if (vci_id != 0) {
      e.vci_id = vci_id;
      e.epoch_ns = epoch.ns();
      ipc::copy_name(e.hardware_id, hardware_id(name));
    }
    return &e;
  };
  for (const DeviceRegistry::Ephemeral& x : devices.ephemeral()) {
    ipc::DeviceEntry* e = add_ephemeral(x.name, x.bus, x.owner_pid, x.line ? x.vci_id : 0,
                                        x.line ? x.line->epoch() : SimTime{});
    if (e != nullptr && x.line && x.line->fd_controller()) {
      e->model = static_cast<uint8_t>(ipc::WireDeviceModel::ixxat_usb_to_can_fd);
      e->controller_fd[0] = static_cast<uint8_t>(ipc::WireControllerKind::can_fd);
    }
  }
  for (const DeviceRegistry::LinEphemeral& x : devices.lin_ephemeral()) {
    ipc::DeviceEntry* e = add_ephemeral(x.name, x.bus, x.owner_pid, x.vci_id, x.line->epoch());
    if (e != nullptr) {
      e->controller_fd[0] = static_cast<uint8_t>(ipc::WireControllerKind::lin);
    }
  }
  r.total = static_cast<uint16_t>(index);
}

void fill_recorder_list(const Simulation& sim, ipc::RecorderListReply& r, std::size_t first) {
  const auto& recorders = sim.recorders();
  r.total = static_cast<uint16_t>(recorders.size());
  r.first = static_cast<uint16_t>(first);
  const std::size_t from = std::min(first, recorders.size());
  r.count = static_cast<uint16_t>(std::min(recorders.size() - from, ipc::kRecorderPage));
  for (std::size_t i = 0; i < r.count; ++i) {
    const Recorder& rec = *recorders[from + i];
    const ipc::CaptureWriter& w = rec.writer();
    ipc::RecorderEntry& e = r.recorders[i];
    ipc::copy_name(e.bus, rec.config().bus);
    ipc::copy_name(e.path, rec.config().path);
    e.format = static_cast<uint8_t>(w.options().format);
    e.errors = rec.config().errors ? 1 : 0;
    e.rotations = w.rotations();
    e.frames = w.frames();
    e.bytes = w.bytes();
    e.lost = w.lost();
    ipc::copy_name(e.error, w.error());
  }
}

void fill_bridge_list(const Simulation& sim, ipc::BridgeListReply& r, std::size_t first) {
  const auto& bridges = sim.bridges();
  r.total = static_cast<uint16_t>(bridges.size());
  r.first = static_cast<uint16_t>(first);
  const std::size_t from = std::min(first, bridges.size());
  r.count = static_cast<uint16_t>(std::min(bridges.size() - from, ipc::kBridgePage));
  for (std::size_t i = 0; i < r.count; ++i) {
    Bridge& b = *bridges[from + i];
    const BridgeStats& st = b.stats();
    model::FaultConfinement& fc = b.node().controller().confinement();
    ipc::BridgeEntry& e = r.bridges[i];
    ipc::copy_name(e.bus, b.options().bus);
    ipc::copy_name(e.interface, b.options().interface);
    e.error_frames = b.options().error_frames ? 1 : 0;
    e.state = static_cast<uint8_t>(fc.state());
    e.tec = fc.tec();
    e.rec = fc.rec();
    e.queued = static_cast<uint32_t>(b.queued());
    e.restart_ms = b.options().restart_ms;
    e.restarts = st.restarts;
    e.to_interface = st.to_interface;
    e.from_interface = st.from_interface;
    e.error_frames_written = st.error_frames;
    e.to_interface_dropped = st.to_interface_dropped;
    e.queue_dropped = st.queue_dropped;
    e.rejected = st.rejected;
    e.tx_failed = st.tx_failed;
    e.kernel_dropped = st.kernel_dropped;
    e.kind = b.kind() == BridgeKind::lcm   ? ipc::kBridgeLcm
             : b.kind() == BridgeKind::dds ? ipc::kBridgeDds
                                           : ipc::kBridgeSocketCan;
    e.received = st.received;
    ipc::copy_name(e.url, b.options().url);
    ipc::copy_name(e.channel_prefix, b.options().channel_prefix);
    static_assert(ipc::kBridgeRejectReasons == kBridgeRejectReasons);
    for (std::size_t k = 0; k < kBridgeRejectReasons; ++k) {
      e.rejected_by[k] = b.rejections().count(k);
    }
    ipc::copy_name(e.last_rejected, ipc::printable(b.rejections().last()));
  }
}

namespace {

// Copies text another daemon sent: every byte outside printable ASCII becomes '?', so that no
// peer can break a table, a log line or a terminal.
template <std::size_t N>
void copy_printable(char (&dst)[N], std::string_view src) {
  ipc::copy_name(dst, src);
  for (char& c : dst) {
    if (c != '\0' && (c < 0x20 || c > 0x7E)) {
      c = '?';
    }
  }
}

}  // namespace

void fill_peer_list(const Simulation& sim, ipc::PeerListReply& r, std::size_t first_peer,
                    std::size_t first_bus) {
  r.first_peer = static_cast<uint16_t>(first_peer);
  r.first_bus = static_cast<uint16_t>(first_bus);
  const RemoteBuses* d = sim.remote();
  if (d == nullptr) {
    return;
  }
  const DistributedConfig& cfg = sim.config().distributed;
  r.enabled = 1;
  ipc::copy_name(r.name, d->name());
  r.domain = cfg.domain;
  ipc::copy_name(r.partition, cfg.partition);
  r.heartbeat_ms = cfg.heartbeat_ms;
  r.timeout_ms = cfg.timeout_ms;
  const DistributedCounters& c = d->counters();
  r.counters.requests_sent = c.requests_sent;
  r.counters.requests_received = c.requests_received;
  r.counters.events_sent = c.events_sent;
  r.counters.events_received = c.events_received;
  r.counters.dropped = c.dropped;
  r.counters.late = c.late;
  r.counters.rejected = c.rejected;
  r.counters.late_max_ns = c.late_max_ns;
  r.counters.late_bound_ns =
      sim.config().simulation.time.mode == TimeMode::stepped ? 0 : kLateBoundNs;
  static_assert(ipc::kNetDropReasons == kNetDropReasons);
  for (std::size_t k = 0; k < kNetDropReasons; ++k) {
    r.counters.by_reason[k] = c.by_reason[k];
  }
  copy_printable(r.counters.last_reason, c.last_reason);

  const std::vector<PeerStatus> peers = d->peers();
  r.peer_total = static_cast<uint16_t>(std::min<std::size_t>(peers.size(), UINT16_MAX));
  const std::size_t peer_from = std::min<std::size_t>(first_peer, r.peer_total);
  r.peer_count = static_cast<uint16_t>(std::min(r.peer_total - peer_from, ipc::kPeerPage));
  for (std::size_t i = 0; i < r.peer_count; ++i) {
    const PeerStatus& p = peers[peer_from + i];
    ipc::PeerEntry& e = r.peers[i];
    copy_printable(e.name, p.name);
    copy_printable(e.version, p.version);
    copy_printable(e.time, p.time);
    copy_printable(e.state, p.state);
    copy_printable(e.reason, p.reason);
    e.protocol = p.protocol;
    e.bus_total = static_cast<uint32_t>(p.buses.size());
    e.bus_count = static_cast<uint8_t>(std::min(p.buses.size(), ipc::kPeerBuses));
    for (std::size_t b = 0; b < e.bus_count; ++b) {
      copy_printable(e.buses[b], p.buses[b]);
    }
    e.last_heard_ms = p.last_heard_ms;
    e.hosted_nodes = p.hosted_nodes;
    e.linked = p.linked ? 1 : 0;
  }

  const std::vector<RemoteBusStatus> buses = d->remote_buses();
  r.bus_total = static_cast<uint16_t>(std::min<std::size_t>(buses.size(), UINT16_MAX));
  const std::size_t bus_from = std::min<std::size_t>(first_bus, r.bus_total);
  r.bus_count = static_cast<uint16_t>(std::min(r.bus_total - bus_from, ipc::kRemoteBusPage));
  for (std::size_t i = 0; i < r.bus_count; ++i) {
    const RemoteBusStatus& b = buses[bus_from + i];
    ipc::RemoteBusEntry& e = r.buses[i];
    ipc::copy_name(e.bus, b.bus);
    ipc::copy_name(e.owner, b.owner);
    ipc::copy_name(e.state, b.state);
    copy_printable(e.reason, b.reason);
    e.nodes = b.nodes;
  }
}

}  // namespace canemu::daemon
