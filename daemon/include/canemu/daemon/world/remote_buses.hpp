// Buses of other daemons and this daemon's nodes on them, as the world sees them: how a node
// of a remote bus is made and named, and what status shows of the other daemons. The link
// between daemons (distributed/distributed.hpp, over Cyclone DDS) implements it; the world
// knows it only through this interface, and Simulation::build is given the function that opens
// it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/config/config.hpp"
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
  bool linked = false;  // a same-host link with it is up: what goes between the two uses it
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

class RemoteBuses {
 public:
  virtual ~RemoteBuses() = default;
  // This daemon's name among the others.
  virtual const std::string& name() const = 0;
  // A node on remote bus `bus` (its CanBus here carries no traffic: every node's controller
  // runs on the owner), of a CAN FD controller when `fd`, else a classic one.
  virtual std::unique_ptr<model::HostedNode> make_node(std::size_t bus, model::CanBus& placeholder,
                                                       bool fd) = 0;
  // The device a node of a remote bus serves got its name: the owner lists the node as
  // "DAEMON/NAME" (faults name it so).
  virtual void name_node(model::HostedNode& node, const std::string& device) = 0;
  // ---- status ----
  virtual std::vector<PeerStatus> peers() const = 0;
  virtual std::vector<RemoteBusStatus> remote_buses() const = 0;
  virtual const DistributedCounters& counters() const = 0;
  // The statistics of node `node` of remote bus `bus` as its owner reported them (the bus here
  // carries nothing); nullptr for any other node.
  virtual const model::NodeStats* remote_stats(std::size_t bus, model::NodeId node) const = 0;
};

// Opens the link to the other daemons for [distributed]; the error says why not.
using RemoteBusesOpener =
    std::function<Result<std::unique_ptr<RemoteBuses>>(Simulation& sim, const Config& config)>;

}  // namespace canemu::daemon
