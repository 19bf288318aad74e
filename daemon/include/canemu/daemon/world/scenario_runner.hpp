// Fault scenarios on the running world (docs/faults.md). apply() resolves a scenario's bus and
// node names against the buses and the device registry, all or nothing, then puts its frame
// faults into the bus's FaultPlan (the runner is every bus's injector) and schedules its bus and
// node effects on the scheduler. status() says what each fault did (`canemu fault list`),
// clear() stops a scenario, device_gone() ends the faults of an ephemeral device that goes.
//
// The log ("<6>canemud: fault: t=SECONDS s: ...") tells, with the simulated time, when a
// scenario is applied or cleared, when a bus or node effect fires or ends, and when a frame
// fault hits its first frame, reaches its count or its window ends; each single hit is in the
// bus trace and the counts, not the log.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/restbus/can_ecu.hpp"
#include "canemu/daemon/world/device_registry.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "canemu/firmware_model/bus/lin_fault_plan.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::daemon {

class ScenarioRunner {
 public:
  // Scenarios without a seed of their own use `default_seed` ([simulation] seed). The
  // scheduler and the registry must outlive the runner.
  ScenarioRunner(model::SimScheduler& scheduler, const DeviceRegistry& devices,
                 uint64_t default_seed)
      : scheduler_(scheduler), devices_(devices), default_seed_(default_seed) {}
  ScenarioRunner(const ScenarioRunner&) = delete;
  ScenarioRunner& operator=(const ScenarioRunner&) = delete;

  // Bus number `bus_count()` from now on, configured as `config`, which runs on one engine: a
  // CAN bus `can` (the runner becomes its fault injector) or a LIN bus `lin` (the runner becomes
  // its fault source). The engines must outlive the runner.
  void add_bus(model::CanBus* can, const BusConfig& config, model::lin::LinBus* lin = nullptr);
  // How LIN node names ("DEVICE:N", a simulated node's name) resolve: their bus and node.
  struct LinNodeRef {
    std::size_t bus;
    model::lin::LinNodeId node;
  };
  std::function<std::optional<LinNodeRef>(std::string_view name)> find_lin_node;
  // How simulated CAN nodes ([[can_node]]) resolve: by NAME or BUS/NAME (node effects, `from`),
  // and as the node that sends a message named `message` on the bus named `bus`. A node that
  // goes must be announced with device_gone() first.
  struct CanNodeRef {
    std::size_t bus;
    restbus::CanEcu* ecu;
  };
  std::function<std::optional<CanNodeRef>(std::string_view name)> find_can_node;
  std::function<std::optional<CanNodeRef>(std::string_view bus, std::string_view message)>
      find_can_message;
  std::size_t bus_count() const { return buses_.size(); }

  // Who loaded a scenario: the configuration (no uid) or a client running as that uid.
  using Owner = std::optional<uint32_t>;
  // Whether a client may clear a scenario of `owner`.
  using MayClear = std::function<bool(const Owner& owner)>;

  // Resolves the scenario's buses and nodes and applies every fault, its times counted from
  // `start`, for `owner`. Nothing is applied when a name does not resolve; the errors say which,
  // with the scenario file's line. A user has at most kMaxScenariosPerUser in force.
  tl::expected<void, std::vector<std::string>> apply(const Scenario& scenario, model::SimTime start,
                                                     Owner owner = {});

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
    // What `match` describes: the CAN or LIN frames a frame effect hits, or babble's own frame
    // (its id, with every bit in the mask, and ext); nothing for other effects.
    enum class Frames : uint8_t { none, can, lin, babble };
    Frames frames = Frames::none;
    FaultMatch match{};
  };
  std::vector<FaultStatus> status() const;
  // Changes whenever status()'s faults move: cleared scenarios forgotten (kKeptCleared). A load
  // only adds at the end, so pages of status() read one after the other fit together while it
  // stays the same.
  uint32_t generation() const { return generation_; }

  // Clears the faults of the scenario named `name` (empty: of every scenario) that `may` allows
  // (no `may`: all): frame rules stop matching, scheduled effects do not fire. Effects that fired
  // stay (an unplugged node stays unplugged). Returns the number of scenarios cleared; counts
  // the ones `may` kept in force in `refused`.
  std::size_t clear(std::string_view name, const MayClear& may = {},
                    std::size_t* refused = nullptr);

  // Bounds on what clients can pile up (docs/faults.md): scenarios in force at once (in all and
  // per user), frame rules per bus and per user, and cleared scenarios kept for `canemu fault
  // list` (the oldest go first).
  static constexpr std::size_t kMaxScenarios = 64;
  static constexpr std::size_t kMaxScenariosPerUser = 16;
  static constexpr std::size_t kMaxRulesPerBus = 1024;
  static constexpr std::size_t kMaxRulesPerUser = 256;
  static constexpr std::size_t kKeptCleared = 32;

  // The ephemeral device or simulated CAN node `what` ("device vci3", "simulated CAN node
  // can0/MOTOR", as the log names it) with node `node` on bus `bus` is going: the faults that
  // act on the node, its messages and signals or match its frames end, and the node, kept for
  // a later device, is plugged in and on its nominal clock again.
  void device_gone(std::string_view what, std::size_t bus, const model::HostedNode& node);

 private:
  struct Bus {
    model::CanBus* bus;  // a CAN bus's engine, and its frame faults
    BusConfig config;
    std::unique_ptr<model::FaultPlan> faults;
    model::lin::LinBus* lin = nullptr;  // a LIN bus's engine, and its frame faults
    std::unique_ptr<model::lin::LinFaultPlan> lin_faults;
  };
  // Shared by a fault's scheduled actions: whether it was cleared, how often it fired.
  struct FaultSwitch {
    bool cleared = false;
    uint64_t fired = 0;
  };
  struct AppliedFault {
    FaultSpec spec;
    std::size_t bus;
    std::string target;
    model::SimTime start;
    std::optional<std::size_t> rule;  // in the bus's FaultPlan (while it is there)
    std::shared_ptr<FaultSwitch> state;
    const model::HostedNode* node = nullptr;  // the node it acts on or matches (`from`)
    uint64_t final_seen = 0;                  // the rule's counts when it left the plan
    uint64_t final_hits = 0;
    std::optional<std::size_t> lin_rule;  // in the LIN bus's LinFaultPlan (while it is there)
    // A simulated CAN node's message or signal effect: the node (valid until the fault is
    // cleared: device_gone() clears it), and checksum_error's frames
    restbus::CanEcu* ecu = nullptr;
    std::shared_ptr<restbus::ChecksumFault> checksum;
  };
  struct LoadedScenario {
    std::string name;
    std::vector<AppliedFault> faults;
    bool cleared = false;
    Owner owner;
  };
  // A fault's bus and node, resolved.
  struct Resolved {
    const FaultSpec* spec;
    std::size_t bus = 0;
    std::optional<DeviceRegistry::NodeRef> node;  // node effects; frame effects with match.from
    std::optional<LinNodeRef> lin_node;           // LIN node effects; LIN frames' match.from
    restbus::CanEcu* ecu = nullptr;               // a simulated CAN node's message or signal
  };
  // A node by name: a device's controller DEVICE:N or an ephemeral device, else a simulated
  // CAN node NAME or BUS/NAME.
  std::optional<DeviceRegistry::NodeRef> find_node(std::string_view name) const;
  // Why fault `f` cannot act on `ecu`'s message or signal ("" when it can).
  static std::string restbus_problem(const FaultSpec& f, const restbus::CanEcu& ecu);
  // Puts a message or signal effect to work on its simulated CAN node.
  void arm_restbus(AppliedFault& applied, const std::string& what);
  void add_lin_rule(const Resolved& r, AppliedFault& applied);
  void lin_fault_hit(std::size_t bus, std::size_t rule, model::SimTime at, uint8_t id);
  // Logs a rule's first hit (with `what_was_hit`) and the hit that reaches its count (a frame
  // rule of bus `bus`'s FaultPlan, or with `lin` of its LinFaultPlan).
  void log_progress(std::size_t bus, std::size_t rule, bool lin, uint64_t hits,
                    const std::optional<uint64_t>& count,
                    const std::function<std::string()>& what_was_hit) const;

  std::optional<std::size_t> bus_index(std::string_view name) const;
  // A fault's frame rule leaves its bus's plan (its counts kept in the fault).
  void retire(AppliedFault& a);
  tl::expected<std::vector<Resolved>, std::vector<std::string>> resolve(const Scenario& s) const;
  // Puts fault `k` of scenario `name` to work: a frame rule, or scheduled effects.
  void arm(const std::string& name, const Resolved& r, std::size_t k, uint64_t seed,
           AppliedFault& applied);
  void add_frame_rule(const Resolved& r, std::size_t k, uint64_t seed, const std::string& what,
                      AppliedFault& applied);
  // Runs `fire` at `at` (at once if due) unless the fault is cleared by then.
  void when(model::SimTime at, const std::shared_ptr<FaultSwitch>& state,
            std::function<void()> fire);
  void frame_fault_hit(std::size_t bus, std::size_t rule, const model::FrameContext& ctx);
  std::string node_name(std::size_t bus, model::NodeId node) const;
  void log(const std::string& text) const;

  model::SimScheduler& scheduler_;
  const DeviceRegistry& devices_;
  uint64_t default_seed_;
  std::vector<Bus> buses_;
  std::vector<LoadedScenario> scenarios_;
  uint32_t generation_ = 0;
};

}  // namespace canemu::daemon
