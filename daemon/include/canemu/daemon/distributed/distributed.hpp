// Buses that span several hosts (docs/distributed.md): canemud joins the installation's DDS
// domain and partition ([distributed]), announces itself and the buses it simulates, and
//   - as the owner of a bus, runs the nodes other daemons ask for on it: real nodes of its
//     simulation (a controller of the bus's kind, arbitration, ACK, error counters, faults by
//     the name "DAEMON/DEVICE"), fed with the frames those daemons send and reporting every
//     event of the controller back to them;
//   - as a user of a remote bus ([[bus]] owner = "..."), gives its local clients nodes on it
//     (model::HostedNode, so ephemeral channels, python-can and VCI adapters work unchanged),
//     whose controller runs on the owner.
// Between hosts everything rides on Cyclone DDS (canemu_net.idl); nothing here is a network
// protocol of its own. Two daemons on one host speak over a Unix socket instead once the DDS
// announcements have told them of each other (distributed_link.cpp). One object per daemon, a
// Doorbell of the server's loop: its epoll set holds the eventfd Cyclone's listeners ring and the
// same-host links' sockets, and the loop's kick() applies what came; a timerfd paces the
// heartbeats.
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

#include "canemu/daemon/base/doorbell.hpp"
#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/world/remote_buses.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"

namespace canemu::daemon {

class Simulation;

// What the server's loop does for the steps of stepped time across hosts (loop/server.cpp).
// Without one (tests of the link alone), a step runs at once and nothing is answered.
class StepLoop {
 public:
  // Before a step runs, idle transmitters look at their rings; after it, the outboxes and
  // recorders are served.
  virtual void before_step() = 0;
  virtual void after_step() = 0;
  // The answer to step(token); `note` names the followers let go while the step waited for
  // them or ran ("" when none was).
  virtual void step_done(uint64_t token, uint64_t events_run, int64_t sim_ns,
                         const std::string& note) = 0;
  // Runs simulated time to `until`, then calls done(events run), in slices between which
  // canemud serves its clients.
  virtual void run_to(model::SimTime until, std::function<void(uint64_t events)> done) = 0;
  // Runs what run_to queued to its end now: a message from another daemon comes after it.
  virtual void finish_runs() = 0;
  // The owner whose steps these are is gone: the steps asked of it will not be answered.
  virtual void steps_failed(const std::string& why) = 0;
  // Simulated instant `t` on CLOCK_MONOTONIC (ns) in real and scaled time; 0 in stepped time.
  virtual int64_t monotonic_at(model::SimTime t) const = 0;

 protected:
  ~StepLoop() = default;
};

class Distributed final : public RemoteBuses, public Doorbell {
 public:
  // Joins the domain; the error says why not (no Cyclone DDS in this build, no domain).
  static Result<std::unique_ptr<Distributed>> open(Simulation& sim, const Config& config);
  // open() as the world asks for it (Simulation::build's `open_remote`).
  static Result<std::unique_ptr<RemoteBuses>> open_remote(Simulation& sim, const Config& config);
  // The link of `sim`, which opened it with open_remote; nullptr without [distributed].
  static Distributed* of(Simulation& sim);
  ~Distributed() override;
  Distributed(const Distributed&) = delete;
  Distributed& operator=(const Distributed&) = delete;

  // ---- RemoteBuses (world/remote_buses.hpp) ----
  const std::string& name() const override;
  std::unique_ptr<model::HostedNode> make_node(std::size_t bus, model::CanBus& placeholder,
                                               bool fd) override;
  void name_node(model::HostedNode& node, const std::string& device) override;
  std::vector<PeerStatus> peers() const override;
  std::vector<RemoteBusStatus> remote_buses() const override;
  const DistributedCounters& counters() const override;
  const model::NodeStats* remote_stats(std::size_t bus, model::NodeId node) const override;

  // ---- the server's loop ----
  // Rung when something arrived; kick() applies it.
  int doorbell_fd() const override;
  void kick() override;
  bool broken() const override { return false; }
  // Requests waiting on same-host links carry the instant their daemon made them (its
  // simulated time on CLOCK_MONOTONIC): the earliest, and kick_rung() applies the requests
  // alone there (docs/distributed.md, "Daemons on one host").
  int64_t take_rung_ns() override;
  bool kick_rung() override;
  // Rung when a heartbeat is due: announces this daemon, says hello to owners not yet
  // answering, and lets daemons not heard from within timeout_ms go.
  Doorbell& heartbeat();
  // Writes the events this daemon's nodes had for other daemons' nodes since the last call
  // (one sample per daemon): the loop calls it as each turn ends, kick() and the heartbeat
  // as they end.
  void flush();

  // ---- stepped time (docs/distributed.md, "Time") ----
  // This daemon uses a remote bus in stepped time: its steps are the owner's.
  bool follows_owner() const;
  // This daemon owns buses that other daemons use in stepped time: its steps wait at the
  // barrier until each of them has sent everything its clients queued.
  bool leads_steps() const;
  // A client asks for a step of `step_ns` (follows_owner() or leads_steps()); step_done(token)
  // answers it once the step has run here. The error says why not.
  Result<> step(int64_t step_ns, uint64_t token);
  // The server's loop takes part in the steps (nullptr: none does).
  void set_step_loop(StepLoop* loop);

  struct Impl;

 private:
  explicit Distributed(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace canemu::daemon
