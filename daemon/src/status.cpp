#include "canemu/daemon/status.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <string>

#include "canemu/daemon/simulation.hpp"

namespace canemu::daemon {

using namespace canemu::model;

void fill_status(const Simulation& sim, ipc::StatusReply& r) {
  const SimTime now = sim.scheduler().now();
  r.sim_time_ns = now.ns();
  r.bus_count = static_cast<uint16_t>(std::min(sim.bus_count(), ipc::kMaxStatusBuses));
  for (std::size_t i = 0; i < r.bus_count; ++i) {
    const BusConfig& c = sim.bus_config(i);
    const CanBus& b = sim.bus(i);
    ipc::StatusBus& s = r.buses[i];
    ipc::copy_name(s.name, c.name);
    s.kind = static_cast<uint8_t>(c.kind);
    s.low_speed = c.low_speed ? 1 : 0;
    s.bitrate = c.bitrate;
    s.data_bitrate = c.data_bitrate;
    s.load_permille = static_cast<uint32_t>(b.bus_load_percent(now) * 10 + 0.5);
    s.frames = b.frames_on_bus();
    s.error_frames = b.error_frames_on_bus();
  }
  std::size_t n = 0;
  auto add_controller = [&](const std::string& name, std::size_t bus, CanController& controller,
                            NodeId id) {
    if (n == ipc::kMaxStatusNodes) {
      return;
    }
    ipc::StatusNode& s = r.nodes[n++];
    ipc::copy_name(s.name, name);
    s.bus = static_cast<uint16_t>(bus);
    FaultConfinement& fc = controller.confinement();
    s.state = static_cast<uint8_t>(fc.state());
    s.tec = fc.tec();
    s.rec = fc.rec();
    const NodeStats& st = sim.bus(bus).stats(id);
    s.frames_sent = st.frames_sent;
    s.frames_received = st.frames_received;
    s.errors = st.errors_as_transmitter.total() + st.errors_as_receiver.total();
  };
  auto add_node = [&](const std::string& name, std::size_t bus, HostedNode& node) {
    add_controller(name, bus, node.controller(), node.node());
  };
  const DeviceRegistry& devices = sim.devices();
  for (const DeviceRegistry::Configured& d : devices.configured()) {
    for (const DeviceRegistry::Controller& c : d.controllers) {
      add_node(c.name, c.bus, *c.node);
    }
  }
  for (const DeviceRegistry::Ephemeral& e : devices.ephemeral()) {
    add_node(e.name + ":0", e.bus, *e.node);
  }
  // X-CAN-2i interfaces: the 82527's counters are the model's (the chip shows them to nobody
  // else).
  for (const DeviceRegistry::Xcan& x : devices.xcan()) {
    for (unsigned i = 0; i < x.buses.size(); ++i) {
      model::I82527& chip = x.device->module().chip(i);
      add_controller(fmt::format("{}:{}", x.config.name, i), x.buses[i], chip, chip.node());
    }
  }
  // SL-CANi interfaces, the same way.
  for (const DeviceRegistry::Slcan& s : devices.slcan()) {
    model::I82527& chip = s.device->module().chip();
    add_controller(s.config.name + ":0", s.bus, chip, chip.node());
  }
  r.node_count = static_cast<uint16_t>(n);
}

void fill_device_list(const Simulation& sim, ipc::DeviceListReply& r) {
  const DeviceRegistry& devices = sim.devices();
  r.generation = devices.generation();
  r.total = static_cast<uint16_t>(devices.configured().size() + devices.ephemeral().size());
  std::size_t n = 0;
  for (const DeviceRegistry::Configured& d : devices.configured()) {
    if (n == ipc::kMaxDevices) {
      break;
    }
    const DeviceConfig& c = d.config;
    ipc::DeviceEntry& e = r.devices[n++];
    ipc::copy_name(e.name, c.name);
    e.model = static_cast<uint8_t>(c.model == DeviceModel::ixxat_usb_to_can
                                       ? ipc::WireDeviceModel::ixxat_usb_to_can
                                       : ipc::WireDeviceModel::ixxat_usb_to_can_fd);
    e.controller_count = static_cast<uint8_t>(c.controllers.size());
    for (std::size_t k = 0; k < c.controllers.size() && k < ipc::kMaxDeviceControllers; ++k) {
      ipc::copy_name(e.buses[k], c.controllers[k]);
      e.controller_fd[k] = c.model == DeviceModel::ixxat_usb_to_can ? 0 : 1;
    }
    e.vci_id = d.vci_id;
    if (!d.controllers.empty() && d.controllers[0].line) {
      e.epoch_ns = d.controllers[0].line->epoch().ns();
    }
    ipc::copy_name(e.hardware_id, hardware_id(c.name));
  }
  for (const DeviceRegistry::Ephemeral& x : devices.ephemeral()) {
    if (n == ipc::kMaxDevices) {
      break;
    }
    ipc::DeviceEntry& e = r.devices[n++];
    ipc::copy_name(e.name, x.name);
    e.model = static_cast<uint8_t>(ipc::WireDeviceModel::ephemeral);
    e.controller_count = 1;
    e.ephemeral = 1;
    e.owner_pid = x.owner_pid;
    ipc::copy_name(e.buses[0], sim.bus_config(x.bus).name);
    if (x.line) {  // a VCI adapter
      const bool fd = x.line->fd_controller();
      e.model = static_cast<uint8_t>(fd ? ipc::WireDeviceModel::ixxat_usb_to_can_fd
                                        : ipc::WireDeviceModel::ixxat_usb_to_can);
      e.controller_fd[0] = fd ? 1 : 0;
      e.vci_id = x.vci_id;
      e.epoch_ns = x.line->epoch().ns();
      ipc::copy_name(e.hardware_id, hardware_id(x.name));
    }
  }
  r.count = static_cast<uint16_t>(n);
}

}  // namespace canemu::daemon
