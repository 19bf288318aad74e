#include "canemu/daemon/world/simulation.hpp"

#include <sys/socket.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <tuple>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/bridges/dds_bridge.hpp"
#include "canemu/daemon/bridges/lcm_bridge.hpp"
#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/firmware_model/adapters/ixxat/lin_line.hpp"
#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

namespace canemu::daemon {

using namespace canemu::model;

NodeRates node_rates(const BusConfig& bus, bool fd, const NodeRates& asked) {
  NodeRates r;
  r.bitrate = asked.bitrate != 0 ? asked.bitrate : bus.bitrate;
  r.sample_point = asked.sample_point != 0 ? asked.sample_point : bus.sample_point;
  r.data_bitrate = !fd                       ? 0
                   : asked.data_bitrate != 0 ? asked.data_bitrate
                   : bus.data_bitrate != 0   ? bus.data_bitrate
                                             : r.bitrate;
  return r;
}

std::optional<HostedNodeSettings> node_timing(bool fd, const NodeRates& rates) {
  const uint32_t bitrate = rates.bitrate;
  const uint32_t data_bitrate = rates.data_bitrate;
  const uint32_t sample_point = rates.sample_point;
  HostedNodeSettings s;
  if (!fd) {
    const auto btr = sja1000::btr_for(bitrate, sample_point);
    if (!btr) {
      return std::nullopt;
    }
    s.btr0 = btr->btr0;
    s.btr1 = btr->btr1;
    s.nominal = *sja1000::decode_btr(btr->btr0, btr->btr1);
    return s;
  }
  const auto nominal =
      ixxat::timing_for(bitrate, sample_point, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  const auto data =
      ixxat::timing_for(data_bitrate, sample_point, ixxat::kFdDataRange, ixxat::Phase::data);
  if (!nominal || !data) {
    return std::nullopt;
  }
  s.nominal = *nominal;
  s.data = *data;
  return s;
}

tl::expected<std::unique_ptr<Simulation>, std::vector<std::string>> Simulation::build(
    const Config& config, const RemoteBusesOpener& open_remote) {
  std::unique_ptr<Simulation> sim(new Simulation(config));
  std::vector<std::string> errors;
  if (sim->config_.distributed.enabled) {
    if (auto family = refused_family(AF_INET); !family) {
      return tl::unexpected(std::vector<std::string>{
          fmt::format("{}: [distributed]: {}", sim->config_.source, family.error().text)});
    }
    if (!open_remote) {
      return tl::unexpected(std::vector<std::string>{fmt::format(
          "{}: [distributed]: this program cannot reach other daemons", sim->config_.source)});
    }
    auto link = open_remote(*sim, sim->config_);
    if (!link) {
      return tl::unexpected(std::vector<std::string>{
          fmt::format("{}: [distributed]: {}", sim->config_.source, link.error().text)});
    }
    sim->remote_ = std::move(*link);
  }
  for (const BusConfig& b : sim->config_.buses) {
    sim->add_bus(b);
  }
  for (const DeviceConfig& d : sim->config_.devices) {
    if (auto added = sim->add_device(d); !added) {
      errors.push_back(added.error().what());
    }
  }
  // The configuration reader checked that each node's bus is a LIN bus.
  for (const LinNodeConfig& n : sim->config_.lin_nodes) {
    const std::size_t bus = *sim->bus_index(n.bus);
    sim->lin_nodes_.push_back(
        make_lin_node(n, bus, *sim->buses_[bus].lin, sim->config_.buses[bus].bitrate));
  }
  for (const CanNodeConfig& n : sim->config_.can_nodes) {
    if (auto added = sim->add_can_node(n); !added) {
      errors.push_back(added.error().what());
    }
  }
  for (const RecorderConfig& r : sim->config_.recorders) {
    if (auto added = sim->add_recorder(r); !added) {
      errors.push_back(added.error().what());
    }
  }
  for (const BridgeConfig& b : sim->config_.bridges) {
    if (auto added = sim->add_bridge(b); !added) {
      errors.push_back(fmt::format("{}: {}", sim->place(b.line), added.error().text));
    }
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  return sim;
}

std::string Simulation::place(uint32_t line) const {
  return fmt::format("{}:{}", config_.source, line);
}

std::optional<HostedNodeSettings> Simulation::bus_timing(std::size_t bus) const {
  const BusConfig& bc = config_.buses[bus];
  const bool fd = bc.kind == BusKind::can_fd;
  return node_timing(fd, node_rates(bc, fd));
}

void Simulation::add_bus(const BusConfig& b) {
  RunningBus& running = buses_.emplace_back();
  if (b.kind == BusKind::lin) {
    lin::Layout layout;
    layout.bitrate = b.bitrate;
    running.lin = std::make_unique<lin::LinBus>(scheduler_, layout);
    nodes_.add_lin_bus();
  } else {
    running.can = std::make_unique<CanBus>(scheduler_, b.name);
    const bool fd = b.kind == BusKind::can_fd;
    NodePool::Maker make;
    if (config_.remote(b)) {
      make = [this, bus = buses_.size() - 1, fd](CanBus& placeholder) {
        return remote_->make_node(bus, placeholder, fd);
      };
    }
    nodes_.add_bus(*running.can, fd, std::move(make));
  }
  scenarios_.add_bus(running.can.get(), b, running.lin.get());
}

std::optional<std::size_t> Simulation::bus_index(std::string_view name) const {
  for (std::size_t i = 0; i < config_.buses.size(); ++i) {
    if (config_.buses[i].name == name) {
      return i;
    }
  }
  return std::nullopt;
}

Result<> Simulation::add_device(const DeviceConfig& d) {
  if (d.model == DeviceModel::sorcus_x_can_2i) {
    return add_xcan(d);
  }
  if (d.model == DeviceModel::sorcus_sl_cani) {
    return add_slcan(d);
  }
  // Every controller's timing first, so that a device is added whole or not at all.
  std::vector<std::size_t> buses;
  for (const std::string& bus_name : d.controllers) {
    const std::size_t bus = *bus_index(bus_name);
    const BusConfig& bc = config_.buses[bus];
    // Checked against the bus as it runs (a reload leaves changed buses as they were).
    if (bc.kind == BusKind::lin) {
      return fail(Errc::bad_argument,
                  fmt::format("device {}: bus {} is a LIN bus; a CAN controller cannot sit on it",
                              d.name, bc.name),
                  place(d.line));
    }
    const bool fd = d.model != DeviceModel::ixxat_usb_to_can;
    const auto timing = node_timing(fd, node_rates(bc, fd));
    if (!timing) {
      return fail(
          Errc::bad_bit_timing,
          fmt::format("device {}: {} cannot run bus {} at {} bit/s", d.name,
                      fd ? "the CAN FD controller" : "an SJA1000 at 16 MHz", bc.name, bc.bitrate),
          place(d.line));
    }
    buses.push_back(bus);
  }
  std::vector<DeviceRegistry::LinController> lin;
  if (auto added = lin_controllers(d, lin); !added) {
    return added;
  }
  std::vector<DeviceRegistry::Controller> controllers;
  for (std::size_t i = 0; i < buses.size(); ++i) {
    DeviceRegistry::Controller c;
    c.name = fmt::format("{}:{}", d.name, i);
    c.bus = buses[i];
    // The controller stays in reset (off the bus) until an application initializes and starts
    // it through the VCI, as on a real adapter.
    CanBus& bus = *buses_[c.bus].can;
    if (config_.remote(config_.buses[c.bus])) {
      c.node = remote_->make_node(c.bus, bus, d.model == DeviceModel::ixxat_usb_to_can_fd);
      // The owner lists it as "DAEMON/DEVICE:0" (controller 0) or "DAEMON/DEVICE-N:0".
      remote_->name_node(*c.node, i == 0 ? d.name : fmt::format("{}-{}", d.name, i));
    } else if (d.model == DeviceModel::ixxat_usb_to_can) {
      c.node = std::make_unique<Sja1000Node>(scheduler_, bus);
    } else {
      c.node = std::make_unique<CanFdNode>(scheduler_, bus);
    }
    c.line =
        std::make_shared<ixxat::CanLine>(scheduler_, *c.node, ixxat::Clocks{}, scheduler_.now());
    c.line->set_low_speed(config_.buses[c.bus].low_speed);
    controllers.push_back(std::move(c));
  }
  devices_.add_configured(d, std::move(controllers), std::move(lin));
  return {};
}

Result<> Simulation::lin_controllers(const DeviceConfig& d,
                                     std::vector<DeviceRegistry::LinController>& out) {
  for (std::size_t i = 0; i < d.lin.size(); ++i) {
    const std::size_t bus = *bus_index(d.lin[i]);
    if (buses_[bus].lin == nullptr) {  // checked against the bus as it runs
      return fail(Errc::bad_argument,
                  fmt::format("device {}: bus {} is not a LIN bus", d.name, d.lin[i]),
                  place(d.line));
    }
    // Offline until an application initializes and starts it, as on a real adapter.
    out.push_back(DeviceRegistry::LinController{
        fmt::format("{}:{}", d.name, d.controllers.size() + i), bus,
        std::make_shared<ixxat::LinLine>(scheduler_, *buses_[bus].lin, ixxat::Clocks{},
                                         scheduler_.now())});
  }
  return {};
}

// The module programs its chips itself (XCAN_BITPARAMS from a client, 20 kbit/s until then), so
// the buses' rates are not checked here.
Result<> Simulation::add_xcan(const DeviceConfig& d) {
  DeviceRegistry::Xcan x;
  x.config = d;
  for (const std::string& bus_name : d.controllers) {
    const std::size_t bus = *bus_index(bus_name);
    const BusConfig& bc = config_.buses[bus];
    if (bc.kind != BusKind::can) {
      return fail(Errc::bad_argument,
                  fmt::format("device {}: bus {} is not a classic CAN bus", d.name, bc.name),
                  place(d.line));
    }
    x.buses.push_back(bus);
  }
  if (x.buses.size() != 2) {
    return fail(Errc::bad_argument, fmt::format("device {}: an X-CAN-2i has 2 interfaces", d.name),
                place(d.line));
  }
  const bool low0 = config_.buses[x.buses[0]].low_speed;
  const bool low1 = config_.buses[x.buses[1]].low_speed;
  if (low0 && !low1) {
    return fail(Errc::bad_argument,
                fmt::format("device {}: no X-CAN-2i variant has interface 0 low-speed and 1 "
                            "high-speed",
                            d.name),
                place(d.line));
  }
  const auto variant = low0   ? model::sorcus::XcanVariant::f
                       : low1 ? model::sorcus::XcanVariant::m
                              : model::sorcus::XcanVariant::h;
  x.device = std::make_shared<XcanDevice>(d.name, scheduler_, variant);
  x.device->module().set_buffer_load_time(d.buffer_load_ns);
  if (!d.mdd_version.empty()) {
    x.device->module().set_mdd_version(
        model::sorcus::MddVersion::parse(d.mdd_version).value_or(model::sorcus::kMdd3C));
  }
  for (unsigned i = 0; i < 2; ++i) {
    x.device->module().connect(i, *buses_[x.buses[i]].can);
  }
  devices_.add_xcan(std::move(x));
  return {};
}

// The driver programs the 82527 from the EEPROM at sl064_config_module (20 kbit/s from the
// factory), so the bus's rate is not checked here. The state file: the configured one, else
// $STATE_DIRECTORY/NAME.eeprom under systemd, else none.
Result<> Simulation::add_slcan(const DeviceConfig& d) {
  const std::size_t bus = *bus_index(d.controllers.at(0));
  const BusConfig& bc = config_.buses[bus];
  if (bc.kind != BusKind::can || bc.low_speed) {
    return fail(
        Errc::bad_argument,
        fmt::format("device {}: bus {} is not a high-speed classic CAN bus", d.name, bc.name),
        place(d.line));
  }
  if (d.slot < 0 || d.slot > 5 || devices_.find_slcan_slot(static_cast<unsigned>(d.slot))) {
    return fail(Errc::exists, fmt::format("device {}: slot {} is not free", d.name, d.slot),
                place(d.line));
  }
  std::string state = d.eeprom;
  if (state.empty()) {
    if (const char* dir = std::getenv("STATE_DIRECTORY"); dir != nullptr && *dir != '\0') {
      // systemd may pass several directories separated by ':'; the first is ours.
      const std::string first(dir, std::strcspn(dir, ":"));
      state = fmt::format("{}/{}.eeprom", first, d.name);
    }
  }
  auto device =
      std::make_shared<SlcanDevice>(d.name, scheduler_, static_cast<uint8_t>(d.slot), state);
  if (auto loaded = device->load(); !loaded) {
    return fail(loaded.error().code,
                fmt::format("device {}: EEPROM state: {}", d.name, loaded.error().text),
                place(d.line));
  }
  device->module().connect(*buses_[bus].can);
  devices_.add_slcan(DeviceRegistry::Slcan{d, bus, std::move(device)});
  return {};
}

Simulation::DeviceLease Simulation::add_ephemeral(std::string name, std::size_t bus,
                                                  HostedNode& node, uint32_t owner_pid) {
  if (config_.remote(config_.buses[bus])) {
    remote_->name_node(node, name);
  }
  // The next device of a name replaces the history of the last one.
  gone_nodes_.forget(name);
  devices_.add_ephemeral(name, bus, node, owner_pid);
  return DeviceLease(this, std::move(name));
}

Simulation::DeviceLease Simulation::add_vci_device(std::string name, std::size_t bus,
                                                   uint32_t owner_pid) {
  // Powered on at the last whole microsecond: the time stamps of every adapter then tick
  // together (1 us), and the same frame carries the same time stamp on all of them.
  const int64_t now_ns = scheduler_.now().ns();
  const SimTime power_on = SimTime::from_ns(now_ns - now_ns % 1000);
  // The next device of a name replaces the history of the last one.
  gone_nodes_.forget(name);
  if (buses_[bus].lin != nullptr) {  // an adapter with one LIN controller
    devices_.add_lin_ephemeral(
        name, bus, owner_pid,
        std::make_shared<ixxat::LinLine>(scheduler_, *buses_[bus].lin, ixxat::Clocks{}, power_on));
    return DeviceLease(this, std::move(name));
  }
  HostedNode& node = nodes_.spare(bus);
  buses_[bus].can->reset_stats(node.node());  // a pooled node: its history is an earlier device's
  if (config_.remote(config_.buses[bus])) {
    remote_->name_node(node, name);
  }
  auto line = std::make_shared<ixxat::CanLine>(scheduler_, node, ixxat::Clocks{}, power_on);
  line->set_low_speed(config_.buses[bus].low_speed);
  devices_.add_ephemeral(name, bus, node, owner_pid, std::move(line));
  return DeviceLease(this, std::move(name));
}

void Simulation::remove_ephemeral(const std::string& name) {
  // Faults that name the device end with it; its node, kept for a later device, comes back
  // plugged in and on its nominal clock. Its counter timeline stays readable.
  if (const DeviceRegistry::Ephemeral* e = devices_.find_ephemeral(name)) {
    scenarios_.device_gone(fmt::format("device {}", e->name), e->bus, *e->node);
    gone_nodes_.keep(e->name, e->bus, scheduler_.now(),
                     buses_[e->bus].can->stats(e->node->node()).timeline);
  }
  devices_.remove_ephemeral(name);
}

Simulation::DeviceLease::~DeviceLease() {
  if (sim_ != nullptr) {
    sim_->remove_ephemeral(name_);
  }
}

}  // namespace canemu::daemon
