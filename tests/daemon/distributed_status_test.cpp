// What the control protocol reports of buses across hosts (PeerListReply, for `canemu status`
// and `canemu metrics`): two daemons' simulations "a" and "b" in one process, in a DDS domain of
// this process's own on the loopback interface only (Cyclone DDS delivers between participants
// of one process), b using a's bus can0. The test runs both daemons' loops by hand: it polls
// their doorbells (messages that came, heartbeats due) with a deadline and kicks what rang, until
// what it waits for is true.
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "bridge_test_support.hpp"
#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/distributed/distributed.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu_net.h"

namespace canemu::daemon {
namespace {

using bridge_test::test_domain;

// A daemon's configuration: [distributed] with `name` in the test's partition (one per test, so
// no test hears another's daemons), and `rest` (buses, devices, the time mode).
std::unique_ptr<Simulation> daemon_named(const std::string& name, const std::string& rest) {
  const std::string text = fmt::format(
      "{}\n[distributed]\nname = \"{}\"\ndomain = {}\npartition = \"{}\"\nheartbeat_ms = 20\n"
      "timeout_ms = 5000\n",
      rest, name, test_domain(), ::testing::UnitTest::GetInstance()->current_test_info()->name());
  auto config = parse_config(text, name + ".toml");
  if (!config) {
    ADD_FAILURE() << config.error().front();
    return nullptr;
  }
  auto sim = Simulation::build(*config, Distributed::open_remote);
  if (!sim) {
    ADD_FAILURE() << sim.error().front();
    return nullptr;
  }
  return std::move(*sim);
}

constexpr const char* kBusA = "[[bus]]\nname = \"can0\"\nbitrate = 500000\n";
constexpr const char* kBusB = "[[bus]]\nname = \"can0\"\nbitrate = 500000\nowner = \"a\"\n";

// Runs the daemons' loops (what came over DDS, the heartbeats) until done() or `limit` passed.
template <class Done>
bool pump(const std::vector<Simulation*>& sims, Done done,
          std::chrono::milliseconds limit = std::chrono::seconds(10)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  std::vector<Doorbell*> bells;
  for (Simulation* s : sims) {
    bells.push_back(Distributed::of(*s));
    bells.push_back(&Distributed::of(*s)->heartbeat());
  }
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) {
      return false;
    }
    std::vector<pollfd> fds;
    for (Doorbell* b : bells) {
      fds.push_back(pollfd{b->doorbell_fd(), POLLIN, 0});
    }
    if (::poll(fds.data(), fds.size(), 100) < 0) {
      return false;
    }
    for (std::size_t i = 0; i < fds.size(); ++i) {
      if ((fds[i].revents & POLLIN) != 0) {
        bells[i]->kick();
      }
    }
  }
  return true;
}

const PeerStatus* peer(const Simulation& sim, const std::string& name,
                       std::vector<PeerStatus>& keep) {
  keep = sim.remote()->peers();
  for (const PeerStatus& p : keep) {
    if (p.name == name) {
      return &p;
    }
  }
  return nullptr;
}

std::string remote_state(const Simulation& sim) {
  const auto buses = sim.remote()->remote_buses();
  return buses.empty() ? std::string() : buses.front().state;
}

TEST(DistributedStatus, WithoutDistributedTheReplySaysSoAndListsNothing) {
  auto sim = std::move(*Simulation::build(*load_default_config()));
  auto r = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>());
  fill_peer_list(*sim, *r, 0, 0);
  EXPECT_EQ(r->enabled, 0u);
  EXPECT_EQ(ipc::name_of(r->name), "");
  EXPECT_EQ(r->domain, 0u);
  EXPECT_EQ(r->peer_total, 0u);
  EXPECT_EQ(r->peer_count, 0u);
  EXPECT_EQ(r->bus_total, 0u);
  EXPECT_EQ(r->bus_count, 0u);
  EXPECT_EQ(r->counters.requests_sent, 0u);
  EXPECT_EQ(ipc::check_message(r.get(), sizeof *r), ipc::ErrorCode::none);
}

TEST(DistributedStatus, AttachedBusAndUpPeerAsTheReplyCarriesThem) {
  auto a = daemon_named("a", std::string(kBusA) + "[[bus]]\nname = \"can1\"\nbitrate = 250000\n");
  auto b = daemon_named("b", kBusB);
  ASSERT_TRUE(a && b);
  // A node of b on the remote bus, programmed and on the bus: a runs its controller.
  model::HostedNode& node = b->spare_node(0);
  auto lease = b->add_ephemeral("eph1", 0, node, 4711);
  node.start(*node_timing(false, {500000, 0, 875}), nullptr,
             [] { return std::optional<model::TxFrame>(); });
  std::vector<PeerStatus> keep;
  // b's requests may reach a before its announcement does: a then knows b by name only.
  const auto ready = [&] {
    const PeerStatus* pb = peer(*a, "b", keep);
    return remote_state(*b) == "attached" && pb != nullptr && pb->state == "up" &&
           pb->hosted_nodes == 1 && !pb->version.empty();
  };
  ASSERT_TRUE(pump({a.get(), b.get()}, ready)) << "b's can0: " << remote_state(*b);

  // a, the owner: b is up and has one node on a's buses; a lists no remote bus.
  auto ra = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>(7));
  fill_peer_list(*a, *ra, 0, 0);
  EXPECT_EQ(ipc::check_message(ra.get(), sizeof *ra), ipc::ErrorCode::none);
  EXPECT_EQ(ra->header.request_id, 7u);
  EXPECT_EQ(ra->enabled, 1u);
  EXPECT_EQ(ipc::name_of(ra->name), "a");
  EXPECT_EQ(ra->domain, test_domain());
  EXPECT_EQ(ipc::name_of(ra->partition), "AttachedBusAndUpPeerAsTheReplyCarriesThem");
  EXPECT_EQ(ra->heartbeat_ms, 20u);
  EXPECT_EQ(ra->timeout_ms, 5000u);
  ASSERT_EQ(ra->peer_total, 1u);
  ASSERT_EQ(ra->peer_count, 1u);
  EXPECT_EQ(ra->first_peer, 0u);
  const ipc::PeerEntry& e = ra->peers[0];
  EXPECT_EQ(ipc::name_of(e.name), "b");
  EXPECT_EQ(ipc::name_of(e.state), "up");
  EXPECT_EQ(ipc::name_of(e.reason), "");
  EXPECT_EQ(ipc::name_of(e.time), "realtime");
  EXPECT_EQ(e.protocol, peer(*a, "b", keep)->protocol);
  EXPECT_NE(e.protocol, 0u);
  EXPECT_EQ(ipc::name_of(e.version), peer(*a, "b", keep)->version);
  EXPECT_FALSE(ipc::name_of(e.version).empty());
  EXPECT_EQ(e.bus_total, 0u);  // b simulates no bus
  EXPECT_EQ(e.bus_count, 0u);
  EXPECT_EQ(e.hosted_nodes, 1u);
  EXPECT_EQ(e.linked, 1u);  // one process, one host: b's requests came over its same-host link
  EXPECT_GE(e.last_heard_ms, 0);
  EXPECT_LT(e.last_heard_ms, 5000);
  EXPECT_EQ(ra->bus_total, 0u);
  EXPECT_EQ(ra->bus_count, 0u);
  const DistributedCounters& ca = Distributed::of(*a)->counters();
  EXPECT_EQ(ra->counters.requests_sent, ca.requests_sent);
  EXPECT_EQ(ra->counters.requests_received, ca.requests_received);
  EXPECT_EQ(ra->counters.events_sent, ca.events_sent);
  EXPECT_EQ(ra->counters.events_received, ca.events_received);
  EXPECT_EQ(ra->counters.dropped, 0u);
  EXPECT_EQ(ra->counters.late, 0u);
  EXPECT_GE(ra->counters.requests_received, 2u);  // a hello and the node's opening at least
  EXPECT_EQ(ra->counters.requests_sent, 0u);      // a uses no bus of b

  // b, the user: can0 attached to a with its one node; a is up and simulates can0 and can1.
  auto rb = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>());
  fill_peer_list(*b, *rb, 0, 0);
  EXPECT_EQ(ipc::name_of(rb->name), "b");
  ASSERT_EQ(rb->peer_count, 1u);
  const ipc::PeerEntry& pa = rb->peers[0];
  EXPECT_EQ(ipc::name_of(pa.name), "a");
  EXPECT_EQ(ipc::name_of(pa.state), "up");
  EXPECT_EQ(pa.bus_total, 2u);
  ASSERT_EQ(pa.bus_count, 2u);
  EXPECT_EQ(ipc::name_of(pa.buses[0]), "can0");
  EXPECT_EQ(ipc::name_of(pa.buses[1]), "can1");
  EXPECT_EQ(pa.hosted_nodes, 0u);
  EXPECT_EQ(pa.linked, 1u);
  ASSERT_EQ(rb->bus_total, 1u);
  ASSERT_EQ(rb->bus_count, 1u);
  const ipc::RemoteBusEntry& can0 = rb->buses[0];
  EXPECT_EQ(ipc::name_of(can0.bus), "can0");
  EXPECT_EQ(ipc::name_of(can0.owner), "a");
  EXPECT_EQ(ipc::name_of(can0.state), "attached");
  EXPECT_EQ(ipc::name_of(can0.reason), "");
  EXPECT_EQ(can0.nodes, 1u);
  EXPECT_EQ(rb->counters.requests_sent, Distributed::of(*b)->counters().requests_sent);
  EXPECT_EQ(rb->counters.requests_received, 0u);
  EXPECT_EQ(rb->counters.dropped, 0u);

  // Pages beyond the end are empty and still give the totals.
  fill_peer_list(*b, *rb, 1, 1);
  EXPECT_EQ(rb->first_peer, 1u);
  EXPECT_EQ(rb->first_bus, 1u);
  EXPECT_EQ(rb->peer_total, 1u);
  EXPECT_EQ(rb->peer_count, 0u);
  EXPECT_EQ(rb->bus_total, 1u);
  EXPECT_EQ(rb->bus_count, 0u);
  node.stop();
}

TEST(DistributedStatus, ABusDeclaredAtAnotherRateIsRefusedNamingBothRates) {
  auto a = daemon_named("a", kBusA);
  auto b = daemon_named("b", "[[bus]]\nname = \"can0\"\nbitrate = 250000\nowner = \"a\"\n");
  ASSERT_TRUE(a && b);
  ASSERT_TRUE(pump({a.get(), b.get()}, [&] { return remote_state(*b) == "refused"; }))
      << "b's can0: " << remote_state(*b);
  auto r = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>());
  fill_peer_list(*b, *r, 0, 0);
  ASSERT_EQ(r->bus_count, 1u);
  EXPECT_EQ(ipc::name_of(r->buses[0].state), "refused");
  EXPECT_EQ(ipc::name_of(r->buses[0].owner), "a");
  EXPECT_EQ(ipc::name_of(r->buses[0].reason),
            "daemon a runs \"can0\" as can at 500000/0 bit/s; this daemon declares can at "
            "250000/0 bit/s");
  ASSERT_EQ(r->peer_count, 1u);
  EXPECT_EQ(ipc::name_of(r->peers[0].state), "up");  // the daemon is fine, the bus is not
}

TEST(DistributedStatus, ADaemonInAnotherTimeModeIsRefusedWithTheReason) {
  auto a = daemon_named("a", kBusA);
  auto b = daemon_named("b", std::string("[simulation]\ntime = \"stepped\"\n") + kBusB);
  ASSERT_TRUE(a && b);
  std::vector<PeerStatus> keep;
  ASSERT_TRUE(pump({a.get(), b.get()}, [&] {
    const PeerStatus* pb = peer(*a, "b", keep);
    return pb != nullptr && pb->state == "refused" && remote_state(*b) == "refused";
  }));
  auto ra = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>());
  fill_peer_list(*a, *ra, 0, 0);
  ASSERT_EQ(ra->peer_count, 1u);
  EXPECT_EQ(ipc::name_of(ra->peers[0].name), "b");
  EXPECT_EQ(ipc::name_of(ra->peers[0].state), "refused");
  EXPECT_EQ(ipc::name_of(ra->peers[0].time), "stepped");
  EXPECT_EQ(ipc::name_of(ra->peers[0].reason), "its time is stepped, this daemon's realtime");
  auto rb = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>());
  fill_peer_list(*b, *rb, 0, 0);
  ASSERT_EQ(rb->bus_count, 1u);
  EXPECT_EQ(ipc::name_of(rb->buses[0].state), "refused");
  EXPECT_EQ(ipc::name_of(rb->buses[0].reason), "its time is realtime, this daemon's stepped");
  EXPECT_EQ(rb->counters.requests_sent, 0u);  // nothing goes to a refused daemon
}

// ---- a daemon of the test's own making: raw samples on canemu/net/* ----

template <std::size_t N>
void put_text(char (&dst)[N], const std::string& s) {
  std::snprintf(dst, N, "%s", s.c_str());
}

// A participant of the test in the daemons' domain and partition that writes Daemon and Request
// samples as a daemon named `name` would (or as one breaking the rules), and reads the events.
struct RawDaemon {
  std::string name;
  uint64_t boot = 0x5eed;
  uint64_t seq = 0;
  dds_entity_t participant;
  dds_entity_t w_daemons = 0, w_requests = 0, r_events = 0;
  std::string from;  // the owner the events taken last came from

  explicit RawDaemon(std::string n)
      : name(std::move(n)), participant(dds_create_participant(test_domain(), nullptr, nullptr)) {
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    dds_qset_partition1(qos, ::testing::UnitTest::GetInstance()->current_test_info()->name());
    const dds_entity_t pub = dds_create_publisher(participant, qos, nullptr);
    const dds_entity_t sub = dds_create_subscriber(participant, qos, nullptr);
    auto topic = [&](const dds_topic_descriptor_t* d, const char* t) {
      return dds_create_topic(participant, d, t, nullptr, nullptr);
    };
    w_daemons =
        dds_create_writer(pub, topic(&canemu_net_Daemon_desc, "canemu/net/daemons"), qos, nullptr);
    w_requests = dds_create_writer(pub, topic(&canemu_net_Request_desc, "canemu/net/requests"), qos,
                                   nullptr);
    r_events =
        dds_create_reader(sub, topic(&canemu_net_Events_desc, "canemu/net/events"), qos, nullptr);
    dds_delete_qos(qos);
  }
  ~RawDaemon() { dds_delete(participant); }
  RawDaemon(const RawDaemon&) = delete;
  RawDaemon& operator=(const RawDaemon&) = delete;

  bool ok() const { return participant > 0 && w_daemons > 0 && w_requests > 0 && r_events > 0; }
  // The daemon's readers and writer are matched (volatile topics: what is written before is lost).
  bool matched() const {
    dds_publication_matched_status_t d{}, r{};
    dds_subscription_matched_status_t e{};
    dds_get_publication_matched_status(w_daemons, &d);
    dds_get_publication_matched_status(w_requests, &r);
    dds_get_subscription_matched_status(r_events, &e);
    return d.current_count >= 1 && r.current_count >= 1 && e.current_count >= 1;
  }
  // Announces itself speaking `protocol`, in real time, using daemon a's can0.
  void announce(uint16_t protocol, const std::string& version = "raw-test") {
    canemu_net_Daemon d{};
    put_text(d.name, name);
    d.boot = boot;
    d.protocol = protocol;
    put_text(d.version, version);
    d.time_mode = canemu_net_TIME_REALTIME;
    d.scale = 1.0;
    char uses[1][32] = {"a/can0"};
    d.uses._buffer = reinterpret_cast<decltype(d.uses._buffer)>(uses);
    d.uses._length = 1;
    d.uses._maximum = 1;
    d.uses._release = false;
    ASSERT_EQ(dds_write(w_daemons, &d), DDS_RETCODE_OK);
  }
  // Sends `r` to daemon a as the next request (seq 1, 2, ...); returns its seq.
  uint64_t request(canemu_net_Request r) {
    put_text(r.from, name);
    r.from_boot = boot;
    put_text(r.to, "a");
    r.seq = ++seq;
    EXPECT_EQ(dds_write(w_requests, &r), DDS_RETCODE_OK);
    return r.seq;
  }
  // The events that came so far, addressed to this daemon (each sample gathers some).
  std::vector<canemu_net_Event> take(std::vector<canemu_net_Event>& into) {
    for (;;) {
      void* samples[16] = {};
      dds_sample_info_t infos[16];
      const dds_return_t n = dds_take(r_events, samples, infos, 16, 16);
      if (n <= 0) {
        return into;
      }
      for (dds_return_t i = 0; i < n; ++i) {
        const auto* b = static_cast<const canemu_net_Events*>(samples[i]);
        if (infos[i].valid_data && std::string(b->to) == name) {
          from = b->from;
          into.insert(into.end(), b->list._buffer, b->list._buffer + b->list._length);
        }
      }
      dds_return_loan(r_events, samples, n);
    }
  }
};

canemu_net_Request request_of(uint8_t kind, uint32_t node = 0) {
  canemu_net_Request r{};
  r.kind = kind;
  r.node = node;
  put_text(r.bus, "can0");
  put_text(r.device, "ecu");
  return r;
}

// A REQ_OPEN for node `node` on can0 programmed as an SJA1000 at 500 kbit/s.
canemu_net_Request open_request(uint32_t node) {
  const model::HostedNodeSettings t = *node_timing(false, {500000, 0, 875});
  canemu_net_Request r = request_of(canemu_net_REQ_OPEN, node);
  r.btr0 = t.btr0;
  r.btr1 = t.btr1;
  r.clock_hz = t.nominal.clock_hz;
  r.n_prescaler = t.nominal.prescaler;
  r.n_tseg1 = t.nominal.tseg1;
  r.n_tseg2 = t.nominal.tseg2;
  r.n_sjw = t.nominal.sjw;
  return r;
}

TEST(DistributedStatus, APeerOfAnotherProtocolIsRefusedAndItsHelloNotAnswered) {
  ASSERT_EQ(canemu_net_PROTOCOL, 2);  // the reason below names protocols 3 and 2
  auto a = daemon_named("a", kBusA);
  ASSERT_TRUE(a);
  RawDaemon r("r");
  ASSERT_TRUE(r.ok());
  ASSERT_TRUE(pump({a.get()}, [&] { return r.matched(); }));
  r.announce(canemu_net_PROTOCOL + 1);
  std::vector<PeerStatus> keep;
  ASSERT_TRUE(pump({a.get()}, [&] { return peer(*a, "r", keep) != nullptr; }));
  const PeerStatus& p = *peer(*a, "r", keep);
  EXPECT_EQ(p.state, "refused");
  EXPECT_EQ(p.reason, "protocol 3, this daemon speaks 2");
  EXPECT_EQ(p.protocol, 3u);
  EXPECT_EQ(p.version, "raw-test");
  EXPECT_EQ(p.time, "realtime");
  EXPECT_EQ(p.hosted_nodes, 0u);

  // Its hello reaches a (counted received) and is not done (counted dropped): no welcome.
  const DistributedCounters before = Distributed::of(*a)->counters();
  r.request(request_of(canemu_net_REQ_HELLO));
  ASSERT_TRUE(pump({a.get()}, [&] {
    return Distributed::of(*a)->counters().requests_received == before.requests_received + 1;
  }));
  const DistributedCounters& after = Distributed::of(*a)->counters();
  EXPECT_EQ(after.dropped, before.dropped + 1);
  EXPECT_EQ(after.events_sent, before.events_sent);
  // a answers a request as it handles it (above), and delivery within the process takes well
  // under a millisecond: 300 ms without a welcome arriving shows that none was written.
  std::vector<canemu_net_Event> events;
  EXPECT_FALSE(pump(
      {a.get()}, [&] { return !r.take(events).empty(); }, std::chrono::milliseconds(300)));
  EXPECT_TRUE(events.empty()) << "event kind " << int(events.front().kind);
  EXPECT_EQ(peer(*a, "r", keep)->state, "refused");
  EXPECT_EQ(peer(*a, "r", keep)->hosted_nodes, 0u);
}

TEST(DistributedStatus, TheLogSaysWhatStatusSaysInPrintableText) {
  auto a = daemon_named("a", kBusA);
  ASSERT_TRUE(a);
  RawDaemon r("r");
  ASSERT_TRUE(r.ok());
  ASSERT_TRUE(pump({a.get()}, [&] { return r.matched(); }));
  log::Capture capture;
  // A daemon of another protocol with control characters in its version: refused, and the log
  // says refused with the reason (not "joined"), its version printable as status shows it.
  r.announce(canemu_net_PROTOCOL + 1, "1.0\x1b[2J\n");
  std::vector<PeerStatus> keep;
  ASSERT_TRUE(pump({a.get()}, [&] { return peer(*a, "r", keep) != nullptr; }));
  EXPECT_EQ(peer(*a, "r", keep)->state, "refused");
  EXPECT_EQ(peer(*a, "r", keep)->version, "1.0?[2J?");
  std::vector<std::string> about_r;
  for (const std::string& line : capture.lines()) {
    if (line.find("daemon r ") != std::string::npos) {
      about_r.push_back(line);
    }
  }
  EXPECT_EQ(about_r, (std::vector<std::string>{
                         "<4>canemud: daemon r (time realtime, protocol 3, version 1.0?[2J?) "
                         "refused: protocol 3, this daemon speaks 2"}));
}

TEST(DistributedStatus, ADaemonNamedAgainstTheRuleIsNotListedAndCountsAsDropped) {
  auto a = daemon_named("a", kBusA);
  ASSERT_TRUE(a);
  RawDaemon r("Bad Name!");
  ASSERT_TRUE(r.ok());
  ASSERT_TRUE(pump({a.get()}, [&] { return r.matched(); }));
  const uint64_t dropped = Distributed::of(*a)->counters().dropped;
  r.announce(canemu_net_PROTOCOL);
  ASSERT_TRUE(
      pump({a.get()}, [&] { return Distributed::of(*a)->counters().dropped == dropped + 1; }));
  EXPECT_TRUE(Distributed::of(*a)->peers().empty());
  EXPECT_EQ(Distributed::of(*a)->counters().requests_received, 0u);
}

// Daemon a (can0 at 500 kbit/s, with a node of its own to acknowledge frames) and the raw
// daemon r, up in a's list, that has said hello to a and been welcomed.
struct WelcomedPeer {
  std::unique_ptr<Simulation> a = daemon_named("a", kBusA);
  RawDaemon r{"r"};
  model::HostedNode* acker = nullptr;
  std::vector<canemu_net_Event> events;  // r's, not yet taken by next_event()
  std::vector<PeerStatus> keep;          // what peer() found last
  uint64_t hello = 0;                    // the hello's request number

  void welcome() {
    ASSERT_TRUE(a);
    acker = &a->spare_node(0);
    acker->start(*node_timing(false, {500000, 0, 875}), nullptr,
                 [] { return std::optional<model::TxFrame>(); });
    ASSERT_TRUE(r.ok());
    ASSERT_TRUE(pump({a.get()}, [&] { return r.matched(); }));
    r.announce(canemu_net_PROTOCOL);
    ASSERT_TRUE(pump({a.get()}, [&] {
      const PeerStatus* p = peer(*a, "r", keep);
      return p != nullptr && p->state == "up";
    }));
    canemu_net_Event e{};
    hello = r.request(request_of(canemu_net_REQ_HELLO));
    ASSERT_TRUE(next_event(e));
    EXPECT_EQ(e.kind, canemu_net_EV_WELCOME);
  }
  // Waits for r's next event from a.
  bool next_event(canemu_net_Event& out) {
    if (!pump({a.get()}, [&] { return !r.take(events).empty(); })) {
      return false;
    }
    out = events.front();
    events.erase(events.begin());
    return true;
  }
  ~WelcomedPeer() {
    if (acker != nullptr) {
      acker->stop();
    }
  }
};

TEST(DistributedStatus, MalformedRequestsAreRefusedOrDroppedAndTheOwnerGoesOn) {
  WelcomedPeer w;
  ASSERT_NO_FATAL_FAILURE(w.welcome());
  canemu_net_Event e{};
  EXPECT_EQ(w.hello, 1u);

  // 1. A REQ_OPEN with a prescaler of 0: refused, the reason naming the timing.
  canemu_net_Request bad = open_request(1);
  bad.n_prescaler = 0;
  const uint64_t bad_seq = w.r.request(bad);
  ASSERT_TRUE(w.next_event(e));
  EXPECT_EQ(e.kind, canemu_net_EV_REFUSED);
  EXPECT_EQ(e.node, 1u);
  EXPECT_EQ(e.opened, bad_seq);
  EXPECT_EQ(w.r.from, "a");
  EXPECT_EQ(std::string(e.text),
            fmt::format("the node's bit timing (clock {} Hz, prescaler 0, tseg1 {}, tseg2 {}, "
                        "sjw {}) is no controller's",
                        bad.clock_hz, bad.n_tseg1, bad.n_tseg2, bad.n_sjw));
  EXPECT_EQ(bad.clock_hz, 16'000'000u);  // the SJA1000's clock: the text above names it
  EXPECT_EQ(peer(*w.a, "r", w.keep)->hosted_nodes, 0u);

  // 2. The node opened properly, then a classic frame of DLC 15 carrying 64 bytes: dropped.
  w.r.request(open_request(1));
  ASSERT_TRUE(pump({w.a.get()}, [&] { return peer(*w.a, "r", w.keep)->hosted_nodes == 1; }));
  const DistributedCounters before = Distributed::of(*w.a)->counters();
  canemu_net_Request tx = request_of(canemu_net_REQ_TX, 1);
  tx.id = 0x123;
  tx.dlc = 15;
  tx.len = 64;
  w.r.request(tx);
  ASSERT_TRUE(pump({w.a.get()}, [&] {
    return Distributed::of(*w.a)->counters().requests_received == before.requests_received + 1;
  }));
  EXPECT_EQ(Distributed::of(*w.a)->counters().dropped, before.dropped + 1);
  EXPECT_EQ(Distributed::of(*w.a)->counters().events_sent, before.events_sent);  // no EV_DROPPED
  // Why, which rule and which daemon: by reason, and the last reason in the status reply.
  EXPECT_EQ(
      Distributed::of(*w.a)->counters().by_reason[static_cast<std::size_t>(NetDrop::malformed)],
      1u);
  EXPECT_EQ(Distributed::of(*w.a)->counters().last_reason,
            "dropped a frame of daemon r's node ecu: id 0x123, dlc 15, 64 bytes is no frame");
  auto reply = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>());
  fill_peer_list(*w.a, *reply, 0, 0);
  EXPECT_EQ(reply->counters.by_reason[static_cast<std::size_t>(NetDrop::malformed)], 1u);
  EXPECT_EQ(ipc::name_of(reply->counters.last_reason),
            "dropped a frame of daemon r's node ecu: id 0x123, dlc 15, 64 bytes is no frame");

  // 3. The owner goes on: online and a valid frame, which goes out on can0 when a's time runs.
  w.r.request(request_of(canemu_net_REQ_ONLINE, 1));
  tx.dlc = 1;
  tx.len = 1;
  tx.data[0] = 0x42;
  w.r.request(tx);
  ASSERT_TRUE(pump({w.a.get()}, [&] {
    return Distributed::of(*w.a)->counters().requests_received == before.requests_received + 3;
  }));
  EXPECT_EQ(Distributed::of(*w.a)->counters().dropped, before.dropped + 1);
  const model::SimTime start = w.a->scheduler().now();
  w.a->scheduler().run_until(start + model::SimDuration(1'000'000));
  EXPECT_EQ(w.a->bus(0).frames_on_bus(), 1u);
  EXPECT_EQ(w.a->bus(0).error_frames_on_bus(), 0u);
  ASSERT_TRUE(w.next_event(e));
  EXPECT_EQ(e.kind, canemu_net_EV_TX_DONE);
  EXPECT_EQ(e.node, 1u);
  EXPECT_EQ(e.id, 0x123u);
  EXPECT_EQ(e.dlc, 1u);
  EXPECT_EQ(e.len, 1u);
  EXPECT_EQ(e.data[0], 0x42);
  // It starts as a's time runs on (can0 idle) and ends after its bits at 500 kbit/s.
  const auto frame = model::Frame::create(
      model::FrameSpec{.id = 0x123, .dlc = 1, .data = std::span<const uint8_t>(tx.data, 1)});
  ASSERT_TRUE(frame);
  const model::SimDuration bits =
      model::frame_duration(model::encode(*frame), node_timing(false, {500000, 0, 875})->nominal);
  EXPECT_EQ(bits.ns(), 106'000);  // 53 bits (canemu calc frame 123#42)
  EXPECT_EQ(e.at_ns, (start + bits).ns());
}

TEST(DistributedStatus, ACanFdFrameForAClassicNodeIsRejectedAndRegistersAloneOpenANode) {
  WelcomedPeer w;
  ASSERT_NO_FATAL_FAILURE(w.welcome());
  canemu_net_Event e{};

  // 1. A classic node given by its SJA1000 registers alone (the IDL's rule): opened.
  canemu_net_Request open = open_request(1);
  open.clock_hz = 0;
  open.n_prescaler = open.n_tseg1 = open.n_tseg2 = open.n_sjw = 0;
  ASSERT_EQ(open.btr0, 0x00);  // 500 kbit/s at 16 MHz, 87.5 %
  ASSERT_EQ(open.btr1, 0x1C);
  w.r.request(open);
  w.r.request(request_of(canemu_net_REQ_ONLINE, 1));
  ASSERT_TRUE(pump({w.a.get()}, [&] { return peer(*w.a, "r", w.keep)->hosted_nodes == 1; }));
  EXPECT_TRUE(w.r.take(w.events).empty()) << "event kind " << int(w.events.front().kind);

  // 2. A remote request with the FD flag, DLC 9 and 12 bytes for that classic node: rejected
  // as the LCM and DDS bridges reject it, with the reason, and the node's driver hears it was
  // not sent (EV_DROPPED); nothing goes on the wire.
  const DistributedCounters before = Distributed::of(*w.a)->counters();
  canemu_net_Request tx = request_of(canemu_net_REQ_TX, 1);
  tx.id = 0x123;
  tx.fd = true;
  tx.dlc = 9;
  tx.len = 12;
  w.r.request(tx);
  ASSERT_TRUE(w.next_event(e));
  EXPECT_EQ(e.kind, canemu_net_EV_DROPPED);
  EXPECT_EQ(e.id, 0x123u);
  EXPECT_TRUE(e.fd);
  const DistributedCounters& after = Distributed::of(*w.a)->counters();
  EXPECT_EQ(after.rejected, before.rejected + 1);
  EXPECT_EQ(after.dropped, before.dropped);
  EXPECT_EQ(after.by_reason[static_cast<std::size_t>(NetDrop::fd_on_classic)], 1u);
  EXPECT_EQ(after.last_reason,
            "rejected a CAN FD frame (id 0x123, dlc 9) of daemon r's node ecu: can0 is a classic "
            "CAN bus");
  w.a->scheduler().run_until(w.a->scheduler().now() + model::SimDuration(1'000'000));
  EXPECT_EQ(w.a->bus(0).frames_on_bus(), 0u);

  // 3. The same frame classic (DLC 8, 8 bytes) goes out: the node works.
  tx.fd = false;
  tx.dlc = 8;
  tx.len = 8;
  const uint64_t received = Distributed::of(*w.a)->counters().requests_received;
  w.r.request(tx);
  ASSERT_TRUE(pump({w.a.get()}, [&] {
    return Distributed::of(*w.a)->counters().requests_received == received + 1;
  }));
  w.a->scheduler().run_until(w.a->scheduler().now() + model::SimDuration(1'000'000));
  EXPECT_EQ(w.a->bus(0).frames_on_bus(), 1u);
  ASSERT_TRUE(w.next_event(e));
  EXPECT_EQ(e.kind, canemu_net_EV_TX_DONE);
}

}  // namespace
TEST(DistributedStatus, InSteppedTimeARemoteBusIsNotAddedByAReload) {
  auto b = daemon_named("b", std::string("[simulation]\ntime = \"stepped\"\n") + kBusB);
  ASSERT_TRUE(b);
  Config fresh = b->config();
  BusConfig far;
  far.name = "can1";
  far.owner = "a";
  fresh.buses.push_back(far);
  const ReloadReport r = b->reload(fresh);
  EXPECT_TRUE(r.applied.empty());
  EXPECT_EQ(r.refused, (std::vector<std::string>{
                           "bus can1: not added (in stepped time the remote buses, whose owner's "
                           "steps are this daemon's, are set at start)"}));
  EXPECT_EQ(b->bus_count(), 1u);
}

}  // namespace canemu::daemon
