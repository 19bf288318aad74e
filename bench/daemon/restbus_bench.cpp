// canemud running a restbus in real time: 40 simulated ECUs ([[can_node]]) sending 300 cyclic
// 8-byte messages with their signals (counters and checksums on some) on one 500 kbit/s bus
// (bench/support/restbus_config.hpp), beside the baseline: the same nodes and messages without
// signals. The two alternate (baseline, restbus, baseline, ...), each a canemud of its own with
// one client receiving every frame through a channel that blocks in receive() (spin_us 0).
// Per run, over a window after a warm-up: canemud's share of a core and wake-ups per second
// (/proc), the frames received against those the schedule queued in the window (none lost), the
// bus load from the received frames' exact bit counts, canemud's own pacing (events late, the
// wake-ups late; docs/daemon.md, "Pacing") and the delivery lateness the client sees: the
// receipt's wall time minus the frame's time stamp (its end of frame) mapped to wall time.
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "../../tests/support/canemud_process.hpp"
#include "../support/latency.hpp"
#include "../support/process_figures.hpp"
#include "../support/restbus_config.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace {

using namespace canemu;
using bench::now_ns;
using bench::Restbus;

struct Figures {
  double cpu_percent = 0;
  double wakeups_per_second = 0;
  double received = 0;  // frames queued in the window and received
  double expected = 0;  // frames the schedule queued in the window
  double ring_lost = 0;
  double bus_load_percent = 0;  // from the frames received
  double event_late_p50_us = 0;
  double event_late_p99_us = 0;
  double wakeup_late_p99_us = 0;
  double max_lag_ms = 0;
  std::vector<int64_t> delivery;  // receipt minus the frame's end, ns
  std::vector<int64_t> wait;      // the frame's end minus its queued instant, ns
};

struct Received {
  int64_t end_ns;  // the time stamp: simulated end of frame
  int64_t wall_ns;
  uint32_t id;
  uint8_t data[8];
};

// One canemud on the restbus, with or without signals, measured over `window_ns` after
// `warm_ns`; nothing and `error` when something failed.
std::optional<Figures> run_once(const Restbus& r, bool signals, int64_t warm_ns, int64_t window_ns,
                                std::string& error) {
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string path = std::string(::mkdtemp(dir)) + "/restbus.toml";
  const auto cleanup = [&] {
    std::remove(path.c_str());
    ::rmdir(dir);
  };
  std::ofstream(path) << bench::restbus_config(r, "realtime", signals);
  testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + path});
  auto c = client::Connection::open(daemon.socket(), "bench-restbus");
  if (!daemon.ready() || !c) {
    error = "canemud did not start: " + daemon.log();
    cleanup();
    return std::nullopt;
  }
  client::ChannelOptions o;
  o.bus = "can0";
  o.rx_capacity = 4096;
  o.spin_us = 0;
  auto ch = client::Channel::open(*c, o);
  if (!ch) {
    error = "the channel did not open: " + ch.error().message;
    cleanup();
    return std::nullopt;
  }
  // Simulated time is CLOCK_MONOTONIC since canemud's start (real time). A status answer's
  // simulated time is at most that, so (receipt - simulated time) is an upper bound on the start;
  // the smallest of these bounds maps the time stamps: the lateness may be low by the error of
  // the bound (a few microseconds), never high.
  int64_t start_ns = INT64_MAX;
  const auto status = [&]() -> std::optional<ipc::StatusReply> {
    auto s = c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
    if (!s) {
      return std::nullopt;
    }
    start_ns = std::min(start_ns, now_ns() - s->sim_time_ns);
    return *s;
  };
  std::vector<Received> got;
  uint64_t ring_lost = 0;
  const auto receive_until = [&](int64_t end, bool keep) {
    for (int64_t t = now_ns(); t < end; t = now_ns()) {
      const auto m = ch->receive(static_cast<int>(std::max<int64_t>(1, (end - t) / 1'000'000)));
      const int64_t wall = now_ns();
      if (!m || m->kind != static_cast<uint8_t>(ipc::ChannelMessageKind::frame)) {
        continue;
      }
      ring_lost += m->lost_before;
      if (keep) {
        Received x{m->timestamp_ns, wall, m->id, {}};
        std::copy(m->data, m->data + 8, x.data);
        got.push_back(x);
      }
    }
  };
  receive_until(now_ns() + warm_ns, false);
  for (int k = 0; k < 10; ++k) {
    (void)status();
  }
  ring_lost = 0;
  const auto [ticks0, switches0] = bench::cpu_ticks_and_switches(daemon.pid());
  const int64_t wall0 = now_ns();
  const auto a = status();
  receive_until(wall0 + window_ns, true);
  const auto b = status();
  const int64_t wall1 = now_ns();
  const auto [ticks1, switches1] = bench::cpu_ticks_and_switches(daemon.pid());
  receive_until(now_ns() + 100'000'000, true);  // the frames queued before b's instant
  for (int k = 0; k < 10; ++k) {
    (void)status();
  }
  cleanup();
  if (!a || !b) {
    error = "no status answer";
    return std::nullopt;
  }
  Figures f;
  const double wall = static_cast<double>(wall1 - wall0) / 1e9;
  f.cpu_percent = 100.0 * static_cast<double>(ticks1 - ticks0) /
                  static_cast<double>(::sysconf(_SC_CLK_TCK)) / wall;
  f.wakeups_per_second = static_cast<double>(switches1 - switches0) / wall;
  f.ring_lost = static_cast<double>(ring_lost);
  const int64_t from = a->sim_time_ns;
  const int64_t to = b->sim_time_ns;
  for (const bench::RestbusMessage& m : r.messages) {
    f.expected += static_cast<double>(Restbus::queued_in(m, from, to));
  }
  // No frame reaches the client before its end of frame: each (receipt - end) is an upper
  // bound on the start as well.
  for (const Received& x : got) {
    start_ns = std::min(start_ns, x.wall_ns - x.end_ns);
  }
  double bits = 0;
  for (const Received& x : got) {
    const bench::RestbusMessage* m = r.find(x.id);
    if (m == nullptr) {
      error = "a frame of an identifier the restbus does not send: " + std::to_string(x.id);
      return std::nullopt;
    }
    const int64_t queued = Restbus::queued_at(*m, x.end_ns);
    if (queued >= from && queued < to) {
      f.received += 1;
      f.delivery.push_back(x.wall_ns - (start_ns + x.end_ns));
      f.wait.push_back(x.end_ns - queued);
    }
    if (x.end_ns >= from && x.end_ns < to) {
      const auto frame = model::Frame::classic(x.id, std::span<const uint8_t>(x.data, 8));
      bits += model::encode(*frame).length + 3;
    }
  }
  f.bus_load_percent = 100.0 * bits / (static_cast<double>(to - from) / 1e9 * Restbus::kBitrate);
  const auto us = [](int64_t ns) { return static_cast<double>(ns) / 1e3; };
  f.event_late_p50_us = us(b->pacing.events_last.p50_ns);
  f.event_late_p99_us = us(b->pacing.events_last.p99_ns);
  f.wakeup_late_p99_us = us(b->pacing.wakeups_last.p99_ns);
  f.max_lag_ms = static_cast<double>(std::max(a->lag_ns, b->lag_ns)) / 1e6;
  return f;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Rounds of baseline then restbus; per kind the median of the rounds' figures, the frames summed
// and the latenesses of all rounds together.
void BM_RestbusRealtime(benchmark::State& state) {
  const bench::Restbus r = bench::restbus_schedule();
  const bool smoke = bench::smoke_run();
  const int rounds = smoke ? 1 : 3;
  const int64_t warm_ns = smoke ? 200'000'000 : 1'000'000'000;
  const int64_t window_ns = smoke ? 500'000'000 : 3'000'000'000;
  for (auto _ : state) {
    std::vector<Figures> runs[2];  // [0] baseline, [1] restbus
    for (int round = 0; round < rounds; ++round) {
      for (int kind = 0; kind < 2; ++kind) {
        std::string error;
        auto f = run_once(r, kind == 1, warm_ns, window_ns, error);
        if (!f) {
          state.SkipWithError(error.c_str());
          return;
        }
        runs[kind].push_back(std::move(*f));
      }
    }
    double cpu[2] = {};
    for (int kind = 0; kind < 2; ++kind) {
      const std::string name = kind == 1 ? "restbus_" : "baseline_";
      const auto med = [&](double Figures::*field) {
        std::vector<double> v;
        for (const Figures& f : runs[kind]) {
          v.push_back(f.*field);
        }
        return median(v);
      };
      const auto sum = [&](double Figures::*field) {
        double s = 0;
        for (const Figures& f : runs[kind]) {
          s += f.*field;
        }
        return s;
      };
      std::vector<int64_t> delivery;
      std::vector<int64_t> wait;
      for (const Figures& f : runs[kind]) {
        delivery.insert(delivery.end(), f.delivery.begin(), f.delivery.end());
        wait.insert(wait.end(), f.wait.begin(), f.wait.end());
      }
      cpu[kind] = med(&Figures::cpu_percent);
      state.counters[name + "cpu_percent_of_a_core"] = cpu[kind];
      state.counters[name + "wakeups_per_second"] = med(&Figures::wakeups_per_second);
      state.counters[name + "frames_received"] = sum(&Figures::received);
      state.counters[name + "frames_expected"] = sum(&Figures::expected);
      state.counters[name + "frames_lost"] = sum(&Figures::expected) - sum(&Figures::received);
      state.counters[name + "ring_lost"] = sum(&Figures::ring_lost);
      state.counters[name + "bus_load_percent"] = med(&Figures::bus_load_percent);
      state.counters[name + "event_late_p50_us"] = med(&Figures::event_late_p50_us);
      state.counters[name + "event_late_p99_us"] = med(&Figures::event_late_p99_us);
      state.counters[name + "wakeup_late_p99_us"] = med(&Figures::wakeup_late_p99_us);
      state.counters[name + "max_lag_ms"] = med(&Figures::max_lag_ms);
      bench::report(state, (name + "delivery_late").c_str(), delivery);
      bench::report(state, (name + "queued_to_end").c_str(), wait);
    }
    state.counters["restbus_over_baseline_cpu"] = cpu[0] > 0 ? cpu[1] / cpu[0] : 0.0;
    state.counters["rounds"] = rounds;
    state.counters["window_s"] = static_cast<double>(window_ns) / 1e9;
  }
  state.counters["messages"] = static_cast<double>(r.messages.size());
  state.counters["nodes"] = Restbus::kNodes;
  state.counters["schedule_frames_per_second"] = r.frames_per_second();
  state.counters["schedule_bus_load_percent"] = r.baseline_load_percent();
}
BENCHMARK(BM_RestbusRealtime)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
