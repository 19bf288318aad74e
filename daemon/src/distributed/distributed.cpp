#include "canemu/daemon/distributed/distributed.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/world/simulation.hpp"

#ifdef CANEMU_HAVE_DDS
#include "remote_node.hpp"
#endif

#ifndef CANEMU_VERSION
#define CANEMU_VERSION "unknown"
#endif

namespace canemu::daemon {

#ifdef CANEMU_HAVE_DDS

Distributed::Impl::~Impl() {
  if (legs.on()) {
    log::info("{}", legs.summary());
  }
  undecodable.clear();  // Cyclone's log no longer rings this daemon's doorbell
  for (RemoteNode* n : nodes) {
    n->unlink();
  }
  hosted.clear();  // their nodes stop and go back to the pool
  if (participant > 0) {
    dds_delete(participant);
  }
  for (const auto& l : links) {
    if (l->fd >= 0) {
      ::close(l->fd);
    }
  }
  for (int fd : {wake, timer, ep, link_listen}) {
    if (fd >= 0) {
      ::close(fd);
    }
  }
}

Result<> Distributed::Impl::open() {
  wake = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  timer = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  if (wake < 0 || timer < 0) {
    return fail(Errc::io, fmt::format("eventfd/timerfd: {}", std::strerror(errno)));
  }
  itimerspec its{};
  its.it_interval.tv_sec = cfg.heartbeat_ms / 1000;
  its.it_interval.tv_nsec = static_cast<long>(cfg.heartbeat_ms % 1000) * 1'000'000;
  its.it_value.tv_nsec = 1'000'000;  // the first at once
  ::timerfd_settime(timer, 0, &its, nullptr);
  if (auto opened = open_links(); !opened) {
    return opened;
  }

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
    return fail(Errc::io, fmt::format("Cyclone DDS cannot join domain {}: {} (CYCLONEDDS_URI: {})",
                                      cfg.domain, dds_strretcode(participant),
                                      std::getenv("CYCLONEDDS_URI") ? std::getenv("CYCLONEDDS_URI")
                                                                    : "unset"));
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
  const dds_entity_t t_events = topic(&canemu_net_Events_desc, "canemu/net/events");
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
    return fail(Errc::io,
                fmt::format("Cyclone DDS cannot make the topics canemu/net/* in domain {}: {}",
                            cfg.domain, dds_strretcode(failure)));
  }
  return {};
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
  r.seq = ++req_seq[owner];
  const int64_t start = legs.on() ? LinkLegs::mono() : 0;
  if (LocalLink* l = link_to(owner)) {
    link_request(*l, r);
    if (legs.on()) {
      legs.add(Leg::request_write, LinkLegs::mono() - start);
    }
    ++counters.requests_sent;
    return true;
  }
  const dds_return_t rc = dds_write(w_requests, &r);
  if (legs.on()) {
    legs.add(Leg::request_write, LinkLegs::mono() - start);
  }
  if (rc != DDS_RETCODE_OK) {
    drop(NetDrop::not_written, fmt::format("DDS did not take a request ({}) for daemon {}: {}",
                                           request_name(r.kind), owner, dds_strretcode(rc)));
    return false;
  }
  ++counters.requests_sent;
  return true;
}

void Distributed::Impl::send_event(const std::string& to, const canemu_net_Event& e) {
  // A follower reads what is for it and what is for every follower ("") in the order written:
  // the two are not reordered against each other.
  for (Outgoing& o : outgoing) {
    if (!o.events.empty() && o.to != to && (to.empty() || o.to.empty())) {
      write_events(o);
    }
  }
  auto it =
      std::find_if(outgoing.begin(), outgoing.end(), [&](const Outgoing& o) { return o.to == to; });
  if (it == outgoing.end()) {
    it = outgoing.insert(outgoing.end(), Outgoing{to, {}});
  }
  it->events.push_back(e);
  if (it->events.size() == kEventsPerSample) {
    write_events(*it);
  }
}

void Distributed::Impl::flush_events() {
  for (Outgoing& o : outgoing) {
    if (!o.events.empty()) {
      write_events(o);
    }
  }
}

void Distributed::Impl::write_events(Outgoing& o) {
  const uint64_t seq = ++ev_seq;
  int64_t start = 0;
  if (legs.on()) {
    start = LinkLegs::mono();
    if (realtime()) {
      legs.observe(sim.scheduler().now().ns());
      for (const canemu_net_Event& e : o.events) {
        if (e.kind == canemu_net_EV_RX || e.kind == canemu_net_EV_TX_DONE) {
          legs.add(Leg::event_wait, legs.since_instant(e.at_ns));
          break;
        }
      }
    }
  }
  const std::size_t n = o.events.size();
  // A user on this host gets its events over its link; what is for every follower goes over
  // every user's link, and over DDS unless every follower has one (a user with a link reads none
  // of its owner's samples).
  LocalLink* only = o.to.empty() ? nullptr : link_from(o.to);
  bool dds = only == nullptr;
  if (only != nullptr) {
    link_events(*only, o.to, seq, o.events);
  } else if (o.to.empty()) {
    for (const auto& l : links) {
      if (l->fd >= 0 && !l->to_owner && link_from(l->peer) == l.get()) {
        link_events(*l, "", seq, o.events);
      }
    }
    dds = std::any_of(peers.begin(), peers.end(), [&](const auto& p) {
      return p.second.follower && !p.second.gone && link_from(p.first) == nullptr;
    });
  }
  if (dds) {
    canemu_net_Events b{};
    put(b.from, cfg.name);
    b.from_boot = boot;
    put(b.to, o.to);
    b.seq = seq;
    b.list._buffer = o.events.data();
    b.list._length = static_cast<uint32_t>(n);
    b.list._maximum = b.list._length;
    b.list._release = false;
    if (const dds_return_t rc = dds_write(w_events, &b); rc != DDS_RETCODE_OK) {
      drop(NetDrop::not_written,
           fmt::format("DDS did not take {} ({}) for daemon {}: {}",
                       n == 1 ? std::string("an event") : fmt::format("{} events", n),
                       event_name(o.events.front().kind),
                       o.to.empty() ? std::string("every follower") : o.to, dds_strretcode(rc)),
           n);
      o.events.clear();
      return;
    }
  }
  if (legs.on()) {
    legs.add(Leg::event_write, LinkLegs::mono() - start);
  }
  counters.events_sent += n;
  o.events.clear();
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
  flush_events();
  links_sweep();
  links_resume();
}

void Distributed::Impl::receive() {
  uint64_t rung = 0;
  [[maybe_unused]] const auto n = ::read(wake, &rung, sizeof rung);
  LinkLegs::Take timing;
  if (legs.on()) {
    timing = legs.take();
    if (realtime()) {
      legs.observe(sim.scheduler().now().ns());
    }
  }
  constexpr int kBatch = 32;
  uint32_t taken = 0;
  bool more = false;
  auto drain = [&](dds_entity_t reader, int timed, auto handle) {
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
          if (timed >= 0 && legs.on()) {
            legs.taken(timing, infos[i].source_timestamp, timed == 1);
          }
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
  drain(r_daemons, -1, [&](void* s) { on_daemon(*static_cast<const canemu_net_Daemon*>(s)); });
  // A daemon with a same-host link to this one speaks over it alone: its samples are not read.
  drain(r_requests, 0, [&](void* s) {
    const auto& r = *static_cast<const canemu_net_Request*>(s);
    if (link_from(get(r.from)) == nullptr) {
      on_request(r);
    }
  });
  drain(r_events, 1, [&](void* s) {
    const auto& b = *static_cast<const canemu_net_Events*>(s);
    if (link_to(get(b.from)) == nullptr) {
      on_events(b);
    }
  });
  flush_events();  // the answers to what came
  if (more) {
    on_data(0, this);  // the rest on the loop's next turn
  }
}

Distributed::Distributed(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Distributed::~Distributed() {
  impl_->stopping = true;  // a link failing from here on lets nobody go (the loop is gone)
  impl_->flush_events();
  impl_->announce(true);
  impl_->links_bye();
}

Result<std::unique_ptr<Distributed>> Distributed::open(Simulation& sim, const Config& config) {
  auto impl = std::make_unique<Impl>(sim, config);
  if (auto opened = impl->open(); !opened) {
    return tl::unexpected(std::move(opened.error()));
  }
  std::unique_ptr<Distributed> d(new Distributed(std::move(impl)));
  return d;
}

Result<std::unique_ptr<RemoteBuses>> Distributed::open_remote(Simulation& sim,
                                                              const Config& config) {
  auto d = open(sim, config);
  if (!d) {
    return tl::unexpected(std::move(d.error()));
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
  return impl_->ep;
}

void Distributed::kick() {
  impl_->serve();
}

int64_t Distributed::take_rung_ns() {
  return impl_->links_rung_ns();
}

bool Distributed::kick_rung() {
  for (const auto& l : impl_->links) {
    if (l->fd >= 0 && !l->to_owner && l->identified) {
      impl_->link_read_requests(*l);
    }
  }
  return false;  // the rest (DDS, events, new connections) at "now"
}

void Distributed::flush() {
  impl_->flush_events();
  impl_->links_sweep();  // a link that closed as it was written to: its daemon is let go now
}

Doorbell& Distributed::heartbeat() {
  return impl_->heartbeat;
}

#else  // no Cyclone DDS

struct Distributed::Impl {};

Distributed::Distributed(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Distributed::~Distributed() = default;

Result<std::unique_ptr<Distributed>> Distributed::open(Simulation&, const Config&) {
  return fail(Errc::unavailable,
              "canemud was built without DDS (cyclonedds-dev, idlc): [distributed] needs it");
}
Result<std::unique_ptr<RemoteBuses>> Distributed::open_remote(Simulation& sim, const Config& c) {
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
int64_t Distributed::take_rung_ns() {
  return 0;
}
bool Distributed::kick_rung() {
  return true;
}
void Distributed::flush() {}
Doorbell& Distributed::heartbeat() {
  return *this;
}
bool Distributed::follows_owner() const {
  return false;
}
bool Distributed::leads_steps() const {
  return false;
}
Result<> Distributed::step(int64_t, uint64_t) {
  return fail(Errc::unavailable, "no DDS in this build");
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
