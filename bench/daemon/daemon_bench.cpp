// canemud as a process, measured from its clients:
// - client -> daemon -> client latency in real time on an idle 1 Mbit/s bus: a frame put in one
//   channel's ring until it comes out of another's, minus the frame's own duration on the wire
//   (targets p50 <= 30 us, p99 <= 200 us), beside a Unix-socket round trip measured in the
//   same run, and the ratio of the two;
// - the same across two daemons sharing a bus over Cyclone DDS: a client of the follower to
//   one of the owner and back, and between two clients of the follower, beside two clients of
//   the owner and two of a daemon without DDS in the same run;
// The rest of daemon.json (freeing a killed client's resources, memory, idle and busy buses,
// scaled and long stepped time) comes from daemon_load_bench.cpp, linked into the same binary.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../../tests/support/canemud_process.hpp"
#include "../../tests/support/scoped_env.hpp"
#include "../support/latency.hpp"
#include "../support/process_figures.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace {

using namespace canemu;
using bench::now_ns;
using bench::report;
using bench::sleep_ns;
using bench::smoke_run;

constexpr std::size_t kSamples = bench::kLatencySamples;
constexpr int64_t kGapNs = bench::kLatencyGapNs;

// `idle_poll`: canemud asks the kernel to keep idle CPUs polling (simulation.cpu_latency_us = 0;
// it holds /dev/cpu_dma_latency, which needs root: without, it logs why and goes on).
std::string write_config(const std::string& dir, bool idle_poll = false) {
  const std::string path = dir + "/bench.toml";
  std::ofstream f(path);
  f << "[simulation]\ntime = \"realtime\"\n"
    << (idle_poll ? "cpu_latency_us = 0\n" : "")
    << "\n[[bus]]\nname = \"fast\"\nkind = \"can\"\nbitrate = 1000000\n";
  return path;
}

void BM_ClientDaemonClientLatencyRealtime(benchmark::State& state) {
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const bool idle_poll = state.range(1) != 0;
  const std::string config = write_config(::mkdtemp(dir), idle_poll);
  testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + config});
  auto ca = client::Connection::open(daemon.socket(), "bench-a");
  auto cb = client::Connection::open(daemon.socket(), "bench-b");
  if (!daemon.ready() || !ca || !cb) {
    state.SkipWithError(("canemud did not start: " + daemon.log()).c_str());
    return;
  }
  if (idle_poll) {  // whether canemud could make the request (1) or runs without it (0)
    state.counters["idle_poll_held"] =
        daemon.read_log_until("CPUs asked to wake within 0 us", 2000) ? 1 : 0;
  }
  client::ChannelOptions o;
  o.bus = "fast";
  o.spin_us = static_cast<uint32_t>(state.range(0));  // both channels' spin before blocking
  auto a = client::Channel::open(*ca, o);
  auto b = client::Channel::open(*cb, o);
  if (!a || !b) {
    state.SkipWithError("channels did not open");
    return;
  }
  ipc::ChannelMessage m;
  m.id = 0x123;
  m.dlc = 8;
  for (uint8_t k = 0; k < 8; ++k) {
    m.data[k] = static_cast<uint8_t>(0x11 * (k + 1));
  }
  const auto frame = model::Frame::classic(0x123, std::span<const uint8_t>(m.data, 8));
  // At 1 Mbit/s every bit is 1 us; a frame is received at the end of its EOF.
  const int64_t wire_ns = int64_t{model::encode(*frame).length} * 1000;
  std::vector<int64_t> beyond;
  std::vector<int64_t> round_trip;
  int fds[2];
  ::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fds);
  const pid_t echo = ::fork();
  if (echo == 0) {
    ::close(fds[0]);
    int64_t t;
    while (::recv(fds[1], &t, sizeof t, 0) == sizeof t) {
      (void)!::send(fds[1], &t, sizeof t, 0);
    }
    ::_exit(0);
  }
  for (auto _ : state) {
    for (std::size_t i = 0; i < kSamples; ++i) {
      sleep_ns(kGapNs);
      // The baseline, in the same run: one Unix-socket round trip, after the pause as the
      // frame (right after the frame it would meet what the spins of the frame's way still
      // occupy).
      int64_t t = now_ns();
      (void)!::send(fds[0], &t, sizeof t, 0);
      (void)!::recv(fds[0], &t, sizeof t, 0);
      round_trip.push_back(now_ns() - t);
      const int64_t t0 = now_ns();
      if (!a->send(m)) {
        state.SkipWithError("send failed");
        break;
      }
      auto got = b->receive(1000);
      const int64_t t1 = now_ns();
      if (!got) {
        state.SkipWithError("frame did not arrive");
        break;
      }
      beyond.push_back(t1 - t0 - wire_ns);
    }
  }
  ::close(fds[0]);
  ::waitpid(echo, nullptr, 0);
  ::close(fds[1]);
  state.counters["frame_wire_us"] = static_cast<double>(wire_ns) / 1000.0;
  report(state, "beyond_frame", beyond);
  report(state, "unix_socket_round_trip", round_trip);
  // Issue 41's figure: the daemon's p50 in units of the socket's, both interleaved in this run.
  state.counters["beyond_frame_over_unix_socket_p50"] =
      bench::percentile(beyond, 0.5) / std::max(bench::percentile(round_trip, 0.5), 1.0);
  state.counters["beyond_frame_over_unix_socket_p99"] =
      bench::percentile(beyond, 0.99) / std::max(bench::percentile(round_trip, 0.99), 1.0);
  ::unlink(config.c_str());
  ::rmdir(dir);
}
BENCHMARK(BM_ClientDaemonClientLatencyRealtime)
    ->ArgNames({"spin_us", "idle_poll"})
    ->ArgsProduct({{0, 50, 200, 1000}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// A bus spanning two daemons, in real time: canemud "a" owns bus "fast" (1 Mbit/s), canemud "b"
// declares it with owner "a"; both in a DDS domain and partition of this run's own, by unicast
// over the loopback interface (CYCLONEDDS_URI). local_link 1 (the default): b's requests and
// a's events go over their same-host link; 0: over DDS, as between two hosts. Two ephemeral
// channels on each daemon (spinning spin_us before they block); frames go round-robin along four
// paths, each beyond the frame's own duration on the bus:
//   a_to_a: a client of a to another of a (no hop: the baseline, in the same run);
//   b_to_a: a client of b to one of a (one hop: b's request to the owner);
//   a_to_b: a client of a to one of b (one hop: the owner's event to b);
//   b_to_b: a client of b to another of b (two hops: request and event);
//   one_daemon: a client of a third canemud, without DDS, to another of it (the baseline of
//   issue 41's figure: b_to_b_over_one_daemon_p50 and _p99).
// kDdsSamples per path, fewer in a smoke run (--benchmark_min_time below 0.5 s, as in CI).

std::string distributed_config(const std::string& dir, const std::string& name, int domain,
                               const char* owner_line, bool local_link) {
  const std::string path = dir + "/" + name + ".toml";
  std::ofstream f(path);
  f << "[simulation]\ntime = \"realtime\"\n\n[distributed]\nname = \"" << name
    << "\"\ndomain = " << domain << "\npartition = \"canemu-bench-" << ::getpid()
    << "\"\nheartbeat_ms = 100\ntimeout_ms = 2000\nlocal_link = " << (local_link ? "true" : "false")
    << "\n\n[[bus]]\nname = \"fast\"\nkind = \"can\"\nbitrate = 1000000\n"
    << owner_line;
  return path;
}

std::string fmt_leg(const char* daemon, const char* leg, const char* p) {
  return std::string("leg_") + daemon + "_" + leg + "_" + p + "_us";
}

constexpr std::size_t kDdsSamples = 2000;  // per path
constexpr std::size_t kDdsSmokeSamples = 50;
constexpr int64_t kDdsGapNs = 1'000'000;

void BM_DdsHopLatencyRealtime(benchmark::State& state) {
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string base = ::mkdtemp(dir);
  const int domain = 1 + static_cast<int>(::getpid() % 200);
  const testing::ScopedEnv uri(
      "CYCLONEDDS_URI",
      "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/>"
      "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
      "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30"
      "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
      "</Domain></CycloneDDS>");
  // Each daemon times the legs of the link's messages and logs them as it stops.
  const testing::ScopedEnv legs("CANEMU_NET_LEGS", "1");
  const bool local_link = state.range(1) != 0;
  const std::string config_a = distributed_config(base, "a", domain, "", local_link);
  const std::string config_b = distributed_config(base, "b", domain, "owner = \"a\"\n", local_link);
  const auto cleanup = [&] {
    std::remove(config_a.c_str());
    std::remove(config_b.c_str());
    std::remove((base + "/bench.toml").c_str());
    ::rmdir(base.c_str());
  };
  testing::CanemudProcess da(CANEMUD_PATH, {"--config=" + config_a});
  testing::CanemudProcess db(CANEMUD_PATH, {"--config=" + config_b});
  testing::CanemudProcess dc(CANEMUD_PATH, {"--config=" + write_config(base)});
  if (!da.ready() || !db.ready() || !dc.ready()) {
    state.SkipWithError(("canemud did not start: " + da.log() + db.log() + dc.log()).c_str());
    cleanup();
    return;
  }
  // b attaches once a answers its hello (discovery over lo takes some 100 ms).
  const int64_t attach_start = now_ns();
  while (!db.read_log_until("daemon a answers", 100) && now_ns() - attach_start < 20'000'000'000) {
  }
  const int64_t attach_ns = now_ns() - attach_start;
  if (db.log().find("daemon a answers") == std::string::npos) {
    state.SkipWithError(("b did not attach within 20 s: " + db.log()).c_str());
    cleanup();
    return;
  }
  auto ca1 = client::Connection::open(da.socket(), "bench-a1");
  auto ca2 = client::Connection::open(da.socket(), "bench-a2");
  auto cb1 = client::Connection::open(db.socket(), "bench-b1");
  auto cb2 = client::Connection::open(db.socket(), "bench-b2");
  auto cc1 = client::Connection::open(dc.socket(), "bench-c1");
  auto cc2 = client::Connection::open(dc.socket(), "bench-c2");
  if (!ca1 || !ca2 || !cb1 || !cb2 || !cc1 || !cc2) {
    state.SkipWithError("connections did not open");
    cleanup();
    return;
  }
  client::ChannelOptions o;
  o.bus = "fast";
  o.spin_us = static_cast<uint32_t>(state.range(0));  // every channel's spin before blocking
  auto a1 = client::Channel::open(*ca1, o);
  auto a2 = client::Channel::open(*ca2, o);
  auto b1 = client::Channel::open(*cb1, o);
  auto b2 = client::Channel::open(*cb2, o);
  auto c1 = client::Channel::open(*cc1, o);
  auto c2 = client::Channel::open(*cc2, o);
  if (!a1 || !a2 || !b1 || !b2 || !c1 || !c2) {
    state.SkipWithError("channels did not open");
    cleanup();
    return;
  }
  std::array<client::Channel*, 6> all{&*a1, &*a2, &*b1, &*b2, &*c1, &*c2};
  struct Path {
    const char* name;
    client::Channel* from;
    client::Channel* to;
    std::vector<int64_t> beyond;
  };
  std::array<Path, 5> paths{{{"a_to_a", &*a1, &*a2, {}},
                             {"b_to_a", &*b1, &*a2, {}},
                             {"a_to_b", &*a1, &*b2, {}},
                             {"b_to_b", &*b1, &*b2, {}},
                             {"one_daemon", &*c1, &*c2, {}}}};
  const std::size_t samples = smoke_run() ? kDdsSmokeSamples : kDdsSamples;
  uint32_t seq = 0;
  // One frame along `p`, tagged with its sequence number in its first four bytes; the receiver
  // passes over anything else (a late copy of an earlier frame). The time beyond the frame, or
  // nothing when it did not come within a second.
  const auto one = [&](Path& p) -> std::optional<int64_t> {
    ipc::ChannelMessage drained;
    for (client::Channel* c : all) {
      while (c->rx().get(&drained) == ipc::RingStatus::ok) {
      }
    }
    ipc::ChannelMessage m;
    m.id = 0x123;
    m.dlc = 8;
    ++seq;
    std::memcpy(m.data, &seq, sizeof seq);
    std::memset(m.data + 4, 0x55, 4);
    const auto frame = model::Frame::classic(0x123, std::span<const uint8_t>(m.data, 8));
    const int64_t wire_ns = int64_t{model::encode(*frame).length} * 1000;  // 1 us a bit
    const int64_t t0 = now_ns();
    if (!p.from->send(m)) {
      return std::nullopt;
    }
    while (now_ns() - t0 < 1'000'000'000) {
      auto got = p.to->receive(1000);
      if (!got) {
        return std::nullopt;
      }
      uint32_t tag = 0;
      std::memcpy(&tag, got->data, sizeof tag);
      if (got->kind == static_cast<uint8_t>(ipc::ChannelMessageKind::frame) && tag == seq) {
        return now_ns() - t0 - wire_ns;
      }
    }
    return std::nullopt;
  };
  for (auto _ : state) {
    // Warming up: b's nodes on the owner, DDS's first samples on each path.
    for (int k = 0; k < 20; ++k) {
      for (Path& p : paths) {
        sleep_ns(kDdsGapNs);
        if (!one(p)) {
          state.SkipWithError((std::string("no frame on ") + p.name + " (warm-up)").c_str());
          cleanup();
          return;
        }
      }
    }
    for (std::size_t i = 0; i < samples; ++i) {
      for (Path& p : paths) {  // round-robin, so a busy spell hits every path alike
        sleep_ns(kDdsGapNs);
        const auto beyond = one(p);
        if (!beyond) {
          state.SkipWithError((std::string("no frame on ") + p.name).c_str());
          cleanup();
          return;
        }
        p.beyond.push_back(*beyond);
      }
    }
  }
  for (const Path& p : paths) {
    report(state, p.name, p.beyond);
    state.counters[std::string(p.name) + "_max_us"] =
        static_cast<double>(*std::max_element(p.beyond.begin(), p.beyond.end())) / 1000.0;
  }
  // Issue 41's figure: both hops against one canemud, interleaved in this run.
  for (const auto& [p, name] : {std::pair{0.5, "p50"}, std::pair{0.99, "p99"}}) {
    state.counters[std::string("b_to_b_over_one_daemon_") + name] =
        bench::percentile(paths[3].beyond, p) /
        std::max(bench::percentile(paths[4].beyond, p), 1.0);
  }
  state.counters["samples_per_path"] = static_cast<double>(samples);
  state.counters["attach_ms"] = static_cast<double>(attach_ns) / 1e6;
  // The legs (p50 and p99, us) as the daemons timed them: the request's on b (its write) and a,
  // the event's on a (the wait from the frame's end, the write) and b.
  const std::vector<const char*> legs_b{"request_write", "event_delivery", "event_turn"};
  const std::vector<const char*> legs_a{"request_delivery", "request_turn", "event_wait",
                                        "event_write"};
  for (auto [d, who, names] : {std::tuple{&db, "b", &legs_b}, std::tuple{&da, "a", &legs_a}}) {
    d->terminate(5000);  // once each: it logs the legs as it stops
    d->read_log_until("link legs", 1000);
    for (const char* leg : *names) {
      const std::size_t at = d->log().find(std::string(leg) + "=");
      double p50 = 0;
      double p99 = 0;
      if (at != std::string::npos &&
          std::sscanf(d->log().c_str() + at + std::strlen(leg) + 1, "%lf/%lf", &p50, &p99) == 2) {
        state.counters[fmt_leg(who, leg, "p50")] = p50;
        state.counters[fmt_leg(who, leg, "p99")] = p99;
      }
    }
  }
  cleanup();
}
BENCHMARK(BM_DdsHopLatencyRealtime)
    ->ArgNames({"spin_us", "local_link"})
    ->ArgsProduct({{0, 200 /* the default */}, {1 /* the default */, 0}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
