#include "canemu/daemon/world/simulation.hpp"

#include <sys/socket.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <tuple>

#include <fmt/format.h>

#include "canemu/daemon/bridges/dds_bridge.hpp"
#include "canemu/daemon/bridges/lcm_bridge.hpp"
#include "canemu/daemon/base/log.hpp"
#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/firmware_model/adapters/ixxat/lin_line.hpp"
#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

namespace canemu::daemon {

namespace {

// "BUS/NAME" as the bus's name and the node's; a bare NAME: no bus.
std::pair<std::string_view, std::string_view> split_lin_name(std::string_view name) {
  const auto slash = name.find('/');
  if (slash == std::string_view::npos) {
    return {{}, name};
  }
  return {name.substr(0, slash), name.substr(slash + 1)};
}

}  // namespace

using namespace canemu::model;

std::optional<HostedNodeSettings> controller_timing(bool fd, uint32_t bitrate,
                                                    uint32_t data_bitrate, uint32_t sample_point) {
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
    if (auto refused = refused_family(AF_INET)) {
      return tl::unexpected(std::vector<std::string>{
          fmt::format("{}: [distributed]: {}", sim->config_.source, *refused)});
    }
    if (!open_remote) {
      return tl::unexpected(std::vector<std::string>{
          fmt::format("{}: [distributed]: this program cannot reach other daemons", sim->config_.source)});
    }
    auto link = open_remote(*sim, sim->config_);
    if (!link) {
      return tl::unexpected(std::vector<std::string>{
          fmt::format("{}: [distributed]: {}", sim->config_.source, link.error())});
    }
    sim->remote_ = std::move(*link);
  }
  for (const BusConfig& b : sim->config_.buses) {
    sim->add_bus(b);
  }
  for (const DeviceConfig& d : sim->config_.devices) {
    if (auto error = sim->add_device(d)) {
      errors.push_back(*error);
    }
  }
  // The configuration reader checked that each node's bus is a LIN bus.
  for (const LinNodeConfig& n : sim->config_.lin_nodes) {
    const std::size_t bus = *sim->bus_index(n.bus);
    sim->lin_nodes_.push_back(
        make_lin_node(n, bus, *sim->lin_buses_[bus], sim->config_.buses[bus].bitrate));
  }
  for (const RecorderConfig& r : sim->config_.recorders) {
    if (auto error = sim->add_recorder(r)) {
      errors.push_back(*error);
    }
  }
  for (const BridgeConfig& b : sim->config_.bridges) {
    if (auto added = sim->add_bridge(b); !added) {
      errors.push_back(fmt::format("{}:{}: {}", sim->config_.source, b.line, added.error()));
    }
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  return sim;
}

std::optional<HostedNodeSettings> Simulation::bus_timing(std::size_t bus) const {
  const BusConfig& bc = config_.buses[bus];
  return controller_timing(bc.kind == BusKind::can_fd, bc.bitrate,
                           bc.data_bitrate != 0 ? bc.data_bitrate : bc.bitrate, bc.sample_point);
}

std::optional<std::string> Simulation::add_recorder(const RecorderConfig& r) {
  const std::size_t bus = *bus_index(r.bus);
  const BusConfig& bc = config_.buses[bus];
  if (lin_buses_[bus] != nullptr) {
    auto recorder = Recorder::start_lin(r, bus, *lin_buses_[bus]);
    if (!recorder) {
      return fmt::format("{}:{}: {}", config_.source, r.line, recorder.error());
    }
    recorders_.push_back(std::move(*recorder));
    return std::nullopt;
  }
  const auto timing = bus_timing(bus);
  if (!timing) {
    return fmt::format("{}:{}: recorder of {}: no controller runs at {} bit/s", config_.source,
                       r.line, r.bus, bc.bitrate);
  }
  auto recorder = Recorder::start(r, bus, nodes_.spare(bus), *timing);
  if (!recorder) {
    return fmt::format("{}:{}: {}", config_.source, r.line, recorder.error());
  }
  recorders_.push_back(std::move(*recorder));
  return std::nullopt;
}

tl::expected<Bridge*, std::string> Simulation::add_bridge(const BridgeConfig& b) {
  const auto bus = bus_index(b.bus);
  if (b.kind == "lcm") {
    if (!bus) {
      return tl::unexpected(fmt::format("no bus is named \"{}\"", b.bus));
    }
    if (find_bridge(BridgeKind::lcm, b.bus) != nullptr) {
      return tl::unexpected(fmt::format("{} has an LCM bridge already", b.bus));
    }
    const std::string url = b.url.empty() ? std::string(kDefaultLcmUrl) : b.url;
    const std::string prefix =
        b.channel_prefix.empty() ? default_lcm_prefix(b.bus) : b.channel_prefix;
    for (const auto& other : bridges_) {
      if (other->kind() == BridgeKind::lcm && other->options().url == url &&
          other->options().channel_prefix == prefix) {
        return tl::unexpected(fmt::format(
            "the LCM bridge of {} uses the channels {}* on {} already (their frames would loop)",
            other->options().bus, prefix, url));
      }
    }
    if (auto refused = refused_family(AF_INET)) {
      return tl::unexpected("LCM bridge of " + b.bus + ": " + *refused);
    }
    auto transport = open_lcm(b.bus, url, prefix);
    if (!transport) {
      return tl::unexpected(transport.error());
    }
    BridgeConfig resolved = b;
    resolved.url = url;
    resolved.channel_prefix = prefix;
    return add_bridge(resolved, std::move(*transport));
  }
  if (b.kind == "dds") {
    if (!bus) {
      return tl::unexpected(fmt::format("no bus is named \"{}\"", b.bus));
    }
    if (find_bridge(BridgeKind::dds, b.bus) != nullptr) {
      return tl::unexpected(fmt::format("{} has a DDS bridge already", b.bus));
    }
    DdsOptions o;
    o.domain = b.domain;
    o.partition = b.partition.empty() ? std::string(kDefaultDdsPartition) : b.partition;
    o.topic_prefix = b.channel_prefix.empty() ? default_dds_prefix(b.bus) : b.channel_prefix;
    o.ros2 = b.ros2;
    const std::string locator = dds_locator(o);
    for (const auto& other : bridges_) {
      if (other->kind() == BridgeKind::dds && other->options().channel_prefix == o.topic_prefix) {
        const auto theirs = parse_dds_locator(other->options().url);
        if (theirs && theirs->domain == o.domain && theirs->partition == o.partition) {
          return tl::unexpected(fmt::format(
              "the DDS bridge of {} uses the topics {}* in domain {}, partition {} already "
              "(their frames would loop)",
              other->options().bus, o.topic_prefix, o.domain, o.partition));
        }
      }
    }
    if (auto refused = refused_family(AF_INET)) {
      return tl::unexpected("DDS bridge of " + b.bus + ": " + *refused);
    }
    auto transport = open_dds(b.bus, o);
    if (!transport) {
      return tl::unexpected(transport.error());
    }
    BridgeConfig resolved = b;
    resolved.url = locator;
    resolved.channel_prefix = o.topic_prefix;
    return add_bridge(resolved, std::move(*transport));
  }
  auto port = open_can_raw(b.interface);
  if (!port) {
    return tl::unexpected("bridge to " + port.error());
  }
  const bool fd_bus = bus && config_.buses[*bus].kind == BusKind::can_fd;
  const auto mtu = interface_mtu(port->get(), b.interface);
  auto added = add_bridge(b, std::move(*port));
  if (added && mtu) {
    if (const auto warning = mtu_warning(b.interface, b.bus, fd_bus, *mtu)) {
      log::warning("bridge to {}: {}", b.interface, *warning);
    }
  }
  return added;
}

tl::expected<Bridge*, std::string> Simulation::add_bridge(const BridgeConfig& b,
                                                          ipc::UniqueFd port) {
  for (const auto& other : bridges_) {
    if (other->kind() == BridgeKind::socketcan && other->options().interface == b.interface) {
      return tl::unexpected(fmt::format("{} is bridged to {} already (its frames would loop)",
                                        b.interface, other->options().bus));
    }
  }
  return add_bridge(b, std::make_unique<SocketCanTransport>(b.interface, std::move(port)));
}

tl::expected<Bridge*, std::string> Simulation::add_bridge(
    const BridgeConfig& b, std::unique_ptr<BridgeTransport> transport) {
  const auto bus = bus_index(b.bus);
  if (!bus) {
    return tl::unexpected(fmt::format("no bus is named \"{}\"", b.bus));
  }
  const bool lcm = b.kind == "lcm";
  const bool dds = b.kind == "dds";
  const BusConfig& bc = config_.buses[*bus];
  if (bc.kind == BusKind::lin) {
    return tl::unexpected(fmt::format("\"{}\" is a LIN bus; {} bridges join CAN buses", b.bus,
                                      lcm   ? "LCM"
                                      : dds ? "DDS"
                                            : "SocketCAN"));
  }
  const auto timing = bus_timing(*bus);
  if (!timing) {
    return tl::unexpected(fmt::format("no controller runs bus {} at {} bit/s", b.bus, bc.bitrate));
  }
  BridgeOptions o;
  o.kind = lcm ? BridgeKind::lcm : dds ? BridgeKind::dds : BridgeKind::socketcan;
  o.bus = b.bus;
  o.interface = b.interface;
  o.error_frames = lcm || dds || b.error_frames;  // LCM, DDS: always (errors and states)
  o.restart_ms = b.restart_ms;
  o.fd = bc.kind == BusKind::can_fd;
  o.url = b.url;
  o.channel_prefix = b.channel_prefix;
  bridges_.push_back(
      Bridge::start(std::move(o), *bus, nodes_.spare(*bus), *timing, std::move(transport)));
  return bridges_.back().get();
}

Bridge* Simulation::find_bridge(BridgeKind kind, const std::string& name) const {
  for (const auto& b : bridges_) {
    if (b->kind() == kind &&
        (kind == BridgeKind::socketcan ? b->options().interface : b->options().bus) == name) {
      return b.get();
    }
  }
  return nullptr;
}

bool Simulation::remove_bridge(const std::string& interface,
                               const std::function<void(Bridge&)>& before) {
  Bridge* found = find_bridge(BridgeKind::socketcan, interface);
  return found != nullptr && remove(found, before);
}

bool Simulation::remove_bus_bridge(BridgeKind kind, const std::string& bus,
                                   const std::function<void(Bridge&)>& before) {
  Bridge* found = find_bridge(kind, bus);
  return found != nullptr && remove(found, before);
}

bool Simulation::remove(Bridge* bridge, const std::function<void(Bridge&)>& before) {
  for (auto it = bridges_.begin(); it != bridges_.end(); ++it) {
    if (it->get() == bridge) {
      if (before) {
        before(**it);
      }
      bridges_.erase(it);
      return true;
    }
  }
  return false;
}

std::vector<std::string> Simulation::flush_recorders() {
  std::vector<std::string> news;
  for (auto& r : recorders_) {
    if (r->flush()) {
      news.push_back(fmt::format("recorder of {}: {}; frames are being lost ({} so far)",
                                 r->config().bus, r->writer().error(), r->writer().lost()));
    }
  }
  return news;
}

void Simulation::add_bus(const BusConfig& b) {
  buses_.push_back(std::make_unique<CanBus>(scheduler_, b.name));
  std::unique_ptr<lin::LinBus> lin_bus;
  if (b.kind == BusKind::lin) {
    lin::Layout layout;
    layout.bitrate = b.bitrate;
    lin_bus = std::make_unique<lin::LinBus>(scheduler_, layout);
  }
  lin_buses_.push_back(std::move(lin_bus));
  NodePool::Maker make;
  if (config_.remote(b)) {
    make = [this, bus = buses_.size() - 1, fd = b.kind == BusKind::can_fd](CanBus& placeholder) {
      return remote_->make_node(bus, placeholder, fd);
    };
  }
  nodes_.add_bus(*buses_.back(), b.kind == BusKind::can_fd, std::move(make));
  scenarios_.add_bus(*buses_.back(), b, lin_buses_.back().get());
}

std::optional<ScenarioRunner::LinNodeRef> Simulation::find_lin_node(std::string_view name) const {
  for (const DeviceRegistry::Configured& d : devices_.configured()) {
    for (const DeviceRegistry::LinController& c : d.lin) {
      if (c.name == name) {
        return ScenarioRunner::LinNodeRef{c.bus, c.line->controller().node()};
      }
    }
  }
  for (const DeviceRegistry::LinEphemeral& e : devices_.lin_ephemeral()) {
    if (e.name == name || e.name + ":0" == name) {
      return ScenarioRunner::LinNodeRef{e.bus, e.line->controller().node()};
    }
  }
  // Simulated nodes: "BUS/NAME", or a NAME only one bus has.
  const auto [bus, node] = split_lin_name(name);
  std::optional<ScenarioRunner::LinNodeRef> found;
  for (const SimulatedLinNode& n : lin_nodes_) {
    if (n.name == node && (bus.empty() || config_.buses[n.bus].name == bus)) {
      if (found) {
        return std::nullopt;  // on several buses
      }
      found = ScenarioRunner::LinNodeRef{n.bus, n.ecu->node()};
    }
  }
  return found;
}

std::optional<std::size_t> Simulation::bus_index(std::string_view name) const {
  for (std::size_t i = 0; i < config_.buses.size(); ++i) {
    if (config_.buses[i].name == name) {
      return i;
    }
  }
  return std::nullopt;
}

std::optional<std::string> Simulation::add_device(const DeviceConfig& d) {
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
      return fmt::format("{}:{}: device {}: bus {} is a LIN bus; a CAN controller cannot sit on it",
                         config_.source, d.line, d.name, bc.name);
    }
    const bool fd = d.model != DeviceModel::ixxat_usb_to_can;
    const auto timing = controller_timing(
        fd, bc.bitrate, bc.data_bitrate != 0 ? bc.data_bitrate : bc.bitrate, bc.sample_point);
    if (!timing) {
      return fmt::format("{}:{}: device {}: {} cannot run bus {} at {} bit/s", config_.source,
                         d.line, d.name, fd ? "the CAN FD controller" : "an SJA1000 at 16 MHz",
                         bc.name, bc.bitrate);
    }
    buses.push_back(bus);
  }
  std::vector<DeviceRegistry::LinController> lin;
  if (auto error = lin_controllers(d, lin)) {
    return error;
  }
  std::vector<DeviceRegistry::Controller> controllers;
  for (std::size_t i = 0; i < buses.size(); ++i) {
    DeviceRegistry::Controller c;
    c.name = fmt::format("{}:{}", d.name, i);
    c.bus = buses[i];
    // The controller stays in reset (off the bus) until an application initializes and starts
    // it through the VCI, as on a real adapter.
    CanBus& bus = *buses_[c.bus];
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
  return std::nullopt;
}

std::optional<std::string> Simulation::lin_controllers(
    const DeviceConfig& d, std::vector<DeviceRegistry::LinController>& out) {
  for (std::size_t i = 0; i < d.lin.size(); ++i) {
    const std::size_t bus = *bus_index(d.lin[i]);
    if (lin_buses_[bus] == nullptr) {  // checked against the bus as it runs
      return fmt::format("{}:{}: device {}: bus {} is not a LIN bus", config_.source, d.line,
                         d.name, d.lin[i]);
    }
    // Offline until an application initializes and starts it, as on a real adapter.
    out.push_back(DeviceRegistry::LinController{
        fmt::format("{}:{}", d.name, d.controllers.size() + i), bus,
        std::make_shared<ixxat::LinLine>(scheduler_, *lin_buses_[bus], ixxat::Clocks{},
                                         scheduler_.now())});
  }
  return std::nullopt;
}

// The module programs its chips itself (XCAN_BITPARAMS from a client, 20 kbit/s until then), so
// the buses' rates are not checked here.
std::optional<std::string> Simulation::add_xcan(const DeviceConfig& d) {
  DeviceRegistry::Xcan x;
  x.config = d;
  for (const std::string& bus_name : d.controllers) {
    const std::size_t bus = *bus_index(bus_name);
    const BusConfig& bc = config_.buses[bus];
    if (bc.kind != BusKind::can) {
      return fmt::format("{}:{}: device {}: bus {} is not a classic CAN bus", config_.source,
                         d.line, d.name, bc.name);
    }
    x.buses.push_back(bus);
  }
  if (x.buses.size() != 2) {
    return fmt::format("{}:{}: device {}: an X-CAN-2i has 2 interfaces", config_.source, d.line,
                       d.name);
  }
  const bool low0 = config_.buses[x.buses[0]].low_speed;
  const bool low1 = config_.buses[x.buses[1]].low_speed;
  if (low0 && !low1) {
    return fmt::format(
        "{}:{}: device {}: no X-CAN-2i variant has interface 0 low-speed and 1 "
        "high-speed",
        config_.source, d.line, d.name);
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
    x.device->module().connect(i, *buses_[x.buses[i]]);
  }
  devices_.add_xcan(std::move(x));
  return std::nullopt;
}

// The driver programs the 82527 from the EEPROM at sl064_config_module (20 kbit/s from the
// factory), so the bus's rate is not checked here. The state file: the configured one, else
// $STATE_DIRECTORY/NAME.eeprom under systemd, else none.
std::optional<std::string> Simulation::add_slcan(const DeviceConfig& d) {
  const std::size_t bus = *bus_index(d.controllers.at(0));
  const BusConfig& bc = config_.buses[bus];
  if (bc.kind != BusKind::can || bc.low_speed) {
    return fmt::format("{}:{}: device {}: bus {} is not a high-speed classic CAN bus",
                       config_.source, d.line, d.name, bc.name);
  }
  if (d.slot < 0 || d.slot > 5 || devices_.find_slcan_slot(static_cast<unsigned>(d.slot))) {
    return fmt::format("{}:{}: device {}: slot {} is not free", config_.source, d.line, d.name,
                       d.slot);
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
    return fmt::format("{}:{}: device {}: EEPROM state: {}", config_.source, d.line, d.name,
                       loaded.error());
  }
  device->module().connect(*buses_[bus]);
  devices_.add_slcan(DeviceRegistry::Slcan{d, bus, std::move(device)});
  return std::nullopt;
}

namespace {

bool same(const BusConfig& a, const BusConfig& b) {
  return a.name == b.name && a.kind == b.kind && a.bitrate == b.bitrate &&
         a.sample_point == b.sample_point && a.data_bitrate == b.data_bitrate && a.owner == b.owner;
}

bool same(const DistributedConfig& a, const DistributedConfig& b) {
  return a.enabled == b.enabled && a.name == b.name && a.domain == b.domain &&
         a.partition == b.partition && a.heartbeat_ms == b.heartbeat_ms &&
         a.timeout_ms == b.timeout_ms;
}

bool same(const DeviceConfig& a, const DeviceConfig& b) {
  return a.name == b.name && a.model == b.model && a.controllers == b.controllers &&
         a.lin == b.lin && a.mdd_version == b.mdd_version && a.buffer_load_ns == b.buffer_load_ns &&
         a.slot == b.slot && a.eeprom == b.eeprom;
}

bool same(const std::vector<RecorderConfig>& a, const std::vector<RecorderConfig>& b) {
  const auto key = [](const RecorderConfig& r) {
    return std::tie(r.bus, r.path, r.pcap, r.max_size, r.max_files, r.errors);
  };
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [&](const auto& x, const auto& y) { return key(x) == key(y); });
}

template <class T>
const T* find_named(const std::vector<T>& items, const std::string& name) {
  for (const T& item : items) {
    if (item.name == name) {
      return &item;
    }
  }
  return nullptr;
}

}  // namespace

ReloadReport Simulation::reload(const Config& fresh) {
  ReloadReport r;
  // What cannot change while the simulation runs.
  if (fresh.simulation.time.mode != config_.simulation.time.mode ||
      fresh.simulation.time.scale != config_.simulation.time.scale) {
    r.refused.push_back(fmt::format("simulation.time: stays {} (a restart changes it)",
                                    to_string(config_.simulation.time)));
  }
  if (fresh.simulation.seed != config_.simulation.seed) {
    r.refused.push_back(
        fmt::format("simulation.seed: stays {} (a restart changes it)", config_.simulation.seed));
  }
  if (!same(fresh.distributed, config_.distributed)) {
    r.refused.push_back("distributed: stays as it was (a restart changes it)");
  }
  for (const BusConfig& old : config_.buses) {
    const BusConfig* now = find_named(fresh.buses, old.name);
    if (now == nullptr) {
      r.refused.push_back(
          fmt::format("bus {}: still there (buses are removed by a restart)", old.name));
    } else if (!same(old, *now)) {
      r.refused.push_back(
          fmt::format("bus {}: keeps its settings ({} at {} bit/s; a restart changes them)",
                      old.name, to_string(old.kind), old.bitrate));
    }
  }
  for (const DeviceConfig& old : config_.devices) {
    const DeviceConfig* now = find_named(fresh.devices, old.name);
    if (now == nullptr) {
      r.refused.push_back(
          fmt::format("device {}: still there (devices are removed by a restart)", old.name));
    } else if (!same(old, *now)) {
      r.refused.push_back(
          fmt::format("device {}: keeps its settings (a restart changes them)", old.name));
    }
  }
  const auto bridge_key = [](const BridgeConfig& b) {
    return std::tie(b.kind, b.bus, b.interface, b.error_frames, b.restart_ms, b.url,
                    b.channel_prefix);
  };
  if (!std::equal(fresh.bridges.begin(), fresh.bridges.end(), config_.bridges.begin(),
                  config_.bridges.end(),
                  [&](const auto& x, const auto& y) { return bridge_key(x) == bridge_key(y); })) {
    r.refused.push_back(
        "bridges: stay as they are (canemu bridge add|remove changes them while running)");
  }
  if (!same(fresh.recorders, config_.recorders)) {
    r.refused.push_back("recorders: stay as they are (a restart changes them)");
  }
  // What can: new buses and devices, the security lists, the wake-up tuning.
  for (const BusConfig& b : fresh.buses) {
    if (find_named(config_.buses, b.name) == nullptr) {
      if (!b.owner.empty() && b.owner != config_.distributed.name && !config_.distributed.enabled) {
        r.refused.push_back(fmt::format(
            "bus {}: not added (daemon {} simulates it, and [distributed] needs a restart)", b.name,
            b.owner));
        continue;
      }
      if (config_.remote(b) && config_.simulation.time.mode == TimeMode::stepped) {
        r.refused.push_back(fmt::format(
            "bus {}: not added (in stepped time the remote buses, whose owner's steps are this "
            "daemon's, are set at start)",
            b.name));
        continue;
      }
      config_.buses.push_back(b);
      add_bus(b);
      r.applied.push_back(
          fmt::format("bus {}: added ({} at {} bit/s)", b.name, to_string(b.kind), b.bitrate));
    }
  }
  for (const DeviceConfig& d : fresh.devices) {
    if (find_named(config_.devices, d.name) != nullptr) {
      continue;
    }
    if (devices_.exists(d.name)) {
      r.refused.push_back(fmt::format("device {}: an ephemeral device has that name", d.name));
    } else if (auto error = add_device(d)) {
      r.refused.push_back(*error);
    } else {
      config_.devices.push_back(d);
      devices_.announce(ipc::NotificationKind::device_added, d.name);
      r.applied.push_back(fmt::format("device {}: added", d.name));
    }
  }
  const bool same_lin_nodes =
      fresh.lin_nodes.size() == config_.lin_nodes.size() &&
      std::equal(fresh.lin_nodes.begin(), fresh.lin_nodes.end(), config_.lin_nodes.begin(),
                 [](const LinNodeConfig& a, const LinNodeConfig& b) { return a.same_as(b); });
  if (!same_lin_nodes) {
    r.refused.push_back(
        "lin_node: the simulated LIN nodes stay as they are (a restart changes them)");
  }
  if (fresh.security.allowed_users != config_.security.allowed_users ||
      fresh.security.allowed_groups != config_.security.allowed_groups) {
    config_.security = fresh.security;
    r.applied.push_back("security: allowed users and groups replaced");
  }
  if (fresh.simulation.batch_us != config_.simulation.batch_us ||
      fresh.simulation.spin_us != config_.simulation.spin_us) {
    config_.simulation.batch_us = fresh.simulation.batch_us;
    config_.simulation.spin_us = fresh.simulation.spin_us;
    r.applied.push_back(fmt::format("simulation: batch_us {}, spin_us {}",
                                    config_.simulation.batch_us, config_.simulation.spin_us));
  }
  return r;
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
  if (lin_buses_[bus] != nullptr) {  // an adapter with one LIN controller
    devices_.add_lin_ephemeral(
        name, bus, owner_pid,
        std::make_shared<ixxat::LinLine>(scheduler_, *lin_buses_[bus], ixxat::Clocks{}, power_on));
    return DeviceLease(this, std::move(name));
  }
  HostedNode& node = nodes_.spare(bus);
  buses_[bus]->reset_stats(node.node());  // a pooled node: its history is an earlier device's
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
    scenarios_.device_gone(e->name, e->bus, *e->node);
    gone_nodes_.keep(e->name, e->bus, scheduler_.now(),
                     buses_[e->bus]->stats(e->node->node()).timeline);
  }
  devices_.remove_ephemeral(name);
}

Simulation::DeviceLease::~DeviceLease() {
  if (sim_ != nullptr) {
    sim_->remove_ephemeral(name_);
  }
}

}  // namespace canemu::daemon

namespace canemu::daemon {

// Names are scoped by bus: `name` is "BUS/NAME", or a NAME that only one bus has.
tl::expected<std::vector<SimulatedLinNode>::iterator, std::string> Simulation::find_lin_named(
    std::string_view name) {
  const auto [bus, node] = split_lin_name(name);
  std::vector<std::vector<SimulatedLinNode>::iterator> found;
  for (auto it = lin_nodes_.begin(); it != lin_nodes_.end(); ++it) {
    if (it->name == node && (bus.empty() || config_.buses[it->bus].name == bus)) {
      found.push_back(it);
    }
  }
  if (found.empty()) {
    return tl::unexpected(fmt::format("no simulated LIN node named \"{}\"", name));
  }
  if (found.size() > 1) {
    std::vector<std::string> where;
    for (auto it : found) {
      where.push_back(fmt::format("{}/{}", config_.buses[it->bus].name, it->name));
    }
    return tl::unexpected(fmt::format("LIN nodes named \"{}\" are on several buses: name one as {}",
                                      name, fmt::join(where, " or ")));
  }
  return found.front();
}

tl::expected<std::vector<std::string>, std::vector<std::string>> Simulation::load_lin_nodes(
    std::string_view text, const std::string& source) {
  auto configs = parse_lin_nodes(text, source, config_.buses);
  if (!configs) {
    return tl::unexpected(configs.error());
  }
  std::vector<std::string> errors;
  for (const LinNodeConfig& n : *configs) {
    if (n.schedule.empty()) {
      continue;
    }
    // A bus has one commander: another node (not one this load replaces) running a schedule
    // there is a conflict.
    for (const SimulatedLinNode& other : lin_nodes_) {
      const bool replaced =
          std::any_of(configs->begin(), configs->end(), [&](const LinNodeConfig& c) {
            return c.name == other.name && c.bus == config_.buses[other.bus].name;
          });
      if (!replaced && config_.buses[other.bus].name == n.bus &&
          !other.ecu->running_schedule().empty()) {
        errors.push_back(fmt::format(
            "{}:{}: lin_node {}: {} is the commander of {} already (running {}); stop its "
            "schedule first",
            source, n.line, n.name, other.name, n.bus, other.ecu->running_schedule()));
      }
    }
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  std::vector<std::string> names;
  for (const LinNodeConfig& n : *configs) {
    // Names are scoped by bus: a node of this name on another bus stays.
    const std::size_t bus = *bus_index(n.bus);
    std::erase_if(lin_nodes_, [&](const SimulatedLinNode& old) {
      return old.name == n.name && old.bus == bus;  // replaced: it leaves the bus first
    });
    lin_nodes_.push_back(make_lin_node(n, bus, *lin_buses_[bus], config_.buses[bus].bitrate));
    names.push_back(fmt::format("{}/{}", n.bus, n.name));
  }
  return names;
}

std::optional<std::string> Simulation::power_lin_node(const std::string& name, bool on) {
  auto found = find_lin_named(name);
  if (!found) {
    return found.error();
  }
  auto it = *found;
  it->ecu->set_powered(on);
  return std::nullopt;
}

std::optional<std::string> Simulation::run_lin_schedule(const std::string& name,
                                                        const std::string& table) {
  auto found = find_lin_named(name);
  if (!found) {
    return found.error();
  }
  auto it = *found;
  if (table.empty()) {
    it->ecu->stop_schedule();
    return std::nullopt;
  }
  for (const SimulatedLinNode& other : lin_nodes_) {
    if (&other != &*it && other.bus == it->bus && !other.ecu->running_schedule().empty()) {
      return fmt::format("{} is the commander of {} already (running {}); stop its schedule first",
                         other.name, config_.buses[it->bus].name, other.ecu->running_schedule());
    }
  }
  if (!it->ecu->run_schedule(table)) {
    return fmt::format("node {} has no schedule table named \"{}\"", name, table);
  }
  return std::nullopt;
}

std::optional<std::string> Simulation::remove_lin_node(const std::string& name) {
  auto found = find_lin_named(name);
  if (!found) {
    return found.error();
  }
  auto it = *found;
  lin_nodes_.erase(it);
  return std::nullopt;
}

}  // namespace canemu::daemon
