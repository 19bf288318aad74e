// Buses that span several hosts (docs/distributed.md): canemud joins the installation's DDS
// domain and partition ([distributed]), announces itself and the buses it simulates, and
//   - as the owner of a bus, runs the nodes other daemons ask for on it: real nodes of its
//     simulation (a controller of the bus's kind, arbitration, ACK, error counters, faults by
//     the name "DAEMON/DEVICE"), fed with the frames those daemons send and reporting every
//     event of the controller back to them;
//   - as a user of a remote bus ([[bus]] owner = "..."), gives its local clients nodes on it
//     (model::HostedNode, so ephemeral channels, python-can and VCI adapters work unchanged),
//     whose controller runs on the owner.
// Everything rides on Cyclone DDS (ddstypes/canemu_net.idl); nothing here is a network protocol
// of its own. One object per daemon, a Doorbell of the server's loop: Cyclone's listeners ring
// its eventfd, and the loop's kick() applies what came; a timerfd paces the heartbeats.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/config.hpp"
#include "canemu/daemon/doorbell.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"

namespace canemu::daemon {

class Simulation;

// What `canemu status` shows of another daemon of the installation.
struct PeerStatus {
  std::string name;
  std::string version;
  uint16_t protocol = 0;
  std::string state;   // "up", "gone" (not heard from within timeout_ms, or it left), "refused"
  std::string reason;  // refused: why (protocol, time mode)
  std::string time;    // its time mode ("realtime", "scaled:2", "stepped")
  int64_t last_heard_ms = 0;       // milliseconds since its last heartbeat
  std::vector<std::string> buses;  // the buses it simulates
  uint32_t hosted_nodes = 0;       // its nodes on this daemon's buses
};

// A bus of this daemon that another daemon simulates.
struct RemoteBusStatus {
  std::string bus;
  std::string owner;
  std::string state;   // "attached", "waiting" (for the owner), "refused"
  std::string reason;  // waiting or refused: why
  uint32_t nodes = 0;  // this daemon's nodes on it
};

// Why a message to or from another daemon was dropped (or, a frame no node of the bus sends,
// rejected): DistributedCounters::by_reason, ipc::WireDistributedCounters's order.
enum class NetDrop : uint8_t {
  unknown_daemon = 0,  // from a name that breaks the configuration's rule: no daemon of canemu's
  not_accepted = 1,    // from a daemon not heard announcing itself, refused, or gone
  lost = 2,            // a gap in a daemon's sequence numbers: lost on the way
  no_node = 3,         // for a node that is not open (any more)
  malformed = 4,       // a field out of range, a frame that is none, a kind unknown
  not_written = 5,     // DDS did not take what this daemon wrote
  undecodable = 6,     // a sample Cyclone DDS could not decode (another type of the same name)
  fd_on_classic = 7,   // rejected: a CAN FD frame for a node that sends classic frames only
};
inline constexpr std::size_t kNetDropReasons = 8;
inline constexpr std::array<std::string_view, kNetDropReasons> kNetDropNames = {
    "unknown_daemon", "not_accepted", "lost",        "no_node",
    "malformed",      "not_written",  "undecodable", "fd_on_classic_bus"};

struct DistributedCounters {
  uint64_t requests_sent = 0;      // to owners
  uint64_t requests_received = 0;  // from daemons using this daemon's buses
  uint64_t events_sent = 0;
  uint64_t events_received = 0;
  uint64_t dropped = 0;   // messages lost, not taken by DDS, from no daemon accepted, for no node
  uint64_t rejected = 0;  // frames of another daemon's node that its controller does not send
  // Real and scaled time: events placed more than kLateBoundNs after their instant here (the
  // owner's time converted); stepped time: events applied after their instant had passed.
  uint64_t late = 0;
  int64_t late_max_ns = 0;  // the largest such delay seen, within the bound or beyond
  std::array<uint64_t, kNetDropReasons> by_reason{};  // dropped and rejected, by NetDrop
  std::string last_reason;                            // the last one, with its rule and its daemon
};
// Real and scaled time: an event of a remote bus placed later than this after the instant it
// happened at on the owner counts as late (docs/distributed.md, "Status and counters").
inline constexpr int64_t kLateBoundNs = 1'000'000;

class Distributed : public Doorbell {
 public:
  // Joins the domain; the error says why not (no Cyclone DDS in this build, no domain).
  static tl::expected<std::unique_ptr<Distributed>, std::string> open(Simulation& sim,
                                                                      const Config& config);
  ~Distributed();
  Distributed(const Distributed&) = delete;
  Distributed& operator=(const Distributed&) = delete;

  const std::string& name() const;

  // A node on remote bus `bus` (its CanBus here carries no traffic: every node's controller
  // runs on the owner), of a CAN FD controller when `fd`, else a classic one.
  std::unique_ptr<model::HostedNode> make_node(std::size_t bus, model::CanBus& placeholder,
                                               bool fd);
  // The device a node of a remote bus serves got its name: the owner lists the node as
  // "DAEMON/NAME" (faults name it so).
  void name_node(model::HostedNode& node, const std::string& device);

  // ---- the server's loop ----
  // Rung when something arrived; kick() applies it.
  int doorbell_fd() const override;
  void kick() override;
  bool broken() const override { return false; }
  // Rung when a heartbeat is due: announces this daemon, says hello to owners not yet
  // answering, and lets daemons not heard from within timeout_ms go.
  Doorbell& heartbeat();

  // ---- stepped time (docs/distributed.md, "Time") ----
  // This daemon uses a remote bus in stepped time: its steps are the owner's.
  bool follows_owner() const;
  // This daemon owns buses that other daemons use in stepped time: its steps wait at the
  // barrier until each of them has sent everything its clients queued.
  bool leads_steps() const;
  // A client asks for a step of `step_ns` (follows_owner() or leads_steps()); step_done(token)
  // answers it once the step has run here. The error says why not.
  std::optional<std::string> step(int64_t step_ns, uint64_t token);
  // The server's parts of a step: before it (idle transmitters look at their rings), after it
  // (outboxes, recorders), and the answer to step(token); `note` names the followers let go
  // while the step waited for them or ran ("" when none was).
  std::function<void()> before_step;
  std::function<void()> after_step;
  std::function<void(uint64_t token, uint64_t events_run, int64_t sim_ns, const std::string& note)>
      step_done;
  // Runs simulated time to `until`, then calls done(events run): canemud runs it in slices
  // between which it serves its clients. Unset: at once.
  std::function<void(model::SimTime until, std::function<void(uint64_t events)> done)> run_to;
  // Runs what run_to queued to its end now: a message from another daemon comes after it.
  std::function<void()> finish_runs;
  // The owner whose steps these are is gone: the steps asked of it will not be answered.
  std::function<void(const std::string& why)> steps_failed;

  // ---- status ----
  std::vector<PeerStatus> peers() const;
  std::vector<RemoteBusStatus> remote_buses() const;
  const DistributedCounters& counters() const;
  // The statistics of node `node` of remote bus `bus` as its owner reported them (the bus here
  // carries nothing); nullptr for any other node.
  const model::NodeStats* remote_stats(std::size_t bus, model::NodeId node) const;

  struct Impl;

 private:
  explicit Distributed(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The name a daemon goes by when [distributed] gives none: the host name, lower case, with
// every character a name may not have made '-', at most 28 characters.
std::string default_daemon_name();

}  // namespace canemu::daemon
