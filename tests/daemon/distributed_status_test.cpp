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

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "canemu/daemon/distributed.hpp"
#include "canemu/daemon/simulation.hpp"
#include "canemu/daemon/status.hpp"

namespace canemu::daemon {
namespace {

// A domain of this process's own, Cyclone on the loopback interface only.
uint32_t test_domain() {
  static const uint32_t domain = [] {
    ::setenv("CYCLONEDDS_URI",
             "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
             "name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
             "</Domain></CycloneDDS>",
             1);
    return static_cast<uint32_t>(1 + ::getpid() % 200);
  }();
  return domain;
}

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
  auto sim = Simulation::build(*config);
  if (!sim) {
    ADD_FAILURE() << sim.error().front();
    return nullptr;
  }
  return std::move(*sim);
}

constexpr const char* kBusA = "[[bus]]\nname = \"can0\"\nbitrate = 500000\n";
constexpr const char* kBusB = "[[bus]]\nname = \"can0\"\nbitrate = 500000\nowner = \"a\"\n";

// Runs the daemons' loops (what came over DDS, the heartbeats) until done() or 10 s passed.
template <class Done>
bool pump(const std::vector<Simulation*>& sims, Done done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  std::vector<Doorbell*> bells;
  for (Simulation* s : sims) {
    bells.push_back(s->distributed());
    bells.push_back(&s->distributed()->heartbeat());
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
  keep = sim.distributed()->peers();
  for (const PeerStatus& p : keep) {
    if (p.name == name) {
      return &p;
    }
  }
  return nullptr;
}

std::string remote_state(const Simulation& sim) {
  const auto buses = sim.distributed()->remote_buses();
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
  node.start(*controller_timing(false, 500000, 500000, 875), nullptr,
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
  EXPECT_GE(e.last_heard_ms, 0);
  EXPECT_LT(e.last_heard_ms, 5000);
  EXPECT_EQ(ra->bus_total, 0u);
  EXPECT_EQ(ra->bus_count, 0u);
  const DistributedCounters& ca = a->distributed()->counters();
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
  ASSERT_EQ(rb->bus_total, 1u);
  ASSERT_EQ(rb->bus_count, 1u);
  const ipc::RemoteBusEntry& can0 = rb->buses[0];
  EXPECT_EQ(ipc::name_of(can0.bus), "can0");
  EXPECT_EQ(ipc::name_of(can0.owner), "a");
  EXPECT_EQ(ipc::name_of(can0.state), "attached");
  EXPECT_EQ(ipc::name_of(can0.reason), "");
  EXPECT_EQ(can0.nodes, 1u);
  EXPECT_EQ(rb->counters.requests_sent, b->distributed()->counters().requests_sent);
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

}  // namespace
}  // namespace canemu::daemon
