// canemud as a process, measured from its clients:
// - client -> daemon -> client latency in real time on an idle 1 Mbit/s bus: a frame put in one
//   channel's ring until it comes out of another's, minus the frame's own duration on the wire
//   (targets p50 <= 30 us, p99 <= 200 us), beside a Unix-socket round trip measured in the
//   same run;
// - how long after a client is killed its resources are freed (target: 100 ms);
// - peak resident memory of canemud on the default configuration with 64 clients connected,
//   each with an open channel (target <= 64 MB);
// - what 16 idle buses with two adapters and a connected client cost canemud in real time:
//   processor time and wake-ups per second (target: nothing).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../../tests/support/canemud_process.hpp"
#include "../support/latency.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace {

using namespace canemu;
using bench::now_ns;
using bench::report;
using bench::sleep_ns;

constexpr std::size_t kSamples = 2000;
constexpr int64_t kGapNs = 500'000;  // the bus is idle again long before the next frame

std::string write_config(const std::string& dir) {
  const std::string path = dir + "/bench.toml";
  std::ofstream f(path);
  f << "[simulation]\ntime = \"realtime\"\n\n[[bus]]\nname = \"fast\"\nkind = \"can\"\n"
       "bitrate = 1000000\n";
  return path;
}

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

void BM_ClientDaemonClientLatencyRealtime(benchmark::State& state) {
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string config = write_config(::mkdtemp(dir));
  testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + config});
  auto ca = client::Connection::open(daemon.socket(), "bench-a");
  auto cb = client::Connection::open(daemon.socket(), "bench-b");
  if (!daemon.ready() || !ca || !cb) {
    state.SkipWithError(("canemud did not start: " + daemon.log()).c_str());
    return;
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
      // The baseline, in the same run: one Unix-socket round trip.
      int64_t t = now_ns();
      (void)!::send(fds[0], &t, sizeof t, 0);
      (void)!::recv(fds[0], &t, sizeof t, 0);
      round_trip.push_back(now_ns() - t);
    }
  }
  ::close(fds[0]);
  ::waitpid(echo, nullptr, 0);
  ::close(fds[1]);
  state.counters["frame_wire_us"] = static_cast<double>(wire_ns) / 1000.0;
  report(state, "beyond_frame", beyond);
  report(state, "unix_socket_round_trip", round_trip);
  ::unlink(config.c_str());
  ::rmdir(dir);
}
BENCHMARK(BM_ClientDaemonClientLatencyRealtime)
    ->ArgName("spin_us")
    ->Arg(0)
    ->Arg(50)
    ->Arg(200)
    ->Arg(1000)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

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

// utime + stime in clock ticks, and voluntary + involuntary context switches, of a process.
std::pair<uint64_t, uint64_t> cpu_ticks_and_switches(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  // Fields after the command's closing parenthesis: state is field 3, utime 14, stime 15.
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::vector<std::string> f((std::istream_iterator<std::string>(fields)),
                             std::istream_iterator<std::string>());
  const uint64_t ticks = f.size() > 12 ? std::stoull(f[11]) + std::stoull(f[12]) : 0;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  uint64_t switches = 0;
  std::string line;
  while (std::getline(status, line)) {
    if (line.find("ctxt_switches:") != std::string::npos) {
      switches += std::stoull(line.substr(line.find(':') + 1));
    }
  }
  return {ticks, switches};
}

void BM_IdleBusesCostNothing(benchmark::State& state) {
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string path = std::string(::mkdtemp(dir)) + "/idle.toml";
  {
    std::ofstream f(path);
    f << "[simulation]\ntime = \"realtime\"\n";
    for (int i = 0; i < 16; ++i) {
      f << "[[bus]]\nname = \"can" << i << "\"\nbitrate = 500000\n";
    }
    f << "[[device]]\nname = \"a\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\", "
         "\"can1\"]\n[[device]]\nname = \"b\"\nmodel = \"ixxat-usb-to-can\"\n"
         "controllers = [\"can2\"]\n";
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
BENCHMARK(BM_IdleBusesCostNothing)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
