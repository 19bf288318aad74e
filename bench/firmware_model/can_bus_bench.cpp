// Simulated bus throughput: 4 nodes keep a 1 Mbit/s bus at 100 % load with 8-byte frames, and
// the benchmark reports simulated frames per second of wall time on one core, and how many
// times faster than real time that is. Target: at least 200 x real time.
#include <benchmark/benchmark.h>

#include <deque>
#include <random>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace {

using namespace canemu::model;

// Always has a frame to send: the next of a fixed random set.
class Saturating final : public CanController {
 public:
  static constexpr std::size_t kFrames = 64;  // a power of two
  Saturating(uint32_t seed, BitTiming t) {
    timing_.nominal = t;
    std::mt19937 rng(seed);
    for (std::size_t i = 0; i < kFrames; ++i) {
      std::vector<uint8_t> data(8);
      for (auto& b : data) {
        b = static_cast<uint8_t>(rng());
      }
      frames_.push_back(TxFrame{*Frame::classic(rng() & 0x7FF, data), false, false});
    }
  }
  NodeId id = 0;
  CanBus* bus = nullptr;
  uint64_t received = 0;

  NodeTiming timing() const override { return timing_; }
  bool participating() const override { return true; }
  BusOffRecovery bus_off_recovery() const override { return BusOffRecovery::automatic; }
  const TxFrame* pending_tx() override { return &frames_[next_ & (kFrames - 1)]; }
  FaultConfinement& confinement() override { return fc_; }
  void on_frame(SimTime, const Frame&, bool) override { ++received; }
  void on_tx_done(SimTime) override {
    ++next_;
    bus->tx_changed(id);
  }
  void on_tx_dropped(SimTime) override {}
  void on_arbitration_lost(SimTime, uint16_t, uint16_t) override {}
  void on_error(const BusErrorEvent&) override {}
  void on_state_change(SimTime, ErrorState) override {}

 private:
  NodeTiming timing_;
  FaultConfinement fc_;
  std::vector<TxFrame> frames_;
  std::size_t next_ = 0;
};

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
