// An SJA1000 run by a minimal host driver, the way an operating system's driver runs the chip:
// it programs the bit timing, accepts every frame, feeds the transmit buffer from a queue the
// owner provides, empties the receive FIFO as frames arrive, reports every event through one
// ControllerEvents sink, and optionally restarts the chip after bus-off.
//
// canemud uses it for ephemeral channels (a node a client asks for on a named bus). A node can
// be stopped and started again, so the daemon reuses chips instead of growing the bus.
#pragma once

#include <functional>
#include <optional>

#include "canemu/firmware_model/sja1000.hpp"

namespace canemu::model {

struct Sja1000NodeSettings {
  uint8_t btr0 = 0;
  uint8_t btr1 = 0;
  bool listen_only = false;
  // After bus-off, the driver clears reset mode this long after the bus-off instant (recovery
  // then takes its 128 x 11 recessive bits). Zero: the node stays in bus-off until restart().
  SimDuration restart_delay{};
};

class Sja1000Node final : private ControllerEvents {
 public:
  // The next frame to send, or nothing when the queue is empty.
  using TxSource = std::function<std::optional<TxFrame>()>;

  // Puts a chip on `bus`, in reset mode. `scheduler` is the bus's.
  Sja1000Node(SimScheduler& scheduler, CanBus& bus);
  Sja1000Node(const Sja1000Node&) = delete;
  Sja1000Node& operator=(const Sja1000Node&) = delete;

  // Clears the counters and statistics, programs the chip and takes it out of reset mode.
  // Events go to `sink` (may be nullptr); frames to send come from `source`.
  void start(const Sja1000NodeSettings& settings, ControllerEvents* sink, TxSource source);
  // Reset mode: the node leaves the bus (a frame already on the wire completes without
  // retransmission); the sink and source are forgotten.
  void stop();
  bool running() const { return running_; }
  // True when start() may be called: stopped and no frame of this node on the wire.
  bool reusable() const { return !running_ && !bus_.in_flight(chip_.node()); }

  // The source has frames: loads the next one if the transmit buffer is free.
  void kick() { load_next(); }
  // Leaves bus-off (clears reset mode): recovery starts counting.
  void restart();
  // A frame is in the transmit buffer.
  bool transmitting() const { return tx_loaded_; }

  SimTime now() const { return bus_.now(); }
  Sja1000& chip() { return chip_; }
  NodeId node() const { return chip_.node(); }

 private:
  void frame_received(SimTime at, const Frame& frame, bool own) override;
  void frame_transmitted(SimTime at, const Frame& frame) override;
  void transmission_dropped(SimTime at, const Frame& frame) override;
  void bus_error(const BusErrorEvent& event) override;
  void state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) override;
  void overrun(SimTime at, const Frame& lost) override;
  void arbitration_lost(SimTime at, uint16_t bit) override;

  void load_next();

  SimScheduler& scheduler_;
  CanBus& bus_;
  Sja1000 chip_;
  Sja1000NodeSettings settings_;
  ControllerEvents* sink_ = nullptr;
  TxSource source_;
  bool running_ = false;
  bool tx_loaded_ = false;
  uint64_t generation_ = 0;  // start() count: a restart scheduled before a stop is void
};

}  // namespace canemu::model
