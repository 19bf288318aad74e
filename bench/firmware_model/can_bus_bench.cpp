// Simulated bus throughput: 4 nodes keep a 1 Mbit/s bus at 100 % load with 8-byte frames, and
// the benchmark reports simulated frames per second of wall time on one core, and how many
// times faster than real time that is. Target: at least 200 x real time.
#include <benchmark/benchmark.h>

#include <deque>

#include "../support/saturating.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace {

using namespace canemu::model;
using canemu::bench::Saturating;

void BM_Bus4Nodes1MbitFullLoad(benchmark::State& state) {
  const BitTiming t1m = *sja1000::decode_btr(0x00, 0x14);
  SimScheduler sched;
  CanBus bus(sched, "bench");
  std::deque<Saturating> nodes;
  for (uint32_t i = 0; i < 4; ++i) {
    nodes.emplace_back(i + 1, t1m);
    nodes.back().bus = &bus;
    nodes.back().id = bus.attach(nodes.back());
  }
  SimTime t;
  const SimDuration step = milliseconds(10);
  for (auto _ : state) {
    t += step;
    sched.run_until(t);
  }
  const double frames = static_cast<double>(bus.frames_on_bus());
  state.counters["simulated_frames_per_second"] =
      benchmark::Counter(frames, benchmark::Counter::kIsRate);
  state.counters["times_real_time"] =
      benchmark::Counter(static_cast<double>(t.ns()) / 1e9, benchmark::Counter::kIsRate);
  state.counters["bus_load_percent"] = bus.bus_load_percent(t);
}

BENCHMARK(BM_Bus4Nodes1MbitFullLoad)->Unit(benchmark::kMillisecond);

}  // namespace
