// A minimal CAN controller for bus-engine tests: a transmit queue and a log of what the bus
// reported, with its instants.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model::testing {

inline BitTiming timing_500k() {
  return *sja1000::decode_btr(0x00, 0x1C);
}
inline BitTiming timing_250k() {
  return *sja1000::decode_btr(0x01, 0x1C);
}

inline Frame frame(uint32_t id, std::vector<uint8_t> data, bool extended = false) {
  auto f = Frame::classic(id, data, extended);
  return *f;
}

inline Frame remote_frame(uint32_t id, uint8_t dlc = 0, bool extended = false) {
  FrameSpec spec;
  spec.id = id;
  spec.extended = extended;
  spec.remote = true;
  spec.dlc = dlc;
  return *Frame::create(spec);
}

inline constexpr int64_t kBit = 2000;  // ns at 500 kbit/s

// A bus on its own scheduler, with a fault plan plugged in (empty unless a test adds rules).
struct BusFixture {
  SimScheduler sched;
  CanBus bus{sched, "can0"};
  FaultPlan plan;
  BusFixture() { bus.set_injector(&plan); }
  void run_until(int64_t ns) { sched.run_until(SimTime::from_ns(ns)); }
};

// A fault rule: `type` errors in the first `count` matching frames (every one if none), at `bit`
// (the type's default bit if none).
inline FaultRule fault_rule(CanErrorType type, std::optional<uint64_t> count = std::nullopt,
                            std::optional<uint16_t> bit = std::nullopt) {
  FaultRule r;
  r.fault.error = type;
  r.fault.bit = bit;
  r.count = count;
  return r;
}
// The same for the frames `node` sends only.
inline FaultRule errors_from(NodeId node, CanErrorType type, uint64_t count,
                             std::optional<uint16_t> bit = std::nullopt) {
  FaultRule r = fault_rule(type, count, bit);
  r.match.transmitter = node;
  return r;
}

// The all-zero standard frame is 50 bits (hand-checked in wire_encoding_test), 0x123 with two
// bytes 62 bits (golden vector).
inline const Frame kZero = *Frame::classic(0x000, {});
inline const Frame k123 = *Frame::classic(0x123, std::vector<uint8_t>{0x11, 0x22});

// What a node was told of frames and errors, each frame with its instant (`Time`: SimTime, or
// ns as int64_t).
template <class Time>
struct FrameLog {
  struct Item {
    Time at;
    Frame frame;
    bool own;
  };
  std::vector<Item> received;
  std::vector<Item> sent;
  std::vector<Time> dropped;
  std::vector<BusErrorEvent> errors;

  // The identifiers of the frames received so far, in order.
  std::vector<uint32_t> received_ids() const {
    std::vector<uint32_t> ids;
    for (const Item& r : received) {
      ids.push_back(r.frame.id());
    }
    return ids;
  }
};

class TestController : public CanController, public FrameLog<SimTime> {
 public:
  explicit TestController(BitTiming nominal = timing_500k()) { timing_.nominal = nominal; }
  // Attached to `bus` at once.
  explicit TestController(CanBus& bus, BitTiming nominal = timing_500k())
      : TestController(nominal) {
    attach_to(bus);
  }

  void attach_to(CanBus& bus) {
    bus_ = &bus;
    id_ = bus.attach(*this);
  }
  NodeId id() const { return id_; }

  void send(const Frame& f, bool single_shot = false, bool self_reception = false) {
    queue_.push_back(TxFrame{f, single_shot, self_reception});
    if (queue_.size() == 1 && bus_ != nullptr) {
      bus_->tx_changed(id_);
    }
  }

  // Withdraws the queued frames, but for one on the wire (CanBus::in_flight), as an abort does.
  void abort() {
    const std::size_t keep = bus_->in_flight(id_) && !queue_.empty() ? 1 : 0;
    while (queue_.size() > keep) {
      queue_.pop_back();
    }
    bus_->tx_changed(id_);
  }
  // Tells the bus to look at the pending frame again, which has not changed.
  void look_again() { bus_->tx_changed(id_); }

  NodeTiming timing() const override { return timing_; }
  bool participating() const override { return running; }
  bool listen_only() const override { return listen; }
  bool self_test() const override { return self_test_mode; }
  bool fd_capable() const override { return fd; }
  BusOffRecovery bus_off_recovery() const override { return recovery; }
  const TxFrame* pending_tx() override { return queue_.empty() ? nullptr : &queue_.front(); }
  FaultConfinement& confinement() override { return fc; }

  void on_frame(SimTime at, const Frame& f, bool own) override { received.push_back({at, f, own}); }
  void on_tx_done(SimTime at) override {
    if (!queue_.empty()) {  // (the bus reports only a frame it took from here)
      sent.push_back({at, queue_.front().frame, false});
      pop();
    }
  }
  void on_tx_dropped(SimTime at) override {
    if (!queue_.empty()) {
      dropped.push_back(at);
      pop();
    }
  }
  void on_arbitration_lost(SimTime at, uint16_t bit, uint16_t) override {
    lost.push_back({at, bit});
  }
  void on_error(const BusErrorEvent& e) override { errors.push_back(e); }
  void on_state_change(SimTime at, ErrorState s) override { states.push_back({at, s}); }

  struct Lost {
    SimTime at;
    uint16_t bit;
  };
  std::vector<Lost> lost;
  std::vector<StateChange> states;

  FaultConfinement fc;
  NodeTiming timing_;
  bool running = true;
  bool listen = false;
  bool self_test_mode = false;
  bool fd = false;
  BusOffRecovery recovery = BusOffRecovery::automatic;

 private:
  void pop() {
    queue_.pop_front();
    if (!queue_.empty()) {
      bus_->tx_changed(id_);
    }
  }
  CanBus* bus_ = nullptr;
  NodeId id_ = 0;
  std::deque<TxFrame> queue_;
};

}  // namespace canemu::model::testing
