// Instructions per frame, counted by valgrind's callgrind on fixed workloads, so that any
// machine agrees on them whatever its speed:
// - the bus engine alone on firmware_model_bench's workload: one 1 Mbit/s bus at full load
//   from 4 nodes that always have a frame to send (issue 41's goal: at most 1,000 a frame);
// - the bus engine alone: N buses at 1 Mbit/s, on each a node sending 000#0102030405060708 back
//   to back and a node receiving it (firmware_model only, in this program's own child);
// - canemud: the same N buses in stepped time, on each an ephemeral channel's node that a
//   babble fault makes send that frame back to back and a second channel's node that receives
//   it into its client's ring, which this program drains after every 2 ms step.
// - canemud on the restbus of bench/support/restbus_config.hpp (40 simulated ECUs, 300 cyclic
//   messages on one 500 kbit/s bus) in stepped time, with the messages' signals and without
//   them (the baseline), a channel receiving every frame, drained after every 100 ms step.
// Each is run twice, for two lengths of simulated time; the difference of the instructions
// divided by the difference of the frames leaves out start-up and shut-down. The ratio of the
// first two is canemud's cost per bus frame in units of the engine's; of the last two, what the
// signals (encoding, counters, checksums) add to a simulated node's frame.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "../../tests/support/canemud_process.hpp"
#include "../support/babbling_buses.hpp"
#include "../support/engine_buses.hpp"
#include "../support/restbus_config.hpp"
#include "../support/saturating.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace {

using namespace canemu;

constexpr int64_t kStepNs = 2'000'000;

// The instruction total of a callgrind output file (its "totals:" or "summary:" line), or
// nothing.
std::optional<double> callgrind_total(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::optional<double> total;
  while (std::getline(in, line)) {
    for (const char* key : {"totals:", "summary:"}) {
      if (line.rfind(key, 0) == 0) {
        total = std::strtod(line.c_str() + std::strlen(key), nullptr);
      }
    }
  }
  return total;
}

std::string temp_dir() {
  char dir[] = "/tmp/canemu-instr-XXXXXX";
  return ::mkdtemp(dir);
}

// Removes a callgrind output file, or with CANEMU_CALLGRIND_KEEP=DIR moves it there (as
// callgrind.N.out, N counting up) for callgrind_annotate.
void done_with(const std::string& out) {
  static int kept = 0;
  if (const char* keep = std::getenv("CANEMU_CALLGRIND_KEEP"); keep != nullptr && *keep != 0) {
    const std::string to = std::string(keep) + "/callgrind." + std::to_string(kept++) + ".out";
    if (std::rename(out.c_str(), to.c_str()) == 0) {
      std::fprintf(stderr, "callgrind output kept: %s\n", to.c_str());
      return;
    }
  }
  std::remove(out.c_str());
}

// ---- the engine alone, run in a child under callgrind: `instructions_bench --engine BUSES MS`
// (bench/support/engine_buses.hpp), or `--engine-nodes NODES MS`: one bus, NODES saturating
// nodes of random frames in steps of 10 ms (firmware_model_bench's BM_Bus4Nodes1MbitFullLoad).

int run_engine(int buses, int64_t ms) {
  bench::EngineBuses engine(buses);
  engine.run(ms * 1'000'000, kStepNs);
  std::printf("%llu\n", static_cast<unsigned long long>(engine.frames()));
  return 0;
}

int run_engine_nodes(int count, int64_t ms) {
  const model::BitTiming t1m = *model::sja1000::decode_btr(0x00, 0x14);
  model::SimScheduler sched;
  model::CanBus bus(sched, "bench");
  std::deque<bench::Saturating> nodes;
  for (int i = 0; i < count; ++i) {
    nodes.emplace_back(static_cast<uint32_t>(i + 1), t1m);
    nodes.back().bus = &bus;
    nodes.back().id = bus.attach(nodes.back());
  }
  for (int64_t at = 10'000'000; at <= ms * 1'000'000; at += 10'000'000) {
    sched.run_until(model::SimTime::from_ns(at));
  }
  std::printf("%llu\n", static_cast<unsigned long long>(bus.frames_on_bus()));
  return 0;
}

struct Count {
  double instructions = 0;
  double frames = 0;
};

// `mode` is "--engine" (`n` buses) or "--engine-nodes" (`n` nodes on one bus).
std::optional<Count> engine_child_count(const char* mode, int n, int64_t ms, std::string& error) {
  const std::string dir = temp_dir();
  const std::string out = dir + "/callgrind.out";
  const std::string command = "valgrind --tool=callgrind --callgrind-out-file=" + out + " /proc/" +
                              std::to_string(::getpid()) + "/exe " + mode + " " +
                              std::to_string(n) + " " + std::to_string(ms) + " 2>/dev/null";
  FILE* p = ::popen(command.c_str(), "r");
  unsigned long long frames = 0;
  const bool read = p != nullptr && std::fscanf(p, "%llu", &frames) == 1;
  const int status = p != nullptr ? ::pclose(p) : -1;
  const auto total = callgrind_total(out);
  done_with(out);
  ::rmdir(dir.c_str());
  if (!read || status != 0 || !total) {
    error = "the engine's run under valgrind failed (is valgrind installed?)";
    return std::nullopt;
  }
  return Count{*total, static_cast<double>(frames)};
}

std::optional<Count> engine_count(int buses, int64_t ms, std::string& error) {
  return engine_child_count("--engine", buses, ms, error);
}

std::optional<Count> engine_nodes_count(int nodes, int64_t ms, std::string& error) {
  return engine_child_count("--engine-nodes", nodes, ms, error);
}

// ---- canemud

// canemud under callgrind on the configuration `config_text` in stepped time: once canemud
// runs, `open(daemon, connection, error)` returns the receivers of the run (and what failed in
// `error`), which live until canemud has ended; then steps of `step_ns` for `ms` of simulated
// time, each followed by the receivers' `drain()`: the frames received since its last call.
template <class Open>
std::optional<Count> canemud_count(const std::string& config_text, int64_t step_ns, int64_t ms,
                                   Open open, std::string& error) {
  const std::string dir = temp_dir();
  const std::string config = dir + "/bench.toml";
  const std::string out = dir + "/callgrind.out";
  std::ofstream(config) << config_text;
  std::optional<Count> count;
  {
    testing::CanemudProcess daemon(
        "/usr/bin/valgrind",
        {"--tool=callgrind", "--callgrind-out-file=" + out, CANEMUD_PATH, "--config=" + config});
    auto c = client::Connection::open(daemon.socket(), "bench-instructions");
    if (!daemon.ready() || !c) {
      error = "canemud did not start under valgrind: " + daemon.log();
    } else {
      auto receivers = open(daemon, *c, error);
      double received = 0;
      for (int64_t at = 0; error.empty() && at < ms * 1'000'000; at += step_ns) {
        auto step = ipc::make_message<ipc::TimeStepRequest>();
        step.step_ns = step_ns;
        if (!c->call<ipc::TimeStepRequest, ipc::TimeStepReply>(step)) {
          error = "a step failed";
        }
        received += static_cast<double>(receivers.drain());
      }
      if (daemon.terminate(60'000) != 0) {
        error = error.empty() ? "canemud did not end within a minute under valgrind" : error;
      }
      const auto total = callgrind_total(out);
      if (error.empty() && total) {
        count = Count{*total, received};
      } else if (error.empty()) {
        error = "callgrind wrote no total";
      }
    }
  }
  done_with(out);
  std::remove(config.c_str());
  ::rmdir(dir.c_str());
  return count;
}

std::optional<Count> daemon_count(int buses, int64_t ms, std::string& error) {
  std::ostringstream config;
  config << "[simulation]\ntime = \"stepped\"\n";
  for (int i = 0; i < buses; ++i) {
    config << "[[bus]]\nname = \"can" << i << "\"\nbitrate = 1000000\n";
  }
  const auto open = [&](const testing::CanemudProcess& daemon, client::Connection& c,
                        std::string& e) {
    bench::BabblingBuses busy;
    e = busy.open(daemon, c, buses);
    return busy;
  };
  return canemud_count(config.str(), kStepNs, ms, open, error);
}

// A channel on can0 receiving every frame.
struct ChannelReceiver {
  std::optional<client::Channel> channel;
  uint64_t drain() {
    uint64_t n = 0;
    ipc::ChannelMessage m;
    while (channel && channel->rx().get(&m) == ipc::RingStatus::ok) {
      n += m.kind == static_cast<uint8_t>(ipc::ChannelMessageKind::frame) ? 1 : 0;
    }
    return n;
  }
};

// The restbus (bench/support/restbus_config.hpp) with its signals (`signals` 1) or without (0);
// steps of 100 ms (some 200 frames each).
std::optional<Count> restbus_count(int signals, int64_t ms, std::string& error) {
  const auto open = [](const testing::CanemudProcess&, client::Connection& c, std::string& e) {
    ChannelReceiver r;
    client::ChannelOptions o;
    o.bus = "can0";
    o.rx_capacity = 4096;
    auto ch = client::Channel::open(c, o);
    if (ch) {
      r.channel.emplace(std::move(*ch));
    } else {
      e = ch.error().message;
    }
    return r;
  };
  return canemud_count(bench::restbus_config(bench::restbus_schedule(), "stepped", signals != 0),
                       100'000'000, ms, open, error);
}

// Instructions per frame from runs of `short_ms` and `long_ms` of simulated time.
template <class Run>
std::optional<double> per_frame(Run run, int arg, int64_t short_ms, int64_t long_ms,
                                std::string& error) {
  const auto a = run(arg, short_ms, error);
  const auto b = a ? run(arg, long_ms, error) : std::nullopt;
  if (!a || !b || b->frames <= a->frames) {
    if (error.empty()) {
      error = "no frames between the two runs";
    }
    return std::nullopt;
  }
  return (b->instructions - a->instructions) / (b->frames - a->frames);
}

// Issue 41's first figure: the engine alone, 4 nodes at full load, from runs of 2.1 and 2.3 s:
// in steady state, once the bus load's record of its last two seconds has stopped growing (its
// growth, about 40 instructions a frame in the first two seconds, is start-up).
void BM_EngineInstructionsPerFrame(benchmark::State& state) {
  for (auto _ : state) {
    std::string error;
    const auto engine =
        per_frame(engine_nodes_count, static_cast<int>(state.range(0)), 2100, 2300, error);
    if (!engine) {
      state.SkipWithError(error.c_str());
      return;
    }
    state.counters["instructions_per_frame"] = *engine;
    std::printf("engine, %d nodes at full load: %.0f instructions per frame (goal <= 1000)\n",
                static_cast<int>(state.range(0)), *engine);
  }
}
BENCHMARK(BM_EngineInstructionsPerFrame)
    ->ArgName("nodes")
    ->Arg(4)
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

void BM_InstructionsPerFrame(benchmark::State& state) {
  const auto buses = static_cast<int>(state.range(0));
  for (auto _ : state) {
    std::string error;
    const auto engine = per_frame(engine_count, buses, 20, 60, error);
    const auto daemon = engine ? per_frame(daemon_count, buses, 20, 60, error) : std::nullopt;
    if (!engine || !daemon) {
      state.SkipWithError(error.c_str());
      return;
    }
    state.counters["engine_instructions_per_frame"] = *engine;
    state.counters["canemud_instructions_per_frame"] = *daemon;
    state.counters["canemud_over_engine"] = *daemon / *engine;
  }
}
BENCHMARK(BM_InstructionsPerFrame)
    ->ArgName("buses")
    ->Arg(1)
    ->Arg(16)
    ->Arg(64)
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

// canemud in stepped time on the restbus of 40 simulated ECUs and 300 cyclic messages at 500
// kbit/s, with their signals and without (the baseline), from runs of 1 and 2 s of simulated
// time (the schedule repeats every second, so the difference is one whole period).
void BM_RestbusInstructionsPerFrame(benchmark::State& state) {
  for (auto _ : state) {
    std::string error;
    const auto baseline = per_frame(restbus_count, 0, 1000, 2000, error);
    const auto restbus = baseline ? per_frame(restbus_count, 1, 1000, 2000, error) : std::nullopt;
    if (!baseline || !restbus) {
      state.SkipWithError(error.c_str());
      return;
    }
    state.counters["baseline_instructions_per_frame"] = *baseline;
    state.counters["restbus_instructions_per_frame"] = *restbus;
    state.counters["restbus_over_baseline"] = *restbus / *baseline;
  }
}
BENCHMARK(BM_RestbusInstructionsPerFrame)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--engine") == 0) {
    return run_engine(std::atoi(argv[2]), std::atoll(argv[3]));
  }
  if (argc == 4 && std::strcmp(argv[1], "--engine-nodes") == 0) {
    return run_engine_nodes(std::atoi(argv[2]), std::atoll(argv[3]));
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
