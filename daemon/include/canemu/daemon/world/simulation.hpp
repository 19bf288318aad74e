// The emulated world canemud runs: one CanBus per configured bus, one controller model per
// configured adapter controller with its adapter firmware, all on one scheduler (one simulation
// island). Simulation builds the world from the configuration, grows it on reload, and
// composes the parts that work on it:
//   DeviceRegistry  the devices and their names, VCI ids, the device generation
//   NodePool        the nodes kept for ephemeral devices
//   ScenarioRunner  the fault scenarios
// What the protocol reports of it is filled in status.hpp.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/bridges/bridge.hpp"
#include "canemu/daemon/bridges/recorder.hpp"
#include "canemu/daemon/bridges/socketcan_bridge.hpp"
#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/restbus/can_ecu.hpp"
#include "canemu/daemon/world/device_registry.hpp"
#include "canemu/daemon/world/gone_nodes.hpp"
#include "canemu/daemon/world/lin_nodes.hpp"
#include "canemu/daemon/world/node_pool.hpp"
#include "canemu/daemon/world/remote_buses.hpp"
#include "canemu/daemon/world/scenario_runner.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/lin_bus.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::daemon {

// The rates a node runs at (bit/s, sample point in per mille).
struct NodeRates {
  uint32_t bitrate = 0;
  uint32_t data_bitrate = 0;  // the data phase's; 0 on a classic controller
  uint32_t sample_point = 0;
};
// The rates of a node on bus `bus`: what `asked` gives, the bus's where it gives 0. A CAN FD
// controller (`fd`) runs its data phase at the bus's data_bitrate, or at its bit rate where the
// bus has no bit-rate switch (data_bitrate 0); a classic controller has none. The one place
// where a bus's configuration becomes a node's rates.
NodeRates node_rates(const BusConfig& bus, bool fd, const NodeRates& asked = {});
// The timing a controller needs for `rates`: for an SJA1000 (`fd` false) the BTR0/BTR1 values
// and their decoded timing; for the CAN FD controller the nominal and the data timing. Nothing
// if the clock cannot make a rate exactly. Only the timing fields of the result are set.
std::optional<model::HostedNodeSettings> node_timing(bool fd, const NodeRates& rates);

// A simulated CAN node ([[can_node]], docs/restbus.md) on bus `bus` (the configuration's index).
struct SimulatedCanNode {
  std::size_t bus = 0;
  std::unique_ptr<restbus::CanEcu> ecu;
};

// What a configuration reload did and what it left as it was, one line each.
struct ReloadReport {
  std::vector<std::string> applied;
  std::vector<std::string> refused;
};

class Simulation {
 public:
  // `open_remote` opens the link to other daemons for [distributed] (canemud passes
  // Distributed::open_remote); without it, a configuration with [distributed] is refused.
  static tl::expected<std::unique_ptr<Simulation>, std::vector<std::string>> build(
      const Config& config, const RemoteBusesOpener& open_remote = {});
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  model::SimScheduler& scheduler() { return scheduler_; }
  const model::SimScheduler& scheduler() const { return scheduler_; }
  const Config& config() const { return config_; }
  // Bus i is config().buses[i]; both only grow. A bus runs on one engine: a CanBus for a CAN or
  // CAN FD bus, a LinBus for a LIN bus.
  std::size_t bus_count() const { return buses_.size(); }
  // The CAN engine of bus i, which must be a CAN or CAN FD bus (lin_bus(i) is nullptr).
  model::CanBus& bus(std::size_t i) { return *buses_[i].can; }
  const model::CanBus& bus(std::size_t i) const { return *buses_[i].can; }
  std::optional<std::size_t> bus_index(std::string_view name) const;
  const BusConfig& bus_config(std::size_t i) const { return config_.buses[i]; }
  // The LIN engine of bus i; nullptr unless it is a LIN bus.
  model::lin::LinBus* lin_bus(std::size_t i) { return buses_[i].lin.get(); }
  const model::lin::LinBus* lin_bus(std::size_t i) const { return buses_[i].lin.get(); }

  // The simulated LIN nodes ([[lin_node]]), in configuration order.
  const std::vector<SimulatedLinNode>& lin_nodes() const { return lin_nodes_; }
  // ---- simulated LIN nodes at run time (`canemu lin`, docs/lin.md) ----
  // Loads [[lin_node]] tables: a node of a name that runs on that bus already is replaced
  // (names are scoped by bus: another bus's node of that name stays); a bus keeps at most one
  // commander running a schedule. All or nothing; the nodes loaded ("BUS/NAME"), or every
  // problem.
  tl::expected<std::vector<std::string>, std::vector<std::string>> load_lin_nodes(
      std::string_view text, const std::string& source);
  // Switches node `name` ("BUS/NAME", or a NAME only one bus has) on or off, runs its schedule
  // table `table` ("": stops its schedule), or removes it; the reason when it cannot.
  Result<> power_lin_node(const std::string& name, bool on);
  Result<> run_lin_schedule(const std::string& name, const std::string& table);
  Result<> remove_lin_node(const std::string& name);

  // ---- simulated CAN nodes ([[can_node]], docs/restbus.md) ----
  // In configuration order, then as loaded.
  const std::vector<SimulatedCanNode>& can_nodes() const { return can_nodes_; }
  // Loads [[can_node]] tables: each node starts on a spare node of its bus; one of a name that
  // runs on that bus already is replaced (names are scoped by bus). All or nothing; the nodes
  // loaded ("BUS/NAME"), or every problem.
  tl::expected<std::vector<std::string>, std::vector<std::string>> load_can_nodes(
      std::string_view text, const std::string& source);
  // The node `name` ("BUS/NAME", or a NAME only one bus has), or the reason there is none.
  Result<restbus::CanEcu*> can_node(std::string_view name);
  // The node that sends message `message` on bus `bus` (a bus's message names are unique), or
  // the reason there is none.
  Result<restbus::CanEcu*> can_message(std::string_view bus, std::string_view message);
  // Removes node `name` (its node leaves the bus); the reason when it cannot.
  Result<> remove_can_node(std::string_view name);

  // The timing of a node on bus `bus` at the bus's rates (nothing if no controller runs them).
  std::optional<model::HostedNodeSettings> bus_timing(std::size_t bus) const;

  DeviceRegistry& devices() { return devices_; }
  const DeviceRegistry& devices() const { return devices_; }
  ScenarioRunner& scenarios() { return scenarios_; }
  const ScenarioRunner& scenarios() const { return scenarios_; }

  // Applies what can change while running (new buses and devices, the security lists, the
  // wake-up tuning) from `fresh`, a configuration already checked, and reports the rest.
  ReloadReport reload(const Config& fresh);

  // ---- ephemeral devices ----
  // A stopped node on bus `bus`, ready to start (an SJA1000 on a classic bus, the CAN FD
  // controller on a CAN FD bus): see NodePool::spare.
  model::HostedNode& spare_node(std::size_t bus) { return nodes_.spare(bus); }
  // Keeps an ephemeral device registered; when it ends, the device's faults end and it goes.
  class DeviceLease {
   public:
    DeviceLease() = default;
    DeviceLease(Simulation* sim, std::string name) : sim_(sim), name_(std::move(name)) {}
    DeviceLease(DeviceLease&& o) noexcept
        : sim_(std::exchange(o.sim_, nullptr)), name_(std::move(o.name_)) {}
    DeviceLease& operator=(DeviceLease&& o) noexcept {
      DeviceLease old(std::move(*this));
      sim_ = std::exchange(o.sim_, nullptr);
      name_ = std::move(o.name_);
      return *this;
    }
    ~DeviceLease();

   private:
    Simulation* sim_ = nullptr;
    std::string name_;
  };
  // Registers an ephemeral device on `node` (a spare node of bus `bus`) for as long as the
  // returned lease lives.
  DeviceLease add_ephemeral(std::string name, std::size_t bus, model::HostedNode& node,
                            uint32_t owner_pid);
  // An ephemeral VCI adapter named `name` with one controller on bus `bus` (an SJA1000 on a
  // classic bus, the CAN FD controller on a CAN FD bus, a LIN controller on a LIN bus) and its
  // firmware, listed with the configured adapters while the lease lives.
  DeviceLease add_vci_device(std::string name, std::size_t bus, uint32_t owner_pid);
  // The counter timelines of ephemeral devices' CAN nodes after their devices went: the newest
  // kGoneNodesPerBus per bus, each until a device of its name comes (docs/cli.md, "Gone nodes").
  static constexpr std::size_t kGoneNodesPerBus = GoneNodes::kPerBus;
  const GoneNodes& gone_nodes() const { return gone_nodes_; }

  // ---- recorders ([[recorder]], set at start) ----
  const std::vector<std::unique_ptr<Recorder>>& recorders() const { return recorders_; }
  // Writes what the recorders hold; one line for each recorder that began to lose frames.
  std::vector<std::string> flush_recorders();

  // ---- bridges ([[bridge]] at start, canemu bridge add|remove at run time): SocketCAN, LCM and
  // DDS
  const std::vector<std::unique_ptr<Bridge>>& bridges() const { return bridges_; }
  // A SocketCAN bridge of `b.bus` to `b.interface` over `port` (the interface's socket, or in
  // tests a stand-in); the error says why not (no such bus, a LIN bus, the interface bridged
  // already, no controller for the bus's rate). add_bridge() opens the CAN_RAW socket itself,
  // or for kind "lcm" the LCM instance, for "dds" the DDS participant and topics.
  Result<Bridge*> add_bridge(const BridgeConfig& b, ipc::UniqueFd port);
  Result<Bridge*> add_bridge(const BridgeConfig& b);
  // A bridge of `b.bus` over `transport` (b.kind says which kind it is).
  Result<Bridge*> add_bridge(const BridgeConfig& b, std::unique_ptr<BridgeTransport> transport);
  // Removes the SocketCAN bridge of `interface` (its node leaves the bus); false if there is
  // none. `before` sees it first (the server stops watching its socket).
  bool remove_bridge(const std::string& interface, const std::function<void(Bridge&)>& before = {});
  // Removes the LCM or DDS bridge (`kind`) of bus `bus`, as remove_bridge().
  bool remove_bus_bridge(BridgeKind kind, const std::string& bus,
                         const std::function<void(Bridge&)>& before = {});
  // The SocketCAN bridge of `interface`, or the LCM or DDS bridge of bus `bus`; nullptr if none.
  Bridge* find_bridge(BridgeKind kind, const std::string& name) const;

  // ---- buses across hosts ([distributed], docs/distributed.md); nullptr without it ----
  RemoteBuses* remote() { return remote_.get(); }
  const RemoteBuses* remote() const { return remote_.get(); }

 private:
  bool remove(Bridge* bridge, const std::function<void(Bridge&)>& before);
  explicit Simulation(Config config)
      : config_(std::move(config)),
        nodes_(scheduler_),
        scenarios_(scheduler_, devices_, config_.simulation.seed) {
    scenarios_.find_lin_node = [this](std::string_view name) { return find_lin_node(name); };
    scenarios_.find_can_node = [this](std::string_view name) { return find_can_node(name); };
    scenarios_.find_can_message = [this](std::string_view bus, std::string_view message) {
      return find_can_sender(bus, message);
    };
  }
  // A simulated CAN node by NAME or BUS/NAME, and the one that sends `message` on `bus`.
  std::optional<ScenarioRunner::CanNodeRef> find_can_node(std::string_view name);
  std::optional<ScenarioRunner::CanNodeRef> find_can_sender(std::string_view bus,
                                                            std::string_view message);
  // The simulated CAN node `n` goes: the faults on it end (before it leaves its node).
  void can_node_gone(const SimulatedCanNode& n);
  // A LIN controller ("DEVICE:N", configured or ephemeral) or a simulated LIN node, by name.
  std::optional<ScenarioRunner::LinNodeRef> find_lin_node(std::string_view name) const;
  // A simulated LIN node by "BUS/NAME", or by a NAME that only one bus has; else the reason.
  Result<std::vector<SimulatedLinNode>::iterator> find_lin_named(std::string_view name);

  void add_bus(const BusConfig& b);
  // Builds a device whose buses exist; an error (and nothing added) if a controller cannot run
  // its bus's timing.
  Result<> add_device(const DeviceConfig& d);
  // "FILE:LINE" of the configuration, where an error about line `line` of it is.
  std::string place(uint32_t line) const;
  Result<> add_xcan(const DeviceConfig& d);
  // The device's LIN controllers (config `lin`), on LIN buses that exist.
  Result<> lin_controllers(const DeviceConfig& d, std::vector<DeviceRegistry::LinController>& out);

  Result<> add_recorder(const RecorderConfig& r);
  // Starts [[can_node]] `n` (its bus a CAN bus of this configuration) on a spare node.
  Result<> add_can_node(const CanNodeConfig& n);
  // A simulated CAN node by "BUS/NAME", or by a NAME that only one bus has; else the reason.
  Result<std::vector<SimulatedCanNode>::iterator> find_can_named(std::string_view name);
  Result<> add_slcan(const DeviceConfig& d);
  void remove_ephemeral(const std::string& name);

  // One configured bus as it runs: exactly one of its engines is set.
  struct RunningBus {
    std::unique_ptr<model::CanBus> can;       // a CAN or CAN FD bus
    std::unique_ptr<model::lin::LinBus> lin;  // a LIN bus
  };

  // Declared in the order they depend on each other (and are destroyed in reverse).
  Config config_;
  model::SimScheduler scheduler_;
  std::vector<RunningBus> buses_;
  std::vector<SimulatedLinNode> lin_nodes_;  // on LIN buses (gone before them)
  NodePool nodes_;
  DeviceRegistry devices_;
  GoneNodes gone_nodes_;
  ScenarioRunner scenarios_;
  std::vector<std::unique_ptr<Recorder>> recorders_;  // on nodes_'s nodes, LIN buses
  std::vector<std::unique_ptr<Bridge>> bridges_;      // on nodes_'s nodes
  std::vector<SimulatedCanNode> can_nodes_;           // on nodes_'s nodes
  // Other daemons' nodes on nodes_'s nodes; gone first (nodes_'s remote nodes outlive it).
  std::unique_ptr<RemoteBuses> remote_;
};

}  // namespace canemu::daemon
