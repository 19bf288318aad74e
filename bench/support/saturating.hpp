// A controller for benchmarks that always has a frame to send (the next of a fixed set) and one
// that only receives: what keeps a bus engine at full load without a chip model's own cost.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"

namespace canemu::bench {

namespace model = canemu::model;

// What both controllers below share: a fixed bit timing, always taking part, automatic recovery
// from bus-off, and nothing to do on the bus's other events.
class BenchController : public model::CanController {
 public:
  explicit BenchController(model::BitTiming t) { timing_.nominal = t; }
  model::NodeTiming timing() const override { return timing_; }
  bool participating() const override { return true; }
  model::BusOffRecovery bus_off_recovery() const override {
    return model::BusOffRecovery::automatic;
  }
  model::FaultConfinement& confinement() override { return fc_; }
  void on_tx_done(model::SimTime) override {}
  void on_tx_dropped(model::SimTime) override {}
  void on_arbitration_lost(model::SimTime, uint16_t, uint16_t) override {}
  void on_error(const model::BusErrorEvent&) override {}
  void on_state_change(model::SimTime, model::ErrorState) override {}

 private:
  model::NodeTiming timing_;
  model::FaultConfinement fc_;
};

// Always has a frame to send: the next of a fixed set.
class Saturating final : public BenchController {
 public:
  static constexpr std::size_t kFrames = 64;  // a power of two
  // kFrames frames of random 11-bit identifiers and data from `seed`.
  Saturating(uint32_t seed, model::BitTiming t) : BenchController(t) {
    std::mt19937 rng(seed);
    for (std::size_t i = 0; i < kFrames; ++i) {
      std::vector<uint8_t> data(8);
      for (auto& b : data) {
        b = static_cast<uint8_t>(rng());
      }
      frames_.push_back(model::TxFrame{*model::Frame::classic(rng() & 0x7FF, data), false, false});
    }
  }
  // `frame` again and again.
  Saturating(const model::Frame& frame, model::BitTiming t)
      : BenchController(t), frames_(kFrames, model::TxFrame{frame, false, false}) {}
  model::NodeId id = 0;
  model::CanBus* bus = nullptr;
  uint64_t received = 0;

  const model::TxFrame* pending_tx() override { return &frames_[next_ & (kFrames - 1)]; }
  void on_frame(model::SimTime, const model::Frame&, bool) override { ++received; }
  void on_tx_done(model::SimTime) override {
    ++next_;
    bus->tx_changed(id);
  }

 private:
  std::vector<model::TxFrame> frames_;
  std::size_t next_ = 0;
};

// Takes part in every frame (acknowledges it) and counts what it receives.
class Receiving final : public BenchController {
 public:
  using BenchController::BenchController;
  uint64_t received = 0;
  const model::TxFrame* pending_tx() override { return nullptr; }
  void on_frame(model::SimTime, const model::Frame&, bool) override { ++received; }
};

}  // namespace canemu::bench
