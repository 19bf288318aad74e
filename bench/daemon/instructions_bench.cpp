// Instructions per frame, counted by valgrind's callgrind on fixed workloads, so that any
// machine agrees on them whatever its speed:
// - the bus engine alone: N buses at 1 Mbit/s, on each a node sending 000#0102030405060708 back
//   to back and a node receiving it (firmware_model only, in this program's own child);
// - canemud: the same N buses in stepped time, on each an ephemeral channel's node that a
//   babble fault makes send that frame back to back and a second channel's node that receives
//   it into its client's ring, which this program drains after every 2 ms step.
// Each is run twice, for two lengths of simulated time; the difference of the instructions
// divided by the difference of the frames leaves out start-up and shut-down. The ratio of the
// two is canemud's cost per bus frame in units of the engine's.
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

// ---- the engine alone (run in a child under callgrind: `instructions_bench --engine BUSES MS`)

int run_engine(int buses, int64_t ms) {
  const model::BitTiming t1m = *model::sja1000::decode_btr(0x00, 0x14);
  const auto frame = *model::Frame::classic(0, std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 8});
  model::SimScheduler sched;
  std::deque<model::CanBus> bus_list;
  std::deque<bench::Saturating> senders;
  std::deque<bench::Receiving> receivers;
  for (int i = 0; i < buses; ++i) {
    model::CanBus& bus = bus_list.emplace_back(sched, "can" + std::to_string(i));
    senders.emplace_back(frame, t1m);
    senders.back().bus = &bus;
    senders.back().id = bus.attach(senders.back());
    receivers.emplace_back(t1m);
    bus.attach(receivers.back());
  }
  for (int64_t at = kStepNs; at <= ms * 1'000'000; at += kStepNs) {
    sched.run_until(model::SimTime::from_ns(at));
  }
  uint64_t frames = 0;
  for (const model::CanBus& bus : bus_list) {
    frames += bus.frames_on_bus();
  }
  std::printf("%llu\n", static_cast<unsigned long long>(frames));
  return 0;
}

struct Count {
  double instructions = 0;
  double frames = 0;
};

std::optional<Count> engine_count(int buses, int64_t ms, std::string& error) {
  const std::string dir = temp_dir();
  const std::string out = dir + "/callgrind.out";
  const std::string command = "valgrind --tool=callgrind --callgrind-out-file=" + out + " /proc/" +
                              std::to_string(::getpid()) + "/exe --engine " +
                              std::to_string(buses) + " " + std::to_string(ms) + " 2>/dev/null";
  FILE* p = ::popen(command.c_str(), "r");
  unsigned long long frames = 0;
  const bool read = p != nullptr && std::fscanf(p, "%llu", &frames) == 1;
  const int status = p != nullptr ? ::pclose(p) : -1;
  const auto total = callgrind_total(out);
  std::remove(out.c_str());
  ::rmdir(dir.c_str());
  if (!read || status != 0 || !total) {
    error = "the engine's run under valgrind failed (is valgrind installed?)";
    return std::nullopt;
  }
  return Count{*total, static_cast<double>(frames)};
}

// ---- canemud

std::optional<Count> daemon_count(int buses, int64_t ms, std::string& error) {
  const std::string dir = temp_dir();
  const std::string config = dir + "/busy.toml";
  const std::string out = dir + "/callgrind.out";
  {
    std::ofstream f(config);
    f << "[simulation]\ntime = \"stepped\"\n";
    for (int i = 0; i < buses; ++i) {
      f << "[[bus]]\nname = \"can" << i << "\"\nbitrate = 1000000\n";
    }
  }
  std::optional<Count> count;
  {
    testing::CanemudProcess daemon(
        "/usr/bin/valgrind",
        {"--tool=callgrind", "--callgrind-out-file=" + out, CANEMUD_PATH, "--config=" + config});
    auto c = client::Connection::open(daemon.socket(), "bench-instructions");
    if (!daemon.ready() || !c) {
      error = "canemud did not start under valgrind: " + daemon.log();
    } else {
      bench::BabblingBuses busy;
      error = busy.open(daemon, *c, buses);
      double received = 0;
      for (int64_t at = 0; error.empty() && at < ms * 1'000'000; at += kStepNs) {
        auto step = ipc::make_message<ipc::TimeStepRequest>();
        step.step_ns = kStepNs;
        if (!c->call<ipc::TimeStepRequest, ipc::TimeStepReply>(step)) {
          error = "a step failed";
        }
        received += static_cast<double>(busy.drain());
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
  std::remove(out.c_str());
  std::remove(config.c_str());
  ::rmdir(dir.c_str());
  return count;
}

// Instructions per frame from runs of `short_ms` and `long_ms` of simulated time.
template <class Run>
std::optional<double> per_frame(Run run, int buses, int64_t short_ms, int64_t long_ms,
                                std::string& error) {
  const auto a = run(buses, short_ms, error);
  const auto b = a ? run(buses, long_ms, error) : std::nullopt;
  if (!a || !b || b->frames <= a->frames) {
    if (error.empty()) {
      error = "no frames between the two runs";
    }
    return std::nullopt;
  }
  return (b->instructions - a->instructions) / (b->frames - a->frames);
}

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

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--engine") == 0) {
    return run_engine(std::atoi(argv[2]), std::atoll(argv[3]));
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
