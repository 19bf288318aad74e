#include "canemu/daemon/distributed.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/simulation.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

#ifdef CANEMU_HAVE_DDS
#include <sys/eventfd.h>
#include <sys/timerfd.h>

#include <deque>
#include <map>
#include <random>
#include <set>
#include <utility>

#include <dds/dds.h>

#include "canemu/daemon/dds_bridge.hpp"
#include "canemu/daemon/log.hpp"
#include "canemu_net.h"
#include "dds_frame_fields.hpp"
#endif

#ifndef CANEMU_VERSION
#define CANEMU_VERSION "unknown"
#endif

namespace canemu::daemon {

std::string default_daemon_name() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') {
    return "canemud";
  }
  std::string name;
  for (const char* p = host; *p != '\0' && *p != '.' && name.size() < 28; ++p) {
    const auto ch = static_cast<unsigned char>(std::tolower(static_cast<unsigned char>(*p)));
    name += std::isalnum(ch) || ch == '_' || ch == '-' ? static_cast<char>(ch) : '-';
  }
  return name.empty() ? std::string("canemud") : name;
}

#ifdef CANEMU_HAVE_DDS

using namespace canemu::model;

namespace {

constexpr uint32_t kTxWindow = 64;       // frames a remote node has on their way to the owner
constexpr std::size_t kOwnerQueue = 64;  // frames the owner keeps for one remote node
constexpr int32_t kWriterDepth = 4096;   // samples a writer keeps for readers catching up
constexpr int32_t kReaderSamples = 8192;
constexpr uint32_t kMaxTakesPerKick = 512;

int64_t monotonic_ms() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1000 + ts.tv_nsec / 1'000'000;
}

template <std::size_t N>
void put(char (&dst)[N], std::string_view s) {
  const std::size_t n = std::min(s.size(), N - 1);
  std::memcpy(dst, s.data(), n);
  dst[n] = '\0';
}

template <std::size_t N>
std::string get(const char (&src)[N]) {
  return std::string(src, strnlen(src, N));
}

// Text from another daemon, shown in logs and status: what is not printable ASCII becomes '?'.
std::string printable(std::string s) {
  for (char& ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    ch = u >= 0x20 && u < 0x7F ? ch : '?';
  }
  return s;
}

uint8_t wire_time_mode(TimeMode m) {
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

std::string time_text(uint8_t mode, double scale) {
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

uint8_t wire_bus_kind(BusKind k) {
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

}  // namespace

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
  uint64_t req_seq = 0;
  uint64_t ev_seq = 0;
  DistributedCounters counters;

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
    void send(canemu_net_Event& e) {
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
  Distributed* self = nullptr;  // its hooks
  std::string stepped_owner;    // follower: the owner whose steps this daemon's are
  // Leader: the steps asked for, the one at the barrier, who has still to say ready.
  struct Step {
    int64_t ns = 0;
    std::string asker;
    uint64_t token = 0;
  };
  std::deque<Step> steps;
  bool barrier = false;
  uint64_t step_no = 0;
  std::set<std::string> waiting;
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

  std::optional<std::string> open();
  void tick();
  void receive();
  void announce(bool leaving);
  bool send_request(const std::string& owner, canemu_net_Request& r);
  void send_event(const std::string& to, canemu_net_Event& e);

  void on_daemon(const canemu_net_Daemon& d);
  void on_request(const canemu_net_Request& r);
  void on_event(const canemu_net_Event& e);
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

  static void on_data(dds_entity_t, void* self) {
    const uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(static_cast<Impl*>(self)->wake, &one, sizeof one);
  }
};

// A node of this daemon's on a bus another daemon simulates: the driver above it (an ephemeral
// channel, a VCI line, a bridge, a recorder) sees a HostedNode; its controller is a node of the
// owner's simulation, programmed, fed and heard through the link.
class RemoteNode final : public HostedNode {
 public:
  RemoteNode(SimScheduler& scheduler, CanBus& placeholder, Distributed::Impl& link, uint32_t number,
             std::size_t bus, std::string bus_name, std::string owner, bool fd)
      : HostedNode(scheduler, placeholder),
        link_(&link),
        number_(number),
        bus_(bus),
        bus_name_(std::move(bus_name)),
        owner_(std::move(owner)),
        fd_(fd),
        device_(fmt::format("n{}", number)),
        id_(placeholder.attach(mirror_)) {
    link.nodes.push_back(this);
  }
  ~RemoteNode() override {
    if (link_ != nullptr) {
      if (programmed_) {
        request(canemu_net_REQ_CLOSE);
      }
      std::erase(link_->nodes, this);
    }
  }

  NodeId node() const override { return id_; }
  CanController& controller() override { return mirror_; }
  bool fd_capable() const override { return fd_; }
  const std::string& owner() const { return owner_; }
  const std::string& bus_name() const { return bus_name_; }
  uint32_t number() const { return number_; }
  bool in_use() const { return programmed_; }
  std::size_t bus() const { return bus_; }
  // What the owner reported of this node: frames, errors, arbitration lost.
  const NodeStats& stats() const { return stats_; }
  void unlink() { link_ = nullptr; }

  void set_device(const std::string& device) {
    device_ = device;
    if (programmed_) {
      request(canemu_net_REQ_NAME);
    }
  }

  // The owner (again) answers: the node is opened there as it is here.
  void replay() {
    if (!programmed_) {
      return;
    }
    send_open();
    if (online_) {
      request(canemu_net_REQ_ONLINE);
    }
    if (reported_off_) {  // back on the bus, error-active with fresh counters
      reported_off_ = false;
      mirror_.confinement().reset();
      events()->state_changed(now(), ErrorState::active, 0, 0);
    }
    kick();
  }

  // The owner is gone: the node is off the bus until it comes back.
  void owner_lost() {
    if (!programmed_ || !online_ || reported_off_) {
      return;
    }
    reported_off_ = true;
    FaultConfinement& fc = mirror_.confinement();
    fc.set_counters(256, fc.rec());
    events()->state_changed(now(), ErrorState::bus_off, fc.tec(), fc.rec());
  }

  void deliver(const canemu_net_Event& e, SimTime at) {
    if (e.opened != opened_) {
      return;  // for the node as it was opened before
    }
    ::canemu::model::ControllerEvents* ev = events();
    switch (e.kind) {
      case canemu_net_EV_RX:
      case canemu_net_EV_TX_DONE:
      case canemu_net_EV_DROPPED:
      case canemu_net_EV_OVERRUN: {
        auto f = frame_of_fields(e);
        if (!f) {
          ++link_->counters.dropped;
          return;
        }
        if (e.kind == canemu_net_EV_RX) {
          stats_.frames_received += e.own ? 0 : 1;
          ev->frame_received(at, *f, e.own);
        } else if (e.kind == canemu_net_EV_TX_DONE) {
          ++stats_.frames_sent;
          ev->frame_transmitted(at, *f);
        } else if (e.kind == canemu_net_EV_DROPPED) {
          ev->transmission_dropped(at, *f);
        } else {
          ev->overrun(at, *f);
        }
        return;
      }
      case canemu_net_EV_ARB_LOST:
        ++stats_.arbitration_lost;
        ev->arbitration_lost(at, e.bit);
        return;
      case canemu_net_EV_ERROR: {
        mirror_.confinement().set_counters(e.tec, e.rec);
        BusErrorEvent b;
        b.at = at;
        b.type = static_cast<CanErrorType>(std::min<uint8_t>(e.error_type, 4));
        b.role = e.role == 0 ? ErrorRole::transmitter : ErrorRole::receiver;
        b.bit = e.bit;
        b.destuffed_bit = e.destuffed_bit;
        b.field = static_cast<Field>(std::min<uint8_t>(e.field, static_cast<uint8_t>(Field::eof)));
        b.extended_frame = e.extended_frame;
        b.in_frame = e.in_frame;
        b.data_phase = e.data_phase;
        b.tec = e.tec;
        b.rec = e.rec;
        ++(b.role == ErrorRole::transmitter ? stats_.errors_as_transmitter
                                            : stats_.errors_as_receiver)[b.type];
        ev->bus_error(b);
        return;
      }
      case canemu_net_EV_STATE:
        mirror_.confinement().set_counters(e.tec, e.rec);
        ev->state_changed(at, static_cast<ErrorState>(std::min<uint8_t>(e.state, 3)), e.tec, e.rec);
        return;
      case canemu_net_EV_REFUSED:
      case canemu_net_EV_GONE:
        log::warning("node {} of bus {} (owner {}): {}", device_, bus_name_, owner_,
                     printable(get(e.text)));
        owner_lost();
        return;
      default:
        return;
    }
  }

 private:
  void program(const HostedNodeSettings& settings) override {
    stats_ = NodeStats{};  // a node configured afresh starts counting afresh, as a local one
    settings_ = settings;
    programmed_ = true;
    online_ = false;
    reported_off_ = false;
    mirror_.confinement().reset();
    send_open();
  }
  void go_on_bus(const HostedNodeSettings&) override {
    online_ = true;
    request(canemu_net_REQ_ONLINE);  // without the owner (yet): frames wait for replay()
  }
  void go_off_bus() override {
    online_ = false;
    request(canemu_net_REQ_OFFLINE);
  }
  void leave_bus_off(const HostedNodeSettings&) override { request(canemu_net_REQ_RESTART); }
  bool buffer_free() override { return usable(); }
  bool usable() const { return link_ != nullptr && link_->usable(link_->sim.bus_config(bus_)); }
  void load(const TxFrame& tx) override {
    canemu_net_Request r{};
    r.kind = canemu_net_REQ_TX;
    r.single_shot = tx.single_shot;
    r.self_reception = tx.self_reception;
    put_frame_fields(r, tx.frame);
    send(r);
  }
  void abort_tx() override {}
  void release_received() override {}
  void released() override {
    if (programmed_) {
      request(canemu_net_REQ_CLOSE);  // the owner gives its node back
    }
    programmed_ = false;
    online_ = false;
    reported_off_ = false;
  }
  uint32_t tx_window() const override { return kTxWindow; }
  bool restarts_itself() const override { return true; }

  void send_open() {
    canemu_net_Request r{};
    r.kind = canemu_net_REQ_OPEN;
    r.fd = fd_ && settings_.fd;
    r.listen_only = settings_.listen_only;
    r.btr0 = settings_.btr0;
    r.btr1 = settings_.btr1;
    if (!r.fd && settings_.nominal.clock_hz == 0) {
      // An SJA1000 programmed by its registers alone (a VCI line's BTR0/BTR1): the timing they
      // give, which the owner checks.
      if (auto t = sja1000::decode_btr(settings_.btr0, settings_.btr1)) {
        settings_.nominal = *t;
      }
    }
    r.clock_hz = settings_.nominal.clock_hz;
    r.n_prescaler = settings_.nominal.prescaler;
    r.n_tseg1 = settings_.nominal.tseg1;
    r.n_tseg2 = settings_.nominal.tseg2;
    r.n_sjw = settings_.nominal.sjw;
    r.d_prescaler = settings_.data.prescaler;
    r.d_tseg1 = settings_.data.tseg1;
    r.d_tseg2 = settings_.data.tseg2;
    r.d_sjw = settings_.data.sjw;
    r.restart_ns = settings_.restart_delay.ns();
    if (auto seq = send(r)) {
      opened_ = *seq;
    }
  }
  void request(uint8_t kind) {
    canemu_net_Request r{};
    r.kind = kind;
    send(r);
  }
  std::optional<uint64_t> send(canemu_net_Request& r) {
    if (!usable()) {
      return std::nullopt;  // replay() sends what matters once the owner answers
    }
    r.node = number_;
    put(r.bus, bus_name_);
    put(r.device, device_);
    if (!link_->send_request(owner_, r)) {
      return std::nullopt;
    }
    return r.seq;
  }

  Distributed::Impl* link_;
  uint32_t number_;
  std::size_t bus_;
  std::string bus_name_;
  std::string owner_;
  bool fd_;
  std::string device_;
  MirrorController mirror_;
  NodeId id_;
  HostedNodeSettings settings_;
  bool programmed_ = false;
  bool online_ = false;
  bool reported_off_ = false;  // owner_lost() told the driver the node is off the bus
  uint64_t opened_ = 0;
  NodeStats stats_;
};

Distributed::Impl::~Impl() {
  for (RemoteNode* n : nodes) {
    n->unlink();
  }
  hosted.clear();  // their nodes stop and go back to the pool
  if (participant > 0) {
    dds_delete(participant);
  }
  for (int fd : {wake, timer}) {
    if (fd >= 0) {
      ::close(fd);
    }
  }
}

std::optional<std::string> Distributed::Impl::open() {
  wake = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  timer = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  if (wake < 0 || timer < 0) {
    return fmt::format("eventfd/timerfd: {}", std::strerror(errno));
  }
  itimerspec its{};
  its.it_interval.tv_sec = cfg.heartbeat_ms / 1000;
  its.it_interval.tv_nsec = static_cast<long>(cfg.heartbeat_ms % 1000) * 1'000'000;
  its.it_value.tv_nsec = 1'000'000;  // the first at once
  ::timerfd_settime(timer, 0, &its, nullptr);

  // The domain as CYCLONEDDS_URI configures it, with one change: a writer being deleted waits at
  // most 50 ms (not Cyclone's 1 s) for readers to acknowledge what it wrote, so that a daemon
  // whose peer vanished stops at once. The domain stays for the process's life; when it exists
  // already (a DDS bridge's, another simulation's in a test) it is taken as it is.
  const char* uri = std::getenv("CYCLONEDDS_URI");
  const std::string config = fmt::format(
      "{}{}<CycloneDDS><Domain Id=\"any\"><Internal><WriterLingerDuration>50ms"
      "</WriterLingerDuration></Internal></Domain></CycloneDDS>",
      uri != nullptr ? uri : "", uri != nullptr && *uri != '\0' ? "," : "");
  [[maybe_unused]] const dds_entity_t domain = dds_create_domain(cfg.domain, config.c_str());
  participant = dds_create_participant(cfg.domain, nullptr, nullptr);
  if (participant < 0) {
    return fmt::format("Cyclone DDS cannot join domain {}: {} (CYCLONEDDS_URI: {})", cfg.domain,
                       dds_strretcode(participant),
                       std::getenv("CYCLONEDDS_URI") ? std::getenv("CYCLONEDDS_URI") : "unset");
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_partition1(qos, cfg.partition.c_str());
  dds_qos_t* wq = dds_create_qos();
  dds_copy_qos(wq, qos);
  dds_qset_history(wq, DDS_HISTORY_KEEP_LAST, kWriterDepth);
  dds_qos_t* rq = dds_create_qos();
  dds_copy_qos(rq, qos);
  dds_qset_history(rq, DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_resource_limits(rq, kReaderSamples, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  // What this daemon writes is not for its own readers (it would only wake the loop).
  dds_qset_ignorelocal(rq, DDS_IGNORELOCAL_PARTICIPANT);
  dds_listener_t* listener = dds_create_listener(this);
  dds_lset_data_available(listener, &Impl::on_data);
  const dds_entity_t pub = dds_create_publisher(participant, qos, nullptr);
  const dds_entity_t sub = dds_create_subscriber(participant, qos, nullptr);
  dds_return_t failure = DDS_RETCODE_OK;
  auto topic = [&](const dds_topic_descriptor_t* d, const char* name) {
    const dds_entity_t t = dds_create_topic(participant, d, name, nullptr, nullptr);
    if (t < 0) {
      failure = t;
    }
    return t;
  };
  const dds_entity_t t_daemons = topic(&canemu_net_Daemon_desc, "canemu/net/daemons");
  const dds_entity_t t_requests = topic(&canemu_net_Request_desc, "canemu/net/requests");
  const dds_entity_t t_events = topic(&canemu_net_Event_desc, "canemu/net/events");
  auto writer = [&](dds_entity_t t) {
    const dds_entity_t w = t > 0 ? dds_create_writer(pub, t, wq, nullptr) : t;
    failure = w < 0 ? w : failure;
    return w;
  };
  auto reader = [&](dds_entity_t t) {
    const dds_entity_t r = t > 0 ? dds_create_reader(sub, t, rq, listener) : t;
    failure = r < 0 ? r : failure;
    return r;
  };
  w_daemons = writer(t_daemons);
  w_requests = writer(t_requests);
  w_events = writer(t_events);
  r_daemons = reader(t_daemons);
  r_requests = reader(t_requests);
  r_events = reader(t_events);
  dds_delete_listener(listener);
  dds_delete_qos(rq);
  dds_delete_qos(wq);
  dds_delete_qos(qos);
  if (failure != DDS_RETCODE_OK || pub < 0 || sub < 0) {
    return fmt::format("Cyclone DDS cannot make the topics canemu/net/* in domain {}: {}",
                       cfg.domain, dds_strretcode(failure));
  }
  return std::nullopt;
}

void Distributed::Impl::announce(bool leaving) {
  canemu_net_Daemon d{};
  put(d.name, cfg.name);
  d.boot = boot;
  d.protocol = canemu_net_PROTOCOL;
  put(d.version, CANEMU_VERSION);
  d.time_mode = wire_time_mode(time.mode);
  d.scale = time.scale;
  d.sim_ns = sim.scheduler().now().ns();
  d.leaving = leaving;
  std::vector<canemu_net_OwnedBus> owned;
  std::vector<std::string> uses;
  for (std::size_t i = 0; i < sim.bus_count(); ++i) {
    const BusConfig& b = sim.bus_config(i);
    if (sim.config().remote(b)) {
      uses.push_back(b.owner + "/" + b.name);
      continue;
    }
    if (owned.size() == 64) {
      continue;
    }
    canemu_net_OwnedBus o{};
    put(o.name, b.name);
    o.kind = wire_bus_kind(b.kind);
    o.bitrate = b.bitrate;
    o.data_bitrate = b.data_bitrate;
    o.sample_point = static_cast<uint16_t>(b.sample_point);
    owned.push_back(o);
  }
  std::vector<char*> use_names;
  std::vector<std::array<char, 32>> use_storage(std::min<std::size_t>(uses.size(), 64));
  for (std::size_t i = 0; i < use_storage.size(); ++i) {
    std::memset(use_storage[i].data(), 0, 32);
    std::memcpy(use_storage[i].data(), uses[i].data(), std::min<std::size_t>(uses[i].size(), 31));
  }
  d.buses._buffer = owned.data();
  d.buses._length = static_cast<uint32_t>(owned.size());
  d.buses._maximum = d.buses._length;
  d.buses._release = false;
  d.uses._buffer = reinterpret_cast<decltype(d.uses._buffer)>(use_storage.data());
  d.uses._length = static_cast<uint32_t>(use_storage.size());
  d.uses._maximum = d.uses._length;
  d.uses._release = false;
  if (dds_write(w_daemons, &d) != DDS_RETCODE_OK) {
    ++counters.dropped;
  }
}

bool Distributed::Impl::send_request(const std::string& owner, canemu_net_Request& r) {
  put(r.from, cfg.name);
  r.from_boot = boot;
  put(r.to, owner);
  r.seq = ++req_seq;
  if (dds_write(w_requests, &r) != DDS_RETCODE_OK) {
    ++counters.dropped;
    return false;
  }
  ++counters.requests_sent;
  return true;
}

void Distributed::Impl::send_event(const std::string& to, canemu_net_Event& e) {
  put(e.from, cfg.name);
  e.from_boot = boot;
  put(e.to, to);
  e.seq = ++ev_seq;
  if (dds_write(w_events, &e) != DDS_RETCODE_OK) {
    ++counters.dropped;
    return;
  }
  ++counters.events_sent;
}

void Distributed::Impl::tick() {
  uint64_t expirations = 0;
  [[maybe_unused]] const auto n = ::read(timer, &expirations, sizeof expirations);
  announce(false);
  const int64_t now = monotonic_ms();
  if (barrier && now > barrier_deadline_ms) {
    for (const std::string& name : std::vector<std::string>(waiting.begin(), waiting.end())) {
      auto it = peers.find(name);
      if (it != peers.end()) {
        peer_gone(it->second, fmt::format("it did not get ready for step {} within {} ms", step_no,
                                          cfg.timeout_ms));
      }
    }
    if (barrier) {
      run_step();
    }
  }
  for (auto& [name, p] : peers) {
    if (!p.gone && now - p.heard_ms > static_cast<int64_t>(cfg.timeout_ms)) {
      peer_gone(p, fmt::format("not heard from for {} ms", now - p.heard_ms));
    }
  }
  // Owners of buses this daemon uses that have not answered yet: hello again (their reader of
  // our requests may not have been matched when the last one went out).
  for (const auto& [name, p] : peers) {
    if (!p.gone && p.refused.empty() && !p.welcomed) {
      hello(p);
    }
  }
}

std::string Distributed::Impl::time_problem(const Peer& p) const {
  const uint8_t ours = wire_time_mode(time.mode);
  if (p.time_mode != ours || (ours == canemu_net_TIME_SCALED && p.scale != time.scale)) {
    return fmt::format("its time is {}, this daemon's {}", time_text(p.time_mode, p.scale),
                       to_string(time));
  }
  return {};
}

void Distributed::Impl::on_daemon(const canemu_net_Daemon& d) {
  const std::string name = get(d.name);
  if (!valid_name(name)) {
    ++counters.dropped;  // not a daemon of ours (names follow the configuration's rule)
    return;
  }
  if (name == cfg.name) {
    if (d.boot != boot) {
      log::warning("another daemon in DDS domain {} partition \"{}\" calls itself \"{}\"",
                   cfg.domain, cfg.partition, name);
    }
    return;
  }
  Peer& p = peers[name];
  const bool fresh = p.name.empty() || p.boot != d.boot;
  if (fresh && !p.name.empty() && !p.gone) {
    peer_gone(p, "restarted");
  }
  if (fresh) {
    p = Peer{};
    p.name = name;
    p.boot = d.boot;
    log::info("daemon {} ({} time, protocol {}, version {}) joined", name,
              time_text(d.time_mode, d.scale), d.protocol, get(d.version));
  }
  if (d.leaving) {
    if (!p.gone) {
      peer_gone(p, "it stopped");
    }
    return;
  }
  p.announced = true;
  p.protocol = d.protocol;
  p.version = printable(get(d.version));
  p.time_mode = d.time_mode;
  p.scale = d.scale;
  p.heard_ms = monotonic_ms();
  p.gone = false;
  p.buses.clear();
  p.owned.clear();
  for (uint32_t i = 0; i < d.buses._length && i < 64; ++i) {
    p.buses.push_back(printable(get(d.buses._buffer[i].name)));
    p.owned.emplace_back(p.buses.back(), d.buses._buffer[i]);
  }
  bool uses_ours = false;
  for (uint32_t i = 0; i < d.uses._length && i < 64; ++i) {
    uses_ours = uses_ours || get(d.uses._buffer[i]).starts_with(cfg.name + "/");
  }
  if (p.protocol != canemu_net_PROTOCOL) {
    p.refused = fmt::format("protocol {}, this daemon speaks {}", p.protocol, canemu_net_PROTOCOL);
  } else {
    p.refused = time_problem(p);
  }
  if (p.refused.empty() && uses_ours && stepped() && !stepped_owner.empty()) {
    p.refused = fmt::format(
        "it uses this daemon's buses in stepped time, and this daemon follows daemon {}'s steps "
        "(an owner follows nobody)",
        stepped_owner);
  }
  // Simulated time there minus here: its time when it wrote this, against ours now, is the
  // offset less the link's delay, so the largest such value is the best estimate.
  const int64_t offset = d.sim_ns - sim.scheduler().now().ns();
  if (!p.offset_known || offset > p.offset_ns) {
    p.offset_ns = offset;
    p.offset_known = true;
  }
  if (fresh && p.refused.empty()) {
    hello(p);
  }
}

void Distributed::Impl::hello(const Peer& p) {
  for (std::size_t i = 0; i < sim.bus_count(); ++i) {
    const BusConfig& b = sim.bus_config(i);
    if (sim.config().remote(b) && b.owner == p.name) {
      canemu_net_Request r{};
      r.kind = canemu_net_REQ_HELLO;
      send_request(p.name, r);
      return;
    }
  }
}

std::string Distributed::Impl::bus_problem(const BusConfig& b) const {
  auto it = peers.find(b.owner);
  if (it == peers.end()) {
    return fmt::format("daemon {} not heard from", b.owner);
  }
  const Peer& p = it->second;
  auto owned = std::find_if(p.owned.begin(), p.owned.end(),
                            [&](const auto& o) { return o.first == b.name; });
  if (owned == p.owned.end()) {
    return fmt::format("daemon {} simulates no bus \"{}\"", b.owner, b.name);
  }
  const canemu_net_OwnedBus& o = owned->second;
  if (o.kind != wire_bus_kind(b.kind) || o.bitrate != b.bitrate ||
      o.data_bitrate != b.data_bitrate) {
    auto kind = [](uint8_t k) {
      return k == canemu_net_BUS_CAN_FD ? "can-fd" : k == canemu_net_BUS_LIN ? "lin" : "can";
    };
    return fmt::format(
        "daemon {} runs \"{}\" as {} at {}/{} bit/s; this daemon declares {} at {}/{} bit/s",
        b.owner, b.name, kind(o.kind), o.bitrate, o.data_bitrate, kind(wire_bus_kind(b.kind)),
        b.bitrate, b.data_bitrate);
  }
  return {};
}

void Distributed::Impl::peer_gone(Peer& p, const std::string& why) {
  p.gone = true;
  p.gone_reason = why;
  p.welcomed = false;
  p.follower = false;
  log::warning("daemon {} is gone: {}", p.name, why);
  drop_hosted_of(p.name, why);
  for (RemoteNode* n : nodes) {
    if (n->owner() == p.name) {
      n->owner_lost();
    }
  }
  if (barrier && waiting.erase(p.name) > 0 && waiting.empty()) {
    run_step();
  }
  if (p.name == stepped_owner && self != nullptr && self->steps_failed) {
    self->steps_failed(fmt::format("daemon {}, whose steps these are, is gone ({})", p.name, why));
  }
}

void Distributed::Impl::owner_up(Peer& p) {
  p.welcomed = true;
  log::info("daemon {} answers: its buses are attached", p.name);
  for (RemoteNode* n : std::vector<RemoteNode*>(nodes)) {
    if (n->owner() == p.name) {
      n->replay();
    }
  }
}

void Distributed::Impl::drop_hosted_of(const std::string& daemon, const std::string& why) {
  std::size_t n = 0;
  for (auto it = hosted.begin(); it != hosted.end();) {
    if (it->first.first == daemon) {
      it = hosted.erase(it);
      ++n;
    } else {
      ++it;
    }
  }
  if (n > 0) {
    log::warning("daemon {}: its {} node{} left this daemon's buses ({})", daemon, n,
                 n == 1 ? "" : "s", why);
  }
}

void Distributed::Impl::open_hosted(const canemu_net_Request& r) {
  const std::string daemon = get(r.from);
  auto refuse = [&](const std::string& why) {
    canemu_net_Event e{};
    e.kind = canemu_net_EV_REFUSED;
    e.node = r.node;
    e.opened = r.seq;
    e.at_ns = sim.scheduler().now().ns();
    put(e.text, why);
    send_event(daemon, e);
  };
  const std::string bus_name = get(r.bus);
  const auto bus = sim.bus_index(bus_name);
  if (!bus || sim.config().remote(sim.bus_config(*bus))) {
    refuse(fmt::format("daemon {} simulates no bus \"{}\"", cfg.name, bus_name));
    return;
  }
  if (sim.lin_bus(*bus) != nullptr) {
    refuse(fmt::format("\"{}\" is a LIN bus", bus_name));
    return;
  }
  // The controller's programming as the other daemon computed it; checked, so that no value
  // that came over the network can upset the model (a prescaler of 0, a bit of 1 quantum).
  auto timing_ok = [](uint64_t clock, uint32_t prescaler, uint32_t tseg1, uint32_t tseg2,
                      uint32_t sjw) {
    return clock >= 1'000'000 && clock <= 1'000'000'000 && prescaler >= 1 && prescaler <= 1024 &&
           tseg1 >= 1 && tseg1 <= 256 && tseg2 >= 1 && tseg2 <= 128 && sjw >= 1 && sjw <= tseg2;
  };
  if (!timing_ok(r.clock_hz, r.n_prescaler, r.n_tseg1, r.n_tseg2, r.n_sjw) ||
      (r.fd && !timing_ok(r.clock_hz, r.d_prescaler, r.d_tseg1, r.d_tseg2, r.d_sjw)) ||
      r.restart_ns < 0) {
    refuse(
        fmt::format("the node's bit timing (clock {} Hz, prescaler {}, tseg1 {}, tseg2 {}, "
                    "sjw {}) is no controller's",
                    r.clock_hz, r.n_prescaler, r.n_tseg1, r.n_tseg2, r.n_sjw));
    return;
  }
  const std::string device = get(r.device);
  if (!valid_name(device)) {
    refuse(fmt::format("\"{}\" is not a device name", printable(device)));
    return;
  }
  Hosted* h = find_hosted(daemon, r.node);
  if (h == nullptr) {
    auto made = std::make_unique<Hosted>();
    h = made.get();
    h->link = this;
    h->daemon = daemon;
    h->number = r.node;
    h->bus = *bus;
    h->node = &sim.spare_node(*bus);
    h->node->claim(true);  // until it is closed, whether on the bus or not
    hosted[{daemon, r.node}] = std::move(made);
  }
  h->opened = r.seq;
  h->queue.clear();
  HostedNodeSettings s;
  s.btr0 = r.btr0;
  s.btr1 = r.btr1;
  s.nominal = BitTiming{r.clock_hz, r.n_prescaler, r.n_tseg1, r.n_tseg2, r.n_sjw, 1};
  s.data = BitTiming{r.clock_hz, r.d_prescaler, r.d_tseg1, r.d_tseg2, r.d_sjw, 1};
  s.listen_only = r.listen_only;
  s.fd = r.fd;
  const BusConfig& bc = sim.bus_config(*bus);
  if (bc.kind == BusKind::can && r.btr0 == 0 && r.btr1 == 0) {
    // A CAN FD controller's node on a classic bus, which this daemon runs on SJA1000s: their
    // registers for the bus's rate.
    if (auto t = controller_timing(false, bc.bitrate, 0, bc.sample_point)) {
      s.btr0 = t->btr0;
      s.btr1 = t->btr1;
    }
  }
  s.restart_delay = SimDuration(std::max<int64_t>(0, r.restart_ns));
  h->node->configure(s, h, [h] { return h->next(); });
  const std::string name = daemon + "/" + get(r.device);
  h->lease = {};
  if (!sim.devices().exists(name)) {
    h->lease = sim.add_ephemeral(name, *bus, *h->node, 0);
  }
}

void Distributed::Impl::on_request(const canemu_net_Request& r) {
  if (get(r.to) != cfg.name) {
    return;
  }
  ++counters.requests_received;
  const std::string from = get(r.from);
  if (!valid_name(from)) {
    ++counters.dropped;
    return;
  }
  auto pit = peers.find(from);
  if (pit == peers.end() || pit->second.boot != r.from_boot) {
    return;  // its announcement has not come yet: only its hello, which it repeats until answered
  }
  Peer& p = pit->second;
  if (!p.announced || !p.refused.empty() || p.gone) {
    // Not heard announcing itself yet (its time mode and protocol unchecked), refused, or let
    // go: nothing it asks is done. A daemon says hello again each heartbeat until answered.
    ++counters.dropped;
    return;
  }
  if (p.next_request != 0 && r.seq > p.next_request) {
    counters.dropped += r.seq - p.next_request;  // lost on the way (a reader that fell behind)
  }
  p.next_request = r.seq + 1;
  if (r.kind == canemu_net_REQ_HELLO) {
    if (stepped() && stepped_owner.empty() && !p.follower) {
      p.follower = true;
      log::info("daemon {} uses this daemon's buses in stepped time: steps wait for it", from);
    }
    canemu_net_Event e{};
    e.kind = canemu_net_EV_WELCOME;
    e.at_ns = sim.scheduler().now().ns();
    send_event(from, e);
    return;
  }
  if (r.kind == canemu_net_REQ_OPEN) {
    open_hosted(r);
    return;
  }
  if (r.kind == canemu_net_REQ_STEP) {
    if (stepped() && stepped_owner.empty() && r.step_ns > 0 &&
        r.step_ns <= int64_t{60} * 1'000'000'000) {
      enqueue_step(Step{r.step_ns, from, r.step});
    } else {
      ++counters.dropped;
    }
    return;
  }
  if (r.kind == canemu_net_REQ_READY) {
    if (barrier && r.step == step_no && waiting.erase(from) > 0 && waiting.empty()) {
      run_step();
    }
    return;
  }
  Hosted* h = find_hosted(from, r.node);
  if (h == nullptr) {
    ++counters.dropped;
    return;
  }
  switch (r.kind) {
    case canemu_net_REQ_ONLINE:
      h->node->go_online();
      break;
    case canemu_net_REQ_OFFLINE:
      h->queue.clear();
      h->node->go_offline();
      break;
    case canemu_net_REQ_CLOSE:
      hosted.erase({from, r.node});
      break;
    case canemu_net_REQ_RESTART:
      h->node->restart();
      break;
    case canemu_net_REQ_NAME: {
      if (!valid_name(get(r.device))) {
        ++counters.dropped;
        break;
      }
      const std::string name = from + "/" + get(r.device);
      if (!sim.devices().exists(name)) {
        h->lease = {};
        h->lease = sim.add_ephemeral(name, h->bus, *h->node, 0);
      }
      break;
    }
    case canemu_net_REQ_TX: {
      auto f = frame_of_fields(r);
      if (!f) {
        ++counters.dropped;
        break;
      }
      if (h->queue.size() >= kOwnerQueue) {
        h->emit(canemu_net_EV_DROPPED, sim.scheduler().now(), &*f);
        break;
      }
      h->queue.push_back(TxFrame{*f, r.single_shot, r.self_reception});
      h->node->kick();
      break;
    }
    default:
      ++counters.dropped;
      break;
  }
}

SimTime Distributed::Impl::local_time(const Peer& owner, int64_t owner_ns) {
  const int64_t now = sim.scheduler().now().ns();
  const int64_t here = owner_ns - owner.offset_ns;
  if (here < now) {
    ++counters.late;
  }
  return SimTime::from_ns(std::min(here, now));
}

void Distributed::Impl::on_event(const canemu_net_Event& e) {
  const std::string to = get(e.to);
  if (to != cfg.name && !to.empty()) {
    return;
  }
  const std::string from = get(e.from);
  auto pit = peers.find(from);
  if (to.empty() && from != stepped_owner) {
    return;  // another owner's steps
  }
  ++counters.events_received;
  if (pit == peers.end() || pit->second.boot != e.from_boot || pit->second.gone) {
    ++counters.dropped;
    return;
  }
  Peer& p = pit->second;
  SimScheduler& s = sim.scheduler();
  switch (e.kind) {
    case canemu_net_EV_WELCOME:
      if (!p.welcomed && p.refused.empty()) {
        owner_up(p);
      }
      return;
    case canemu_net_EV_STEP_BEGIN: {
      // This daemon's world runs to the owner's instant (it joins at the owner's time), its
      // transmitters look at their rings, and what they send reaches the owner before "ready".
      s.run_until(SimTime::from_ns(std::max(e.at_ns, s.now().ns())));
      if (self->before_step) {
        self->before_step();
      }
      canemu_net_Request r{};
      r.kind = canemu_net_REQ_READY;
      r.step = e.step;
      send_request(from, r);
      return;
    }
    case canemu_net_EV_STEP_DONE: {
      const std::size_t events = s.run_until(SimTime::from_ns(std::max(e.at_ns, s.now().ns())));
      if (self->after_step) {
        self->after_step();
      }
      if (get(e.asker) == cfg.name && self->step_done) {
        self->step_done(e.token, events, s.now().ns());
      }
      return;
    }
    default:
      break;
  }
  for (RemoteNode* n : nodes) {
    if (n->owner() == from && n->number() == e.node) {
      deliver(*n, e, p);
      return;
    }
  }
  ++counters.dropped;
}

void Distributed::Impl::deliver(RemoteNode& n, const canemu_net_Event& e, const Peer& owner) {
  if (!stepped()) {
    n.deliver(e, local_time(owner, e.at_ns));
    return;
  }
  // Stepped: this daemon's time is the owner's; an event of the step runs here at its instant
  // when the step's end is reached (EV_STEP_DONE), so everything on this daemon sees it in order.
  SimScheduler& s = sim.scheduler();
  const SimTime at = SimTime::from_ns(e.at_ns);
  if (at <= s.now()) {
    counters.late += at < s.now() ? 1 : 0;
    n.deliver(e, s.now());
    return;
  }
  s.schedule_at(at, [this, e, number = n.number()](SimTime now) {
    for (RemoteNode* m : nodes) {
      if (m->number() == number) {
        m->deliver(e, now);
        return;
      }
    }
  });
}

void Distributed::Impl::enqueue_step(Step st) {
  steps.push_back(std::move(st));
  if (!barrier) {
    start_next_step();
  }
}

void Distributed::Impl::start_next_step() {
  if (steps.empty() || barrier) {
    return;
  }
  ++step_no;
  waiting.clear();
  for (const auto& [name, p] : peers) {
    if (p.follower && !p.gone) {
      waiting.insert(name);
    }
  }
  if (waiting.empty()) {
    run_step();
    return;
  }
  barrier = true;
  barrier_deadline_ms = monotonic_ms() + cfg.timeout_ms;
  canemu_net_Event e{};
  e.kind = canemu_net_EV_STEP_BEGIN;
  e.at_ns = sim.scheduler().now().ns();
  e.step = step_no;
  e.step_ns = steps.front().ns;
  send_event("", e);
}

void Distributed::Impl::run_step() {
  barrier = false;
  waiting.clear();
  if (steps.empty()) {
    return;
  }
  const Step st = steps.front();
  steps.pop_front();
  if (self->before_step) {
    self->before_step();
  }
  SimScheduler& s = sim.scheduler();
  const std::size_t events = s.run_until(s.now() + SimDuration(st.ns));
  if (self->after_step) {
    self->after_step();
  }
  canemu_net_Event e{};
  e.kind = canemu_net_EV_STEP_DONE;
  e.at_ns = s.now().ns();
  e.step = step_no;
  e.step_ns = st.ns;
  e.token = st.token;
  put(e.asker, st.asker);
  send_event("", e);  // every follower runs to the step's end; the asker answers its client
  if (st.asker == cfg.name && self->step_done) {
    self->step_done(st.token, events, s.now().ns());
  }
  start_next_step();
}

void Distributed::Impl::receive() {
  uint64_t rung = 0;
  [[maybe_unused]] const auto n = ::read(wake, &rung, sizeof rung);
  constexpr int kBatch = 32;
  uint32_t taken = 0;
  bool more = false;
  auto drain = [&](dds_entity_t reader, auto handle) {
    while (true) {
      if (taken >= kMaxTakesPerKick) {
        more = true;
        return;
      }
      void* samples[kBatch] = {};
      dds_sample_info_t infos[kBatch];
      const dds_return_t got = dds_take(reader, samples, infos, kBatch, kBatch);
      if (got <= 0) {
        return;
      }
      for (dds_return_t i = 0; i < got; ++i) {
        if (infos[i].valid_data) {
          handle(samples[i]);
        }
      }
      dds_return_loan(reader, samples, got);
      taken += static_cast<uint32_t>(got);
      if (got < kBatch) {
        return;
      }
    }
  };
  drain(r_daemons, [&](void* s) { on_daemon(*static_cast<const canemu_net_Daemon*>(s)); });
  drain(r_requests, [&](void* s) { on_request(*static_cast<const canemu_net_Request*>(s)); });
  drain(r_events, [&](void* s) { on_event(*static_cast<const canemu_net_Event*>(s)); });
  if (more) {
    on_data(0, this);  // the rest on the loop's next turn
  }
}

Distributed::Distributed(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Distributed::~Distributed() {
  impl_->announce(true);
}

tl::expected<std::unique_ptr<Distributed>, std::string> Distributed::open(Simulation& sim,
                                                                          const Config& config) {
  auto impl = std::make_unique<Impl>(sim, config);
  if (auto problem = impl->open()) {
    return tl::unexpected(*problem);
  }
  Impl* raw = impl.get();
  std::unique_ptr<Distributed> d(new Distributed(std::move(impl)));
  raw->self = d.get();
  return d;
}

const std::string& Distributed::name() const {
  return impl_->cfg.name;
}

std::unique_ptr<HostedNode> Distributed::make_node(std::size_t bus, CanBus& placeholder, bool fd) {
  const BusConfig& b = impl_->sim.bus_config(bus);
  return std::make_unique<RemoteNode>(impl_->sim.scheduler(), placeholder, *impl_,
                                      impl_->next_node++, bus, b.name, b.owner, fd);
}

void Distributed::name_node(HostedNode& node, const std::string& device) {
  for (RemoteNode* n : impl_->nodes) {
    if (n == &node) {
      n->set_device(device);
    }
  }
}

int Distributed::doorbell_fd() const {
  return impl_->wake;
}

void Distributed::kick() {
  impl_->receive();
}

Doorbell& Distributed::heartbeat() {
  return impl_->heartbeat;
}

bool Distributed::follows_owner() const {
  return impl_->stepped() && !impl_->stepped_owner.empty();
}

bool Distributed::leads_steps() const {
  return impl_->leads();
}

std::optional<std::string> Distributed::step(int64_t step_ns, uint64_t token) {
  Impl& d = *impl_;
  if (follows_owner()) {
    if (!d.attached(d.stepped_owner)) {
      return fmt::format("steps are daemon {}'s, which is not attached ({})", d.stepped_owner,
                         remote_buses().empty() ? "" : remote_buses().front().reason);
    }
    canemu_net_Request r{};
    r.kind = canemu_net_REQ_STEP;
    r.step_ns = step_ns;
    r.step = token;
    if (!d.send_request(d.stepped_owner, r)) {
      return fmt::format("DDS did not take the step request for daemon {}", d.stepped_owner);
    }
    return std::nullopt;
  }
  d.enqueue_step(Impl::Step{step_ns, d.cfg.name, token});
  return std::nullopt;
}

std::vector<PeerStatus> Distributed::peers() const {
  std::vector<PeerStatus> out;
  const int64_t now = monotonic_ms();
  for (const auto& [name, p] : impl_->peers) {
    PeerStatus s;
    s.name = name;
    s.version = p.version;
    s.protocol = p.protocol;
    s.state = p.gone ? "gone" : !p.refused.empty() ? "refused" : "up";
    s.reason = p.gone ? p.gone_reason : p.refused;
    s.time = time_text(p.time_mode, p.scale);
    s.last_heard_ms = now - p.heard_ms;
    s.buses = p.buses;
    for (const auto& [key, h] : impl_->hosted) {
      s.hosted_nodes += key.first == name ? 1 : 0;
    }
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<RemoteBusStatus> Distributed::remote_buses() const {
  std::vector<RemoteBusStatus> out;
  const Simulation& sim = impl_->sim;
  for (std::size_t i = 0; i < sim.bus_count(); ++i) {
    const BusConfig& b = sim.bus_config(i);
    if (!sim.config().remote(b)) {
      continue;
    }
    RemoteBusStatus s;
    s.bus = b.name;
    s.owner = b.owner;
    auto it = impl_->peers.find(b.owner);
    if (it == impl_->peers.end() || it->second.gone) {
      s.state = "waiting";
      s.reason = it == impl_->peers.end() ? fmt::format("daemon {} not heard from", b.owner)
                                          : fmt::format("daemon {} is gone", b.owner);
    } else if (!it->second.refused.empty()) {
      s.state = "refused";
      s.reason = it->second.refused;
    } else if (std::string problem = impl_->bus_problem(b); !problem.empty()) {
      s.state = "refused";
      s.reason = problem;
    } else if (!it->second.welcomed) {
      s.state = "waiting";
      s.reason = fmt::format("daemon {} has not answered yet", b.owner);
    } else {
      s.state = "attached";
    }
    for (RemoteNode* n : impl_->nodes) {
      s.nodes += n->bus_name() == b.name && n->in_use() ? 1 : 0;
    }
    out.push_back(std::move(s));
  }
  return out;
}

const DistributedCounters& Distributed::counters() const {
  return impl_->counters;
}

const NodeStats* Distributed::remote_stats(std::size_t bus, NodeId node) const {
  for (const RemoteNode* n : impl_->nodes) {
    if (n->bus() == bus && n->node() == node) {
      return &n->stats();
    }
  }
  return nullptr;
}

#else  // no Cyclone DDS

struct Distributed::Impl {};

Distributed::Distributed(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Distributed::~Distributed() = default;

tl::expected<std::unique_ptr<Distributed>, std::string> Distributed::open(Simulation&,
                                                                          const Config&) {
  return tl::unexpected(
      std::string("canemud was built without DDS (cyclonedds-dev, idlc): [distributed] needs it"));
}
// Never reached: open() makes no object in this build.
const std::string& Distributed::name() const {
  static const std::string none;
  return none;
}
std::unique_ptr<model::HostedNode> Distributed::make_node(std::size_t, model::CanBus&, bool) {
  return nullptr;
}
void Distributed::name_node(model::HostedNode&, const std::string&) {}
int Distributed::doorbell_fd() const {
  return -1;
}
void Distributed::kick() {}
Doorbell& Distributed::heartbeat() {
  return *this;
}
bool Distributed::follows_owner() const {
  return false;
}
bool Distributed::leads_steps() const {
  return false;
}
std::optional<std::string> Distributed::step(int64_t, uint64_t) {
  return std::string("no DDS in this build");
}
std::vector<PeerStatus> Distributed::peers() const {
  return {};
}
std::vector<RemoteBusStatus> Distributed::remote_buses() const {
  return {};
}
const DistributedCounters& Distributed::counters() const {
  static const DistributedCounters none;
  return none;
}
const model::NodeStats* Distributed::remote_stats(std::size_t, model::NodeId) const {
  return nullptr;
}

#endif

}  // namespace canemu::daemon
