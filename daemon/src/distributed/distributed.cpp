#include "canemu/daemon/distributed/distributed.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/world/simulation.hpp"

#ifdef CANEMU_HAVE_DDS
#include "distributed_impl.hpp"
#endif

#ifndef CANEMU_VERSION
#define CANEMU_VERSION "unknown"
#endif

namespace canemu::daemon {


#ifdef CANEMU_HAVE_DDS

Distributed::Impl::~Impl() {
  undecodable.clear();  // Cyclone's log no longer rings this daemon's doorbell
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
  for (const char* name : {"canemu/net/daemons", "canemu/net/requests", "canemu/net/events"}) {
    undecodable.push_back(
        std::make_unique<UndecodableSamples>(cfg.domain, name, [this] { on_data(0, this); }));
  }
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
  if (const dds_return_t rc = dds_write(w_daemons, &d); rc != DDS_RETCODE_OK) {
    drop(NetDrop::not_written,
         fmt::format("DDS did not take this daemon's announcement: {}", dds_strretcode(rc)));
  }
}

bool Distributed::Impl::send_request(const std::string& owner, canemu_net_Request& r) {
  put(r.from, cfg.name);
  r.from_boot = boot;
  put(r.to, owner);
  r.seq = ++req_seq;
  if (const dds_return_t rc = dds_write(w_requests, &r); rc != DDS_RETCODE_OK) {
    drop(NetDrop::not_written, fmt::format("DDS did not take a request ({}) for daemon {}: {}",
                                           request_name(r.kind), owner, dds_strretcode(rc)));
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
  if (const dds_return_t rc = dds_write(w_events, &e); rc != DDS_RETCODE_OK) {
    drop(NetDrop::not_written,
         fmt::format("DDS did not take an event ({}) for daemon {}: {}", event_name(e.kind),
                     to.empty() ? std::string("every follower") : to, dds_strretcode(rc)));
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
  settle();
  const std::string name = get(d.name);
  if (!valid_name(name)) {
    // Not a daemon of ours (names follow the configuration's rule).
    drop(NetDrop::unknown_daemon,
         fmt::format("dropped an announcement from \"{}\": a daemon's name {}", printable(name),
                     kNameRule));
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
  const std::string was_refused = p.refused;
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
  // The log says what status says: joined, or refused with the reason (and any change).
  const std::string who = fmt::format("daemon {} (time {}, protocol {}, version {})", name,
                                      time_text(p.time_mode, p.scale), p.protocol, p.version);
  if (fresh || p.refused != was_refused) {
    if (p.refused.empty()) {
      log::info("{} {}", who, fresh ? "joined" : "is accepted now");
    } else {
      log::warning("{} refused: {}", who, p.refused);
    }
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

void Distributed::Impl::peer_gone(Peer& p, const std::string& why) {
  if (p.follower && (barrier || running)) {
    step_dropped.push_back(fmt::format("daemon {} ({})", p.name, why));
  }
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
  if (p.name == stepped_owner && loop != nullptr) {
    loop->steps_failed(fmt::format("daemon {}, whose steps these are, is gone ({})", p.name, why));
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
  // A classic controller may be given by its SJA1000 registers alone (ddstypes/canemu_net.idl):
  // their timing at the IXXAT's 16 MHz is its nominal timing.
  BitTiming nominal{r.clock_hz, r.n_prescaler, r.n_tseg1, r.n_tseg2, r.n_sjw, 1};
  const bool registers_only = !r.fd && r.clock_hz == 0 && r.n_prescaler == 0 && r.n_tseg1 == 0 &&
                              r.n_tseg2 == 0 && r.n_sjw == 0 && (r.btr0 != 0 || r.btr1 != 0);
  if (registers_only) {
    auto t = sja1000::decode_btr(r.btr0, r.btr1);
    if (!t) {
      refuse(fmt::format("BTR0 0x{:02X} BTR1 0x{:02X} are no SJA1000 timing: {}", r.btr0, r.btr1,
                         t.error().message));
      return;
    }
    nominal = *t;
  }
  if (!timing_ok(nominal.clock_hz, nominal.prescaler, nominal.tseg1, nominal.tseg2, nominal.sjw) ||
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
  h->fd = r.fd && h->node->fd_capable();
  h->queue.clear();
  HostedNodeSettings s;
  s.btr0 = r.btr0;
  s.btr1 = r.btr1;
  s.nominal = nominal;
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
  settle();
  ++counters.requests_received;
  const std::string from = get(r.from);
  if (!valid_name(from)) {
    drop(NetDrop::unknown_daemon,
         fmt::format("dropped a request ({}) from \"{}\": a daemon's name {}", request_name(r.kind),
                     printable(from), kNameRule));
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
    drop(NetDrop::not_accepted,
         fmt::format("dropped a request ({}) from daemon {}: it is {}", request_name(r.kind), from,
                     p.gone               ? "gone (" + p.gone_reason + ")"
                     : !p.refused.empty() ? "refused (" + p.refused + ")"
                                          : std::string("not heard announcing itself yet")));
    return;
  }
  if (p.next_request != 0 && r.seq > p.next_request) {
    // Lost on the way (a reader that fell behind).
    drop(NetDrop::lost,
         fmt::format("{} request{} from daemon {} lost on the way (sequence {} after {})",
                     r.seq - p.next_request, r.seq - p.next_request == 1 ? "" : "s", from, r.seq,
                     p.next_request - 1),
         r.seq - p.next_request);
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
      drop(NetDrop::malformed,
           fmt::format("dropped a step request of {} ns from daemon {}: {}", r.step_ns, from,
                       !stepped() || !stepped_owner.empty() ? "this daemon leads no steps"
                                                            : "a step is 1 ns to 60 s"));
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
    drop(NetDrop::no_node,
         fmt::format("dropped a request ({}) from daemon {}: its node {} ({}) "
                     "is not open here",
                     request_name(r.kind), from, r.node, printable(get(r.device))));
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
        drop(NetDrop::malformed,
             fmt::format("dropped a name request from daemon {}: \"{}\" is not a device name", from,
                         printable(get(r.device))));
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
        drop(NetDrop::malformed,
             fmt::format("dropped a frame of daemon {}'s node {}: id 0x{:X}, dlc {}, {} bytes{}{} "
                         "is no frame",
                         from, printable(get(r.device)), r.id, r.dlc, r.len, r.fd ? ", CAN FD" : "",
                         r.remote ? ", remote" : ""));
        break;
      }
      if (f->fd() && !h->fd) {
        // As the LCM and DDS bridges: a frame this node's controller does not send is rejected,
        // not put on the wire as something else; the node's driver hears it was not sent.
        drop(NetDrop::fd_on_classic,
             fmt::format("rejected a CAN FD frame (id 0x{:X}, dlc {}) of daemon {}'s node {}: "
                         "{}",
                         f->id(), f->dlc(), from, printable(get(r.device)),
                         sim.bus_config(h->bus).kind == BusKind::can
                             ? sim.bus_config(h->bus).name + " is a classic CAN bus"
                             : std::string("the node was opened as a classic controller")));
        h->emit(canemu_net_EV_DROPPED, sim.scheduler().now(), &*f);
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
      drop(NetDrop::malformed,
           fmt::format("dropped a request of unknown kind {} from daemon {}", r.kind, from));
      break;
  }
}

SimTime Distributed::Impl::local_time(const Peer& owner, int64_t owner_ns) {
  const int64_t now = sim.scheduler().now().ns();
  const int64_t here = owner_ns - owner.offset_ns;
  // The offset underestimates by the heartbeat's delay, so an event is normally a little late
  // here (the link's delay beyond the fastest heartbeat's): late beyond kLateBoundNs counts.
  if (here < now) {
    counters.late_max_ns = std::max(counters.late_max_ns, now - here);
    counters.late += now - here > kLateBoundNs ? 1 : 0;
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
    drop(NetDrop::not_accepted,
         fmt::format("dropped an event ({}) from daemon {}: it is {}", event_name(e.kind),
                     printable(from),
                     pit == peers.end()                ? "not heard announcing itself"
                     : pit->second.boot != e.from_boot ? "of another boot than the one heard"
                                                       : "gone (" + pit->second.gone_reason + ")"));
    return;
  }
  Peer& p = pit->second;
  settle();
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
      if (loop != nullptr) {
        loop->before_step();
      }
      canemu_net_Request r{};
      r.kind = canemu_net_REQ_READY;
      r.step = e.step;
      send_request(from, r);
      return;
    }
    case canemu_net_EV_STEP_DONE: {
      run_to(SimTime::from_ns(std::max(e.at_ns, s.now().ns())),
             [this, mine = get(e.asker) == cfg.name, token = e.token,
              note = printable(get(e.text))](uint64_t events) {
               if (loop != nullptr) {
                 loop->after_step();
               }
               if (mine && loop != nullptr) {
                 loop->step_done(token, events, sim.scheduler().now().ns(), note);
               }
             });
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
  drop(NetDrop::no_node,
       fmt::format("dropped an event ({}) from daemon {}: node {} is not open here",
                   event_name(e.kind), from, e.node));
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
    counters.late_max_ns = std::max(counters.late_max_ns, (s.now() - at).ns());
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
  for (const auto& u : undecodable) {
    if (const uint64_t lost = u->take(); lost > 0) {
      drop(NetDrop::undecodable,
           fmt::format("{} sample{} on {} that Cyclone DDS could not decode (a daemon of another "
                       "protocol, or no daemon of canemu's)",
                       lost, lost == 1 ? "" : "s", u->topic()),
           lost);
    }
  }
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
  std::unique_ptr<Distributed> d(new Distributed(std::move(impl)));
  return d;
}

tl::expected<std::unique_ptr<RemoteBuses>, std::string> Distributed::open_remote(
    Simulation& sim, const Config& config) {
  auto d = open(sim, config);
  if (!d) {
    return tl::unexpected(d.error());
  }
  return std::unique_ptr<RemoteBuses>(std::move(*d));
}

Distributed* Distributed::of(Simulation& sim) {
  return dynamic_cast<Distributed*>(sim.remote());
}

void Distributed::set_step_loop(StepLoop* loop) {
  impl_->loop = loop;
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

#else  // no Cyclone DDS

struct Distributed::Impl {};

Distributed::Distributed(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Distributed::~Distributed() = default;

tl::expected<std::unique_ptr<Distributed>, std::string> Distributed::open(Simulation&,
                                                                          const Config&) {
  return tl::unexpected(
      std::string("canemud was built without DDS (cyclonedds-dev, idlc): [distributed] needs it"));
}
tl::expected<std::unique_ptr<RemoteBuses>, std::string> Distributed::open_remote(Simulation& sim,
                                                                                const Config& c) {
  return tl::unexpected(open(sim, c).error());
}
Distributed* Distributed::of(Simulation&) {
  return nullptr;
}
// Never reached: open() makes no object in this build.
void Distributed::set_step_loop(StepLoop*) {}
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
