// What the files of buses across hosts share (distributed.cpp: the link between daemons;
// distributed_peers.cpp: the other daemons; distributed_owner.cpp: the nodes others open on this
// daemon's buses; distributed_events.cpp: what owners report of this daemon's nodes;
// distributed_steps.cpp: stepped time's barrier; distributed_status.cpp: what status shows):
// the link's state (Distributed::Impl) and small helpers (the nodes this daemon runs on other
// daemons' buses: remote_node.hpp). Private to them; only in builds with Cyclone DDS.
#pragma once

#ifdef CANEMU_HAVE_DDS

#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <dds/dds.h>
#include <fmt/format.h>

#include "bridges/dds_frame_fields.hpp"
#include "bridges/dds_log.hpp"
#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/base/reject_log.hpp"
#include "canemu/daemon/distributed/distributed.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu_net.h"
#include "distributed_legs.hpp"

namespace canemu::daemon {

using namespace canemu::model;

namespace net_detail {

constexpr uint32_t kTxWindow = 64;       // frames a remote node has on their way to the owner
constexpr std::size_t kOwnerQueue = 64;  // frames the owner keeps for one remote node
constexpr int32_t kWriterDepth = 4096;   // samples a writer keeps for readers catching up
constexpr int32_t kReaderSamples = 8192;
constexpr uint32_t kMaxTakesPerKick = 512;
constexpr std::size_t kEventsPerSample = 64;  // canemu_net.idl: Events

inline int64_t monotonic_ms() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1000 + ts.tv_nsec / 1'000'000;
}

template <std::size_t N>
inline void put(char (&dst)[N], std::string_view s) {
  const std::size_t n = std::min(s.size(), N - 1);
  std::memcpy(dst, s.data(), n);
  dst[n] = '\0';
}

template <std::size_t N>
inline std::string get(const char (&src)[N]) {
  return std::string(src, strnlen(src, N));
}

// Text from another daemon, shown in logs and status: what is not printable ASCII becomes '?'.
using ipc::printable;

inline const char* request_name(uint8_t kind) {
  static constexpr const char* kNames[] = {"open",    "online", "offline", "close", "transmit",
                                           "restart", "name",   "step",    "ready", "hello"};
  return kind < std::size(kNames) ? kNames[kind] : "unknown";
}

inline const char* event_name(uint8_t kind) {
  static constexpr const char* kNames[] = {
      "received",         "transmitted", "dropped", "error",      "state",     "overrun",
      "arbitration lost", "refused",     "unknown", "step begin", "step done", "welcome"};
  return kind < std::size(kNames) ? kNames[kind] : "unknown";
}

inline uint8_t wire_time_mode(TimeMode m) {
  switch (m) {
    case TimeMode::realtime:
      return canemu_net_TIME_REALTIME;
    case TimeMode::scaled:
      return canemu_net_TIME_SCALED;
    case TimeMode::stepped:
      return canemu_net_TIME_STEPPED;
  }
  return canemu_net_TIME_REALTIME;
}

inline std::string time_text(uint8_t mode, double scale) {
  switch (mode) {
    case canemu_net_TIME_REALTIME:
      return "realtime";
    case canemu_net_TIME_SCALED:
      return fmt::format("scaled:{}", scale);
    case canemu_net_TIME_STEPPED:
      return "stepped";
  }
  return fmt::format("unknown time mode {}", mode);
}

inline uint8_t wire_bus_kind(BusKind k) {
  switch (k) {
    case BusKind::can:
      return canemu_net_BUS_CAN;
    case BusKind::can_fd:
      return canemu_net_BUS_CAN_FD;
    case BusKind::lin:
      return canemu_net_BUS_LIN;
  }
  return canemu_net_BUS_CAN;
}

// A same-host link (docs/distributed.md, "Daemons on one host"): a SOCK_SEQPACKET connection in
// the abstract namespace from a daemon that uses another's buses (the user, which connects) to
// that owner (which accepts), carrying what would go between the two over canemu/net/requests
// and canemu/net/events, in the order written. distributed_link.cpp.
struct LocalLink {
  int fd = -1;              // -1 once closed (the link is dropped at the end of the turn)
  bool to_owner = false;    // this daemon connected: the other one owns buses this one uses
  bool identified = false;  // the owner's side: the user's hello came and was accepted
  bool bye = false;         // the other daemon said it stops
  bool heard = false;       // something came over it
  bool waits_out = false;   // its socket is watched for room (the backlog is not empty)
  std::string gone_why;     // closed: why the other daemon is let go (links_sweep), or ""
  int64_t opened_ms = 0;    // the owner's side: when it was accepted (a hello is due within
                            // timeout_ms)
  std::string peer;         // the other daemon's name and boot
  uint64_t peer_boot = 0;
  std::deque<std::vector<char>> backlog;  // messages the socket did not take yet, in order
};

// A controller that never takes part in the traffic of the bus it sits on: it gives a node of a
// remote bus a node id on the bus here (which carries nothing) and keeps the counters the owner
// last reported.
class MirrorController final : public CanController {
 public:
  NodeTiming timing() const override { return {}; }
  bool participating() const override { return false; }
  BusOffRecovery bus_off_recovery() const override { return BusOffRecovery::on_restart; }
  const TxFrame* pending_tx() override { return nullptr; }
  FaultConfinement& confinement() override { return fc_; }
  void on_frame(SimTime, const Frame&, bool) override {}
  void on_tx_done(SimTime) override {}
  void on_tx_dropped(SimTime) override {}
  void on_arbitration_lost(SimTime, uint16_t, uint16_t) override {}
  void on_error(const BusErrorEvent&) override {}
  void on_state_change(SimTime, ErrorState) override {}

 private:
  FaultConfinement fc_;
};

}  // namespace net_detail

using namespace net_detail;

class RemoteNode;

struct Distributed::Impl {
  Simulation& sim;
  DistributedConfig cfg;
  TimeSetting time;
  uint64_t boot = 0;
  int wake = -1;
  int timer = -1;
  dds_entity_t participant = 0;
  dds_entity_t w_daemons = 0, w_requests = 0, w_events = 0;
  dds_entity_t r_daemons = 0, r_requests = 0, r_events = 0;
  std::map<std::string, uint64_t> req_seq;  // per owner: the sequence of the last request
  uint64_t ev_seq = 0;
  DistributedCounters counters;
  RejectLog<kNetDropReasons> drops{"distributed", kNetDropNames};
  // A message dropped (or, NetDrop::fd_on_classic, a frame rejected) for reason `why`; `detail`
  // names the rule and the daemon. Counted by reason and logged (rate-limited).
  void drop(NetDrop why, const std::string& detail, uint64_t n = 1) {
    (why == NetDrop::fd_on_classic ? counters.rejected : counters.dropped) += n;
    counters.by_reason[static_cast<std::size_t>(why)] += n;
    counters.last_reason = detail;
    drops.add(static_cast<std::size_t>(why), detail, n);
  }
  // Samples of the link's topics Cyclone could not decode (dds_log.hpp).
  std::vector<std::unique_ptr<UndecodableSamples>> undecodable;

  // Another daemon, as heard.
  struct Peer {
    std::string name;
    uint64_t boot = 0;
    uint16_t protocol = 0;
    std::string version;
    uint8_t time_mode = 0;
    double scale = 1.0;
    int64_t heard_ms = 0;    // monotonic
    bool announced = false;  // its Daemon sample came (protocol, time mode known)
    bool gone = false;
    std::string gone_reason;
    std::string refused;  // why this daemon will not use its buses
    std::vector<std::string> buses;
    std::vector<std::pair<std::string, canemu_net_OwnedBus>> owned;
    // As owner of buses this daemon uses:
    bool welcomed = false;  // it answered our hello: our requests reach it
    bool offset_known = false;
    int64_t offset_ns = 0;  // its simulated time minus ours (the largest estimate so far)
    // As user of our buses:
    uint64_t next_request = 0;  // the seq expected next
    bool follower = false;      // stepped time: its steps are ours (it said hello, stepped)
  };
  std::map<std::string, Peer> peers;
  uint64_t next_event_from(const std::string&);

  // ---- this daemon's nodes on remote buses ----
  std::vector<RemoteNode*> nodes;
  uint32_t next_node = 1;
  bool attached(const std::string& owner) const {
    auto it = peers.find(owner);
    return it != peers.end() && !it->second.gone && it->second.refused.empty() &&
           it->second.welcomed;
  }
  // Why remote bus `b` cannot be used as declared here (its owner runs it otherwise), or "".
  std::string bus_problem(const BusConfig& b) const;
  bool usable(const BusConfig& b) const { return attached(b.owner) && bus_problem(b).empty(); }
  // Says hello to `p` if this daemon uses a bus of it.
  void hello(const Peer& p);

  // ---- other daemons' nodes on this daemon's buses ----
  struct Hosted final : ControllerEvents {
    ~Hosted() override {
      if (node != nullptr) {
        node->stop();
        node->claim(false);
      }
    }
    Impl* link = nullptr;
    std::string daemon;
    uint32_t number = 0;
    uint64_t opened = 0;
    std::size_t bus = 0;
    HostedNode* node = nullptr;
    bool fd = false;  // its controller sends CAN FD frames (opened so, on a CAN FD bus)
    Simulation::DeviceLease lease;
    std::deque<TxFrame> queue;

    void emit(uint8_t kind, SimTime at, const Frame* f = nullptr, bool own = false) {
      canemu_net_Event e{};
      e.kind = kind;
      e.at_ns = at.ns();
      e.own = own;
      if (f != nullptr) {
        put_frame_fields(e, *f);
      }
      send(e);
    }
    void send(canemu_net_Event e) {
      e.node = number;
      e.opened = opened;
      link->send_event(daemon, e);
    }
    void fill_state(canemu_net_Event& e) {
      FaultConfinement& fc = node->controller().confinement();
      e.state = static_cast<uint8_t>(fc.state());
      e.tec = fc.tec();
      e.rec = fc.rec();
    }
    void frame_received(SimTime at, const Frame& frame, bool own) override {
      emit(canemu_net_EV_RX, at, &frame, own);
    }
    void frame_transmitted(SimTime at, const Frame& frame) override {
      emit(canemu_net_EV_TX_DONE, at, &frame);
    }
    void transmission_dropped(SimTime at, const Frame& frame) override {
      emit(canemu_net_EV_DROPPED, at, &frame);
    }
    void overrun(SimTime at, const Frame& lost) override { emit(canemu_net_EV_OVERRUN, at, &lost); }
    void arbitration_lost(SimTime at, uint16_t bit) override {
      canemu_net_Event e{};
      e.kind = canemu_net_EV_ARB_LOST;
      e.at_ns = at.ns();
      e.bit = bit;
      send(e);
    }
    void bus_error(const BusErrorEvent& b) override {
      canemu_net_Event e{};
      e.kind = canemu_net_EV_ERROR;
      e.at_ns = b.at.ns();
      e.error_type = static_cast<uint8_t>(b.type);
      e.role = static_cast<uint8_t>(b.role);
      e.bit = b.bit;
      e.destuffed_bit = b.destuffed_bit;
      e.field = static_cast<uint8_t>(b.field);
      e.extended_frame = b.extended_frame;
      e.in_frame = b.in_frame;
      e.data_phase = b.data_phase;
      fill_state(e);
      e.tec = b.tec;
      e.rec = b.rec;
      send(e);
    }
    void state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) override {
      canemu_net_Event e{};
      e.kind = canemu_net_EV_STATE;
      e.at_ns = at.ns();
      e.state = static_cast<uint8_t>(state);
      e.tec = tec;
      e.rec = rec;
      send(e);
    }
    std::optional<TxFrame> next() {
      if (queue.empty()) {
        return std::nullopt;
      }
      TxFrame f = queue.front();
      queue.pop_front();
      return f;
    }
  };
  std::map<std::pair<std::string, uint32_t>, std::unique_ptr<Hosted>> hosted;

  // ---- stepped time ----
  StepLoop* loop = nullptr;   // the server's loop (Distributed::set_step_loop)
  std::string stepped_owner;  // follower: the owner whose steps this daemon's are
  // Leader: the steps asked for, the one at the barrier, who has still to say ready.
  struct Step {
    int64_t ns = 0;
    std::string asker;
    uint64_t token = 0;
  };
  std::deque<Step> steps;
  bool barrier = false;
  bool running = false;  // the owner's step runs (Distributed::run_to)
  int runs_queued = 0;   // runs given to run_to and not ended
  // A message from another daemon is handled after the runs queued before it.
  void settle() {
    if (runs_queued > 0 && loop != nullptr) {
      loop->finish_runs();
    }
  }
  // Runs to `until`, then done(events): in slices through run_to where canemud offers it.
  void run_to(SimTime until, std::function<void(uint64_t)> done);
  uint64_t step_no = 0;
  std::set<std::string> waiting;
  // Followers let go from the step's barrier to its end ("daemon b (why)"): its answer names them.
  std::vector<std::string> step_dropped;
  std::string step_note() const;
  int64_t barrier_deadline_ms = 0;
  bool stepped() const { return time.mode == TimeMode::stepped; }
  bool leads() const {
    if (!stepped() || !stepped_owner.empty()) {
      return false;
    }
    return std::any_of(peers.begin(), peers.end(),
                       [](const auto& p) { return p.second.follower && !p.second.gone; });
  }
  void enqueue_step(Step s);
  void start_next_step();
  void run_step();
  void deliver(RemoteNode& n, const canemu_net_Event& e, const Peer& owner);

  // The heartbeat timer as a doorbell of the loop.
  struct Heartbeat final : Doorbell {
    Impl* impl = nullptr;
    int doorbell_fd() const override { return impl->timer; }
    void kick() override { impl->tick(); }
    bool broken() const override { return false; }
  } heartbeat;

  Impl(Simulation& s, const Config& config)
      : sim(s), cfg(config.distributed), time(config.simulation.time) {
    heartbeat.impl = this;
    if (stepped()) {
      for (const BusConfig& b : config.buses) {
        if (config.remote(b)) {
          stepped_owner = b.owner;  // the configuration reader allows one owner in stepped time
          break;
        }
      }
    }
    std::random_device rd;
    boot = (uint64_t{rd()} << 32) ^ rd() ^ static_cast<uint64_t>(monotonic_ms());
  }
  ~Impl();

  Result<> open();
  void tick();
  void receive();
  void announce(bool leaving);
  bool send_request(const std::string& owner, canemu_net_Request& r);
  // An event for daemon `to` ("": every follower): written with the others for `to` when the
  // loop's turn ends (flush_events), in one sample.
  void send_event(const std::string& to, const canemu_net_Event& e);
  struct Outgoing {
    std::string to;
    std::vector<canemu_net_Event> events;
  };
  std::vector<Outgoing> outgoing;  // by daemon, each in the order its events happened
  void flush_events();
  void write_events(Outgoing& o);

  void on_daemon(const canemu_net_Daemon& d);
  void on_request(const canemu_net_Request& r);
  void on_events(const canemu_net_Events& b);
  void on_event(Peer& p, const std::string& from, const canemu_net_Event& e);
  void peer_gone(Peer& p, const std::string& why);
  void owner_up(Peer& p);
  void drop_hosted_of(const std::string& daemon, const std::string& why);
  void open_hosted(const canemu_net_Request& r);
  Hosted* find_hosted(const std::string& daemon, uint32_t number) {
    auto it = hosted.find({daemon, number});
    return it == hosted.end() ? nullptr : it->second.get();
  }
  // Whether this daemon's time mode lets it use a bus of `p`, or why not.
  std::string time_problem(const Peer& p) const;
  SimTime local_time(const Peer& owner, int64_t owner_ns);

  // ---- daemons on one host (distributed_link.cpp) ----
  int ep = -1;           // the doorbell: `wake` (Cyclone's listeners) and the links' sockets
  int link_listen = -1;  // this daemon's same-host address, where users connect (-1: none)
  std::vector<std::unique_ptr<LocalLink>> links;
  // Owners whose link failed, with the boot it failed with: that boot is spoken to over DDS.
  std::set<std::pair<std::string, uint64_t>> link_failed;
  bool stopping = false;        // links_bye(): nobody is let go any more
  bool listen_paused = false;   // out of descriptors: no connections taken before the heartbeat
  bool listen_starved = false;  // said so in the log: not again until a connection is taken
  Result<> open_links();
  static std::string link_address(const std::string& name, uint64_t boot);
  void serve();  // the loop's kick: what rang in `ep`
  void link_accept();
  void link_read(LocalLink& l);
  // The leading requests of `l`'s queue, and nothing after the first message that is none.
  void link_read_requests(LocalLink& l);
  // The earliest instant the first waiting request of an owner's link was made at (0: none).
  int64_t links_rung_ns();
  void link_message(LocalLink& l, const char* data, std::size_t size);
  bool link_hello(LocalLink& l, const char* data, std::size_t size);
  // What send_request() and write_events() send over a link instead of DDS.
  void link_request(LocalLink& l, const canemu_net_Request& r);
  void link_events(LocalLink& l, const std::string& to, uint64_t seq,
                   const std::vector<canemu_net_Event>& events);
  // Queues a message (type, `to` and `seq` for events, `count` items of `item_size` at `items`).
  void link_send(LocalLink& l, uint8_t type, const std::string& to, uint64_t seq, const void* items,
                 uint32_t count, std::size_t item_size);
  void link_flush(LocalLink& l);
  void link_write_failed(LocalLink& l);  // closes `l` with what errno says
  // Closes `l` (`malformed`: for what came over it, counted as a malformed message); the other
  // daemon, if it is the one heard, is let go.
  void link_close(LocalLink& l, const std::string& why, bool malformed = false);
  void links_bye();
  // Lets go the daemons of the links closed since the last call, drops those links, and times
  // out connections that did not say hello: at the loop's level only (kick, heartbeat, flush).
  void links_sweep();
  void links_resume();  // the heartbeat: connections are taken again after a lack of descriptors
  void try_link(const Peer& owner);
  // The link to `owner` (its boot as heard) or from user `user`, if one is up.
  LocalLink* link_to(const std::string& owner);
  LocalLink* link_from(const std::string& user);
  // The open link with daemon `name` (its boot as heard) in that direction, or nullptr.
  LocalLink* find_link(const std::string& name, bool to_owner) const;
  // Whether a link with `name` (either way) is up, for status.
  bool linked(const std::string& name) const;

  LinkLegs legs;  // off unless CANEMU_NET_LEGS is set
  bool realtime() const { return time.mode == TimeMode::realtime; }

  static void on_data(dds_entity_t, void* self) {
    if (static_cast<Impl*>(self)->legs.on()) {
      static_cast<Impl*>(self)->legs.rung();
    }
    const uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(static_cast<Impl*>(self)->wake, &one, sizeof one);
  }
};

}  // namespace canemu::daemon

#endif
