// canemud as a process under load, measured from its clients (part of daemon_bench, with
// daemon_bench.cpp's latencies):
// - how long after a client is killed its resources are freed (target: 100 ms);
// - peak resident memory of canemud on the default configuration with 64 clients connected,
//   each with an open channel (target <= 64 MB);
// - what 16 and 64 idle buses with adapters and a connected client cost canemud in real time:
//   processor time and wake-ups per second (target: nothing);
// - 16 and 64 buses at 1 Mbit/s kept at full load by babbling nodes in real time: canemud's
//   share of a core and whether simulated time keeps up (target: 64 buses keep up with at most
//   50 % of a core), and canemud's processor time per bus frame over the bus engine's alone,
//   measured in this process between the windows;
// - one bus at full load in scaled time, and a long step of busy buses in stepped time.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../../tests/support/canemud_process.hpp"
#include "../support/babbling_buses.hpp"
#include "../support/engine_buses.hpp"
#include "../support/latency.hpp"
#include "../support/process_figures.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace {

using namespace canemu;
using bench::BabblingBuses;
using bench::cpu_ticks_and_switches;
using bench::now_ns;
using bench::report;
using bench::sleep_ns;
using bench::smoke_run;

uint64_t peak_rss_kib(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return std::stoull(line.substr(6));
    }
  }
  return 0;
}

// A client killed with an open channel: the time from SIGKILL until a subscriber hears that
// its device is gone (target: within 100 ms).
void BM_DeadClientCleanup(benchmark::State& state) {
  testing::CanemudProcess daemon(CANEMUD_PATH, {});
  auto watcher = client::Connection::open(daemon.socket(), "bench-watcher");
  if (!daemon.ready() || !watcher || !watcher->subscribe(ipc::kEventDevices)) {
    state.SkipWithError("canemud did not start");
    return;
  }
  std::vector<int64_t> cleanup;
  for (auto _ : state) {
    for (int round = 0; round < 20; ++round) {
      int ready[2];
      if (::pipe(ready) != 0) {
        state.SkipWithError("pipe");
        return;
      }
      const pid_t child = ::fork();
      if (child == 0) {
        auto c = client::Connection::open(daemon.socket(), "doomed");
        client::ChannelOptions o;
        o.bus = "can0";
        auto ch = c ? client::Channel::open(*c, o) : tl::unexpected(c.error());
        (void)!::write(ready[1], ch ? "y" : "n", 1);
        ::pause();
        ::_exit(0);
      }
      ::close(ready[1]);
      char ok = 'n';
      (void)!::read(ready[0], &ok, 1);
      ::close(ready[0]);
      const auto added = watcher->next_notification(5000);
      const int64_t t0 = now_ns();
      ::kill(child, SIGKILL);
      const auto removed = watcher->next_notification(5000);
      const int64_t t1 = now_ns();
      ::waitpid(child, nullptr, 0);
      if (ok != 'y' || !added || !removed) {
        state.SkipWithError("the client's device did not come and go");
        return;
      }
      cleanup.push_back(t1 - t0);
    }
  }
  report(state, "cleanup", cleanup);
  state.counters["cleanup_max_us"] =
      static_cast<double>(*std::max_element(cleanup.begin(), cleanup.end())) / 1000.0;
}
BENCHMARK(BM_DeadClientCleanup)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_DaemonPeakRss64Clients(benchmark::State& state) {
  testing::CanemudProcess daemon(CANEMUD_PATH, {});
  if (!daemon.ready()) {
    state.SkipWithError(("canemud did not start: " + daemon.log()).c_str());
    return;
  }
  for (auto _ : state) {
    std::vector<client::Connection> connections;
    std::vector<client::Channel> channels;
    connections.reserve(64);
    for (int i = 0; i < 64; ++i) {
      auto c = client::Connection::open(daemon.socket(), "bench-" + std::to_string(i));
      if (!c) {
        state.SkipWithError(c.error().message.c_str());
        return;
      }
      connections.push_back(std::move(*c));
      client::ChannelOptions o;
      o.bus = i % 2 ? "can1" : "can0";
      auto ch = client::Channel::open(connections.back(), o);
      if (!ch) {
        state.SkipWithError(ch.error().message.c_str());
        return;
      }
      channels.push_back(std::move(*ch));
    }
    // Some traffic, so every ring has been written by the daemon.
    ipc::ChannelMessage m;
    m.id = 0x100;
    m.dlc = 8;
    for (int k = 0; k < 20; ++k) {
      (void)channels[static_cast<std::size_t>(k)].send(m);
    }
    for (std::size_t k = 0; k < channels.size(); ++k) {
      (void)channels[k].receive(1000);
    }
    state.counters["peak_rss_mb"] = static_cast<double>(peak_rss_kib(daemon.pid())) / 1024.0;
    state.counters["clients"] = static_cast<double>(connections.size());
  }
}
BENCHMARK(BM_DaemonPeakRss64Clients)->Iterations(1)->Unit(benchmark::kMillisecond);

// N idle buses; two adapters on the first three, and with 64 buses 64 more adapters with four
// controllers each (256 controllers on the 64 buses).
void BM_IdleBusesCostNothing(benchmark::State& state) {
  const auto buses = static_cast<int>(state.range(0));
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string path = std::string(::mkdtemp(dir)) + "/idle.toml";
  {
    std::ofstream f(path);
    f << "[simulation]\ntime = \"realtime\"\n";
    for (int i = 0; i < buses; ++i) {
      f << "[[bus]]\nname = \"can" << i << "\"\nbitrate = 500000\n";
    }
    f << "[[device]]\nname = \"a\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\", "
         "\"can1\"]\n[[device]]\nname = \"b\"\nmodel = \"ixxat-usb-to-can\"\n"
         "controllers = [\"can2\"]\n";
    if (buses == 64) {
      for (int d = 0; d < 63; ++d) {  // 253 more controllers: 256 in all
        f << "[[device]]\nname = \"d" << d << "\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [";
        for (int k = 0; k < (d == 62 ? 1 : 4); ++k) {
          f << (k == 0 ? "" : ", ") << "\"can" << (4 * d + k) % 64 << "\"";
        }
        f << "]\n";
      }
    }
  }
  testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + path});
  auto c = client::Connection::open(daemon.socket(), "bench-idle");
  if (!daemon.ready() || !c) {
    state.SkipWithError(("canemud did not start: " + daemon.log()).c_str());
    return;
  }
  client::ChannelOptions o;
  o.bus = "can0";
  auto ch = client::Channel::open(*c, o);
  if (!ch) {
    state.SkipWithError("the channel did not open");
    return;
  }
  constexpr int64_t kWindowNs = 2'000'000'000;
  for (auto _ : state) {
    const auto [ticks0, switches0] = cpu_ticks_and_switches(daemon.pid());
    sleep_ns(kWindowNs);
    const auto [ticks1, switches1] = cpu_ticks_and_switches(daemon.pid());
    const double seconds = static_cast<double>(kWindowNs) / 1e9;
    state.counters["cpu_percent_of_a_core"] = 100.0 * static_cast<double>(ticks1 - ticks0) /
                                              static_cast<double>(::sysconf(_SC_CLK_TCK)) / seconds;
    state.counters["wakeups_per_second"] = static_cast<double>(switches1 - switches0) / seconds;
  }
  std::remove(path.c_str());
  ::rmdir(dir);
}
BENCHMARK(BM_IdleBusesCostNothing)
    ->ArgName("buses")
    ->Arg(16)
    ->Arg(64)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// N buses at 1 Mbit/s in real time (the event loop waking at most every batch_us, or up to
// batch_max_us while events come densely: docs/daemon.md, "Time"), each with a
// babbling node (an ephemeral channel's node that a babble fault makes send 000#0102030405060708
// back to back, for 3600 s) and a second channel's node that acknowledges and receives every
// frame; this process drains the receiving rings every 5 ms. Measured over five windows of 0.6 s
// after a second of warming up: canemud's processor time (/proc/PID/task/*/schedstat, to the
// nanosecond) and wake-ups, simulated seconds per real second, the largest lag a status reply
// showed, the frames the buses carried against what back-to-back frames at 1 Mbit/s would be,
// the frames received, and canemud's own pacing figures over the last second (events, wake-ups
// and the timer against their instants; docs/daemon.md). Before, between and after the windows
// this process runs the bus engine alone on the same workload (bench/support/engine_buses.hpp,
// one thread, some 55,000 frames a turn): canemud's processor time per bus frame in a window
// divided by the engine's per frame in the two turns around it is that window's ratio, and
// `canemud_over_engine_cpu` is the median of the five (issue 41's goal: at most 2 with 64 buses;
// `_min`, `_max` and `_pooled`, all windows against all turns, beside it).
void BM_BusyBusesRealtime(benchmark::State& state) {
  const auto buses = static_cast<int>(state.range(0));
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string path = std::string(::mkdtemp(dir)) + "/busy.toml";
  {
    std::ofstream f(path);
    f << "[simulation]\ntime = \"realtime\"\nbatch_us = " << state.range(1)
      << "\nbatch_max_us = " << state.range(2) << "\n";
    for (int i = 0; i < buses; ++i) {
      f << "[[bus]]\nname = \"can" << i << "\"\nbitrate = 1000000\n";
    }
  }
  testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + path});
  auto c = client::Connection::open(daemon.socket(), "bench-busy");
  BabblingBuses bus;
  if (!bus.start(state, daemon, c, buses)) {
    return;
  }
  uint64_t received = 0;
  const auto drain = [&] { received += bus.drain(); };
  // Sim time, bus frames summed, the largest lag seen and the load of the buses (permille).
  struct Sample {
    int64_t wall_ns = 0;
    int64_t sim_ns = 0;
    uint64_t frames = 0;
    uint64_t load_permille = 0;
    uint64_t cpu_ns = 0;
    uint64_t switches = 0;
    ipc::WirePacing pacing;  // canemud's own figures (docs/daemon.md, "Pacing")
  };
  int64_t max_lag_ns = 0;
  const auto sample = [&]() -> std::optional<Sample> {
    auto s = client::fetch_status(*c);
    if (!s) {
      return std::nullopt;
    }
    Sample out;
    out.wall_ns = now_ns();
    out.sim_ns = s->sim_time_ns;
    for (const ipc::StatusBus& b : s->buses) {
      out.frames += b.frames;
      out.load_permille += b.load_permille;
    }
    out.cpu_ns = bench::cpu_ns(daemon.pid());
    out.switches = cpu_ticks_and_switches(daemon.pid()).second;
    max_lag_ns = std::max(max_lag_ns, s->lag_ns);
    out.pacing = s->pacing;
    return out;
  };
  const auto run_for = [&](int64_t ns) {
    const int64_t end = now_ns() + ns;
    int64_t next_status = now_ns();
    while (now_ns() < end) {
      drain();
      if (now_ns() >= next_status) {  // the lag, five times a second
        auto r =
            c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
        if (r) {
          max_lag_ns = std::max(max_lag_ns, r->lag_ns);
        }
        next_status += 200'000'000;
      }
      sleep_ns(5'000'000);
    }
  };
  // The engine alone, in this thread: some 55,000 frames a turn whatever the number of buses.
  bench::EngineBuses engine(buses);
  const int64_t engine_turn_ns = 6'400'000'000 / buses;
  struct Cost {
    uint64_t cpu_ns = 0;
    uint64_t frames = 0;
    double per_frame() const {
      return static_cast<double>(cpu_ns) / static_cast<double>(std::max<uint64_t>(frames, 1));
    }
  };
  const auto engine_turn = [&] {
    drain();
    Cost turn;
    const uint64_t f0 = engine.frames();
    const int64_t t0 = bench::thread_cpu_ns();
    engine.run(engine_turn_ns);
    turn.cpu_ns = static_cast<uint64_t>(bench::thread_cpu_ns() - t0);
    turn.frames = engine.frames() - f0;
    drain();
    return turn;
  };
  // Windows of canemud alternate with turns of the engine; each window's cost per frame is
  // divided by that of the two turns around it, so that the machine's speed, which drifts over
  // seconds on a shared VM, is the same on both sides of each ratio.
  constexpr int64_t kWarmUpNs = 1'000'000'000;
  constexpr int kWindows = 5;
  constexpr int64_t kWindowNs = 600'000'000;
  for (auto _ : state) {
    engine.run(engine_turn_ns / 4);  // warming up
    run_for(kWarmUpNs);
    max_lag_ns = 0;
    const uint64_t received0 = received;
    std::vector<Cost> turns{engine_turn()};
    std::vector<Cost> windows;
    const auto a = sample();
    std::optional<Sample> b = a;
    for (int w = 0; w < kWindows && b; ++w) {
      const auto w0 = w == 0 ? a : sample();
      run_for(kWindowNs);
      b = w0 ? sample() : std::nullopt;
      if (b) {
        windows.push_back(Cost{b->cpu_ns - w0->cpu_ns, b->frames - w0->frames});
      }
      turns.push_back(engine_turn());
    }
    if (!a || !b) {
      state.SkipWithError("no status");
      return;
    }
    Cost daemon_all;
    Cost engine_all;
    std::vector<double> ratios;
    for (std::size_t w = 0; w < windows.size(); ++w) {
      const Cost around{turns[w].cpu_ns + turns[w + 1].cpu_ns,
                        turns[w].frames + turns[w + 1].frames};
      ratios.push_back(windows[w].per_frame() / around.per_frame());
      daemon_all.cpu_ns += windows[w].cpu_ns;
      daemon_all.frames += windows[w].frames;
    }
    for (const Cost& t : turns) {
      engine_all.cpu_ns += t.cpu_ns;
      engine_all.frames += t.frames;
    }
    std::sort(ratios.begin(), ratios.end());
    const double wall = static_cast<double>(b->wall_ns - a->wall_ns) / 1e9;
    state.counters["cpu_percent_of_a_core"] =
        100.0 * static_cast<double>(b->cpu_ns - a->cpu_ns) / 1e9 / wall;
    state.counters["sim_seconds_per_second"] =
        static_cast<double>(b->sim_ns - a->sim_ns) / 1e9 / wall;
    state.counters["wakeups_per_second"] = static_cast<double>(b->switches - a->switches) / wall;
    state.counters["max_lag_ms"] = static_cast<double>(max_lag_ns) / 1e6;
    state.counters["frames_per_second"] = static_cast<double>(b->frames - a->frames) / wall;
    state.counters["received_per_second"] = static_cast<double>(received - received0) / wall;
    state.counters["mean_bus_load_percent"] =
        static_cast<double>(b->load_permille) / 10.0 / static_cast<double>(buses);
    const double daemon_us = daemon_all.per_frame() / 1e3;
    const double engine_us = engine_all.per_frame() / 1e3;
    state.counters["canemud_cpu_us_per_frame"] = daemon_us;
    state.counters["engine_cpu_us_per_frame"] = engine_us;
    // The median of the windows' ratios; the lowest, the highest and the ratio of all windows
    // to all turns beside it.
    state.counters["canemud_over_engine_cpu"] = ratios[ratios.size() / 2];
    state.counters["canemud_over_engine_cpu_min"] = ratios.front();
    state.counters["canemud_over_engine_cpu_max"] = ratios.back();
    state.counters["canemud_over_engine_cpu_pooled"] = daemon_us / engine_us;
    // canemud's pacing over the last complete second of the window.
    const ipc::WirePacing& p = b->pacing;
    const auto us = [](int64_t ns) { return static_cast<double>(ns) / 1e3; };
    state.counters["event_late_p50_us"] = us(p.events_last.p50_ns);
    state.counters["event_late_p99_us"] = us(p.events_last.p99_ns);
    state.counters["event_late_max_us"] = us(p.events_last.max_ns);
    state.counters["wakeup_late_p50_us"] = us(p.wakeups_last.p50_ns);
    state.counters["wakeup_late_p99_us"] = us(p.wakeups_last.p99_ns);
    state.counters["wakeup_late_max_us"] = us(p.wakeups_last.max_ns);
    state.counters["timer_late_p99_us"] = us(p.timer_last.p99_ns);
    state.counters["spin_us"] = us(p.spin_ns);
  }
  // What the buses would carry at full load: back-to-back frames and 3 bits of intermission.
  const uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  const auto frame = model::Frame::classic(0, std::span<const uint8_t>(data, 8));
  const double bits = static_cast<double>(model::encode(*frame).length + 3);
  state.counters["full_load_frames_per_second"] = static_cast<double>(buses) * 1e6 / bits;
  std::remove(path.c_str());
  ::rmdir(dir);
}
BENCHMARK(BM_BusyBusesRealtime)
    ->ArgNames({"buses", "batch_us", "batch_max_us"})
    ->Args({1, 50, 1000})   // one busy bus: what the spin costs (too few events to widen)
    ->Args({16, 0, 0})      // a wake-up per event: the pacing without batching
    ->Args({16, 50, 50})    // a fixed window of 50 us
    ->Args({16, 50, 1000})  // the defaults: the window widens under load
    ->Args({64, 50, 50})    // a fixed window of 50 us
    ->Args({64, 50, 1000})  // the defaults (issue 41's figure)
    ->Args({64, 1000, 1000})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// Scaled time at full load: one 1 Mbit/s bus kept busy by a babbling node and a receiving node
// (two clients' nodes), at scaled:F. For 3 s after a second of warming up this process drains
// the receiving ring and asks for the status every 10 ms: the scale achieved (simulated seconds
// per real second), the lag at the end, canemud's share of a core, the frames the receiving
// client took, and how long each status answer took (target: within 10 ms at any load).
void BM_ScaledTimeFullLoad(benchmark::State& state) {
  const int64_t scale = state.range(0);
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string path = std::string(::mkdtemp(dir)) + "/scaled.toml";
  {
    std::ofstream f(path);
    f << "[simulation]\ntime = \"scaled:" << scale << "\"\n[[bus]]\nname = \"can0\"\n"
      << "bitrate = 1000000\n";
  }
  testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + path});
  auto c = client::Connection::open(daemon.socket(), "bench-scaled");
  BabblingBuses bus;
  if (!bus.start(state, daemon, c, 1)) {
    return;
  }
  std::vector<int64_t> answers;
  uint64_t received = 0;
  ipc::StatusReply last{};
  const auto run_for = [&](int64_t ns) {
    for (const int64_t end = now_ns() + ns; now_ns() < end;) {
      received += bus.drain();
      const int64_t t0 = now_ns();
      auto r =
          c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
      answers.push_back(now_ns() - t0);
      if (r) {
        last = *r;
      }
      sleep_ns(10'000'000);
    }
  };
  for (auto _ : state) {
    run_for(1'000'000'000);
    answers.clear();
    received = 0;
    const auto [ticks0, switches0] = cpu_ticks_and_switches(daemon.pid());
    const int64_t sim0 = last.sim_time_ns;
    const int64_t wall0 = now_ns();
    run_for(3'000'000'000);
    const double wall = static_cast<double>(now_ns() - wall0) / 1e9;
    const auto [ticks1, switches1] = cpu_ticks_and_switches(daemon.pid());
    state.counters["achieved_scale"] = static_cast<double>(last.sim_time_ns - sim0) / 1e9 / wall;
    state.counters["achieved_scale_status"] = last.achieved_scale;
    state.counters["lag_s"] = static_cast<double>(last.lag_ns) / 1e9;
    state.counters["cpu_percent_of_a_core"] = 100.0 * static_cast<double>(ticks1 - ticks0) /
                                              static_cast<double>(::sysconf(_SC_CLK_TCK)) / wall;
    state.counters["received_per_second"] = static_cast<double>(received) / wall;
    state.counters["status_answer_max_ms"] =
        static_cast<double>(*std::max_element(answers.begin(), answers.end())) / 1e6;
    report(state, "status_answer", answers);
  }
  std::remove(path.c_str());
  ::rmdir(dir);
}
BENCHMARK(BM_ScaledTimeFullLoad)
    ->ArgName("scale")
    ->Arg(100)
    ->Arg(500)
    ->Arg(2000)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// Stepped time with N busy 1 Mbit/s buses (BabblingBuses): one client asks for a step of 60 s
// (the longest allowed) while another asks for the status every 5 ms and canemud pings a watchdog
// every 50 ms (a datagram socket standing in for systemd's). Reported: how long the step took,
// the status answers' times while it ran (target: p99 within 50 ms) and the longest gap between
// two watchdog pings (the unit's WatchdogSec is 10 s; a ping is due every 50 ms here).
void BM_LongStepServesOthers(benchmark::State& state) {
  const auto buses = static_cast<int>(state.range(0));
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string folder = ::mkdtemp(dir);
  const std::string path = folder + "/step.toml";
  {
    std::ofstream f(path);
    f << "[simulation]\ntime = \"stepped\"\n";
    for (int i = 0; i < buses; ++i) {
      f << "[[bus]]\nname = \"can" << i << "\"\nbitrate = 1000000\n";
    }
  }
  const std::string notify_path = folder + "/notify";
  ipc::UniqueFd notify(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::strncpy(a.sun_path, notify_path.c_str(), sizeof a.sun_path - 1);
  if (::bind(notify.get(), reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    state.SkipWithError("cannot bind the notification socket");
    return;
  }
  ::setenv("NOTIFY_SOCKET", notify_path.c_str(), 1);
  ::setenv("WATCHDOG_USEC", "100000", 1);
  testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + path});
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");
  auto c = client::Connection::open(daemon.socket(), "bench-status");
  BabblingBuses bus;
  if (!bus.start(state, daemon, c, buses)) {
    return;
  }
  auto stepper = client::Connection::open(daemon.socket(), "bench-stepper");
  if (!stepper) {
    state.SkipWithError(stepper.error().message.c_str());
    return;
  }
  for (auto _ : state) {
    std::atomic<bool> done{false};
    std::vector<int64_t> pings;
    std::thread watch([&] {
      char buf[256];
      while (!done) {
        pollfd p{notify.get(), POLLIN, 0};
        if (::poll(&p, 1, 20) == 1 && ::recv(notify.get(), buf, sizeof buf, 0) > 0) {
          pings.push_back(now_ns());
        }
      }
    });
    std::vector<int64_t> answers;
    const int64_t start = now_ns();
    int64_t step_ns = 0;
    std::thread step([&] {
      auto req = ipc::make_message<ipc::TimeStepRequest>();
      req.step_ns = int64_t{60} * 1'000'000'000;
      auto r = stepper->call<ipc::TimeStepRequest, ipc::TimeStepReply>(req, -1);
      step_ns = now_ns() - start;
      done = true;
      (void)r;
    });
    while (!done) {
      const int64_t t0 = now_ns();
      auto r =
          c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
      if (!done) {
        answers.push_back(now_ns() - t0);
      }
      bus.drain();
      sleep_ns(5'000'000);
    }
    step.join();
    watch.join();
    int64_t gap = 0;
    for (std::size_t i = 1; i < pings.size(); ++i) {
      if (pings[i] <= start + step_ns) {
        gap = std::max(gap, pings[i] - pings[i - 1]);
      }
    }
    state.counters["step_wall_s"] = static_cast<double>(step_ns) / 1e9;
    state.counters["status_answers"] = static_cast<double>(answers.size());
    state.counters["status_answer_max_ms"] =
        answers.empty()
            ? 0.0
            : static_cast<double>(*std::max_element(answers.begin(), answers.end())) / 1e6;
    state.counters["watchdog_gap_max_ms"] = static_cast<double>(gap) / 1e6;
    report(state, "status_answer", answers);
  }
  std::remove(path.c_str());
  ::unlink(notify_path.c_str());
  ::rmdir(dir);
}
BENCHMARK(BM_LongStepServesOthers)
    ->ArgName("buses")
    ->Arg(8)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
