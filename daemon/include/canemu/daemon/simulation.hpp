// The emulated world canemud runs: one CanBus per configured bus, one controller model per
// configured adapter controller, all on one scheduler (one simulation island).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/config.hpp"
#include "canemu/daemon/scenario.hpp"
#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "canemu/firmware_model/chips/can_fd/can_fd_controller.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

// The timing a controller needs: for an SJA1000 (`fd` false) the BTR0/BTR1 values for
// `bitrate` and their decoded timing; for the CAN FD controller the nominal timing for
// `bitrate` and the data timing for `data_bitrate`. Nothing if the clock cannot make a rate
// exactly. Only the timing fields of the result are set.
std::optional<model::HostedNodeSettings> controller_timing(bool fd, uint32_t bitrate,
                                                           uint32_t data_bitrate,
                                                           uint32_t sample_point);

// The VCI hardware ID of a configured device: "HW" and six digits from its name, so that it
// stays the same from run to run.
std::string hardware_id(std::string_view device_name);

// What a configuration reload did and what it left as it was, one line each.
struct ReloadReport {
  std::vector<std::string> applied;
  std::vector<std::string> refused;
};

class Simulation {
 public:
  static tl::expected<std::unique_ptr<Simulation>, std::vector<std::string>> build(
      const Config& config);

  model::SimScheduler& scheduler() { return scheduler_; }
  const Config& config() const { return config_; }
  std::size_t bus_count() const { return buses_.size(); }
  model::CanBus& bus(std::size_t i) { return *buses_[i].bus; }

  std::optional<std::size_t> bus_index(std::string_view name) const;
  const BusConfig& bus_config(std::size_t i) const { return config_.buses[i]; }

  // Resolves the scenario's buses and nodes and applies every fault, its times counted from
  // `start`. Nothing is applied when a name does not resolve; the errors say which, with the
  // scenario file's line. The log ("fault: t=...") tells, with the simulated time, when a
  // scenario is applied or cleared, when a bus or node effect fires or ends, and when a frame
  // fault hits its first frame, reaches its count or its window ends (each hit is in the bus
  // trace and the counts, not the log).
  tl::expected<void, std::vector<std::string>> apply_scenario(const Scenario& scenario,
                                                              model::SimTime start);
  // Every fault applied so far, with what it did.
  struct FaultStatus {
    enum class State : uint8_t { pending, active, done, cleared };
    std::string scenario;
    uint32_t line;
    FaultEffect effect;
    std::string target;  // bus, or node
    int64_t at_ns;       // absolute simulated time
    std::optional<int64_t> until_ns;
    uint64_t seen;  // frame effects: matching frames; others: 0
    uint64_t hits;  // frame effects: frames hit; others: times fired
    State state;
  };
  std::vector<FaultStatus> fault_status() const;
  // Clears the faults of the scenario named `name` (empty: of every scenario): frame rules stop
  // matching, scheduled effects do not fire. Effects that fired stay (an unplugged node stays
  // unplugged). Returns the number of scenarios cleared.
  std::size_t clear_scenarios(std::string_view name);

  // Applies what can change while running (new buses and devices, the security lists, the
  // wake-up tuning) from `fresh`, a configuration already checked, and reports the rest.
  ReloadReport reload(const Config& fresh);

  // What `canemu status` shows.
  void fill_status(ipc::StatusReply& reply);
  // What a device list request shows: configured devices, then ephemeral ones.
  void fill_devices(ipc::DeviceListReply& reply) const;

  // ---- VCI ----
  // The adapter firmware of controller `controller` of the VCI device `device` (configured, or
  // ephemeral from add_vci_device); nullptr if there is no such controller. Shared: objects a
  // client opened keep the firmware running after an ephemeral device has gone.
  std::shared_ptr<model::ixxat::CanLine> vci_line(std::string_view device, uint32_t controller);
  // The VCI firmware driving `node`, if a VCI adapter's.
  std::shared_ptr<model::ixxat::CanLine> vci_line_of(const model::HostedNode* node) const;

  // ---- ephemeral devices ----
  // A stopped node on bus `bus`, ready to start (an SJA1000 on a classic bus, the CAN FD
  // controller on a CAN FD bus): one that an earlier ephemeral device left (and that has no
  // frame on the wire), or a new one. Nodes are never removed from a bus,
  // so the number of nodes is the largest number of ephemeral devices alive at once.
  model::HostedNode& spare_node(std::size_t bus);
  bool device_exists(std::string_view name) const;
  // A name no device has: `prefix` followed by a number.
  std::string unique_device_name(std::string_view prefix) const;
  // Registers an ephemeral device for as long as the returned lease lives.
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
  DeviceLease add_ephemeral(std::string name, std::size_t bus, model::HostedNode& node,
                            uint32_t owner_pid);
  // An ephemeral VCI adapter named `name` with one controller on bus `bus` (an SJA1000 on a
  // classic bus, the CAN FD controller on a CAN FD bus) and its firmware, listed with the
  // configured adapters while the lease lives.
  DeviceLease add_vci_device(std::string name, std::size_t bus, uint32_t owner_pid);
  // The VciObjectId of a VCI device (configured or ephemeral); 0 if there is none.
  uint64_t vci_id_of(std::string_view device) const;
  uint32_t device_generation() const { return generation_; }
  // Told of every device that comes or goes (ephemeral devices).
  std::function<void(ipc::NotificationKind, const std::string&)> on_device_change;

 private:
  explicit Simulation(Config config) : config_(std::move(config)) {}

  // Bus i is config_.buses[i]: both only grow, in step.
  struct Bus {
    std::unique_ptr<model::CanBus> bus;
    std::unique_ptr<model::FaultPlan> faults;  // the bus's injector: frame faults of scenarios
  };
  struct NodeRef {
    std::size_t bus;
    model::NodeId node;
    model::CanController* controller;
    model::HostedNode* hosted;
  };
  // A configured controller ("DEVICE:N") or an ephemeral device ("NAME" or "NAME:0").
  std::optional<NodeRef> find_node(std::string_view name);
  // The name of node `node` of bus `bus` ("DEVICE:N", an ephemeral device's "NAME:0").
  std::string node_name(std::size_t bus, model::NodeId node) const;
  void fault_log(const std::string& text);
  void frame_fault_hit(std::size_t bus, std::size_t rule, const model::FrameContext& ctx);
  struct FaultSwitch {
    bool cleared = false;
    uint64_t fired = 0;
  };
  struct AppliedFault {
    FaultSpec spec;
    std::size_t bus;
    std::string target;
    model::SimTime start;
    std::optional<std::size_t> rule;  // in the bus's FaultPlan
    std::shared_ptr<FaultSwitch> state;
    const model::HostedNode* node = nullptr;  // the node it acts on or matches (`from`)
  };
  struct LoadedScenario {
    std::string name;
    std::vector<AppliedFault> faults;
    bool cleared = false;
  };
  std::vector<LoadedScenario> scenarios_;
  void add_bus(const BusConfig& b);
  // Adds a device whose buses exist; an error (and nothing added) if a controller cannot run
  // its bus's timing.
  std::optional<std::string> add_device(const DeviceConfig& d);
  struct Controller {
    std::string name;  // "device:N"
    std::size_t bus;
    std::unique_ptr<model::HostedNode> node;
    std::shared_ptr<model::ixxat::CanLine> line;  // the adapter firmware driving it
  };

  struct Ephemeral {
    std::string name;
    std::size_t bus;
    model::HostedNode* node;
    uint32_t owner_pid;
    std::shared_ptr<model::ixxat::CanLine> line;  // VCI adapters only
    uint64_t vci_id = 0;
  };
  void remove_ephemeral(const std::string& name);
  void end_node_faults(const Ephemeral& e);

  Config config_;
  model::SimScheduler scheduler_;
  std::vector<Bus> buses_;
  std::vector<Controller> controllers_;
  std::vector<Ephemeral> ephemeral_;  // in order of creation
  // Per bus, the nodes made for ephemeral devices (in use or spare).
  std::vector<std::vector<std::unique_ptr<model::HostedNode>>> pools_;
  uint32_t generation_ = 0;
  std::map<std::string, uint64_t, std::less<>> vci_ids_;  // configured device -> VciObjectId
  uint64_t next_vci_id_ = 1;
};

}  // namespace canemu::daemon
