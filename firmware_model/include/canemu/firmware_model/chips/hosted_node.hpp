// A controller run by a minimal host driver, the way an operating system's driver runs a CAN
// chip: it programs the bit timing, accepts every frame, feeds the transmit buffer from a queue
// the owner provides (one frame at a time, so the owner's queue fills when the bus is busy),
// takes received frames out at once, reports every event through one ControllerEvents sink, and
// optionally restarts the controller after bus-off.
//
// canemud runs ephemeral channels on these: an SJA1000 on classic CAN buses (Sja1000Node), the
// CAN FD controller on CAN FD buses (CanFdNode). A node can be stopped and started again, so
// the daemon reuses nodes instead of growing the bus.
#pragma once

#include <functional>
#include <optional>
#include <utility>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/controller_events.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::model {

struct HostedNodeSettings {
  uint8_t btr0 = 0;  // Sja1000Node: the bit timing registers
  uint8_t btr1 = 0;
  BitTiming nominal;  // CanFdNode: the arbitration-phase timing
  BitTiming data;     // CanFdNode: the data-phase timing of frames with BRS
  bool listen_only = false;
  bool fd = true;  // CanFdNode: decodes and sends CAN FD frames (false: a classic controller)
  // After bus-off, the driver restarts the controller this long after the bus-off instant
  // (recovery then takes its 128 x 11 recessive bits). Zero: the node stays in bus-off until
  // restart().
  SimDuration restart_delay{};
};

class HostedNode : private ControllerEvents {
 public:
  // The next frame to send, or nothing when the queue is empty.
  using TxSource = std::function<std::optional<TxFrame>()>;

  ~HostedNode() override = default;
  HostedNode(const HostedNode&) = delete;
  HostedNode& operator=(const HostedNode&) = delete;

  // Clears the counters and statistics, programs the controller and puts it on the bus.
  // Events go to `sink` (may be nullptr); frames to send come from `source`.
  void start(const HostedNodeSettings& settings, ControllerEvents* sink, TxSource source) {
    configure(settings, sink, std::move(source));
    go_online();
  }
  // Off the bus (a frame already on the wire completes without retransmission); the sink and
  // source are forgotten.
  void stop();

  // The steps of start() and stop() apart, for a firmware that keeps its controller
  // configured while it is off the bus (VCI InitLine, StartLine, StopLine):
  // configure() is a hardware reset and programming (counters and statistics cleared), off the
  // bus; go_online() joins the bus (from bus-off, recovery starts counting); go_offline()
  // leaves it (a frame on the wire completes, a frame loaded but not started is dropped) and
  // keeps the sink, the source and the settings.
  void configure(const HostedNodeSettings& settings, ControllerEvents* sink, TxSource source);
  void go_online();
  void go_offline();
  bool running() const { return running_; }
  // True when start() may be called: stopped, nobody's (see claim()), and no frame of this node
  // on the wire.
  bool reusable() const { return !running_ && !claimed_ && !bus_.in_flight(node()); }
  // A firmware that keeps the node while it is stopped (a VCI line) holds it claimed, so that
  // the daemon does not hand it to another device.
  void claim(bool claimed) { claimed_ = claimed; }

  // The source has frames: loads the next one if the transmit buffer is free.
  void kick() { load_next(); }
  // Leaves bus-off: recovery starts counting.
  void restart();
  // A frame is in the transmit buffer.
  bool transmitting() const { return tx_loaded_ > 0; }

  // Fault injection, a babbling idiot: from now until `until` the node sends `frame` back to
  // back, each copy as soon as arbitration lets it (errors and retransmissions as for any
  // frame, on this node's counters). A frame of its own already in the transmit buffer goes
  // first; the rest of its traffic waits until the babbling ends. At `until` a copy not yet on
  // the wire is withdrawn (one on the wire completes). The sink hears nothing of the copies
  // (nobody above asked for them) apart from bus errors and state changes, which are its
  // controller's. False (and nothing happens) when the node is not on the bus.
  bool babble(const Frame& frame, SimTime until);
  bool babbling() const { return babble_.has_value(); }
  SimTime now() const { return bus_.now(); }
  SimScheduler& scheduler() { return scheduler_; }
  // This node's frame is on the wire (start of frame to the end of its frame or error frame).
  bool frame_on_wire() const { return bus_.in_flight(node()); }
  CanBus& bus() { return bus_; }

  virtual NodeId node() const = 0;
  virtual CanController& controller() = 0;
  virtual bool fd_capable() const = 0;

 protected:
  HostedNode(SimScheduler& scheduler, CanBus& bus) : scheduler_(scheduler), bus_(bus) {}
  // What the derived class hands its controller as listener.
  ControllerEvents* events() { return this; }

  // --- what differs per chip ---
  // Everything the last user left dropped, counters cleared, timing and acceptance programmed,
  // still off the bus.
  virtual void program(const HostedNodeSettings& settings) = 0;
  virtual void go_on_bus(const HostedNodeSettings& settings) = 0;
  virtual void go_off_bus() = 0;
  virtual void leave_bus_off(const HostedNodeSettings& settings) = 0;
  virtual bool buffer_free() = 0;
  virtual void load(const TxFrame& tx) = 0;
  // Withdraws the loaded frame: gone if it has not started, else it completes without being
  // repeated.
  virtual void abort_tx() = 0;
  virtual void release_received() = 0;
  // How many frames the driver hands over before the first is done: 1 for a chip's transmit
  // buffer; more for a node whose controller is elsewhere (a bus of another daemon), so that
  // the link's delay does not come between frames. buffer_free() is asked before each.
  virtual uint32_t tx_window() const { return 1; }
  // stop() ended the node's use: nobody drives it until it is configured again.
  virtual void released() {}
  // The controller leaves bus-off by itself after settings.restart_delay (the controller of a
  // node of another daemon's bus is restarted there): no restart is scheduled here.
  virtual bool restarts_itself() const { return false; }
  // Reads what the chip captured of an arbitration loss, as a driver that reports every loss
  // does: the chip captures the next one only then (SJA1000: ALC).
  virtual void read_arbitration_capture() {}

 private:
  void frame_received(SimTime at, const Frame& frame, bool own) override;
  void frame_transmitted(SimTime at, const Frame& frame) override;
  void transmission_dropped(SimTime at, const Frame& frame) override;
  void bus_error(const BusErrorEvent& event) override;
  void state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) override;
  void overrun(SimTime at, const Frame& lost) override;
  void arbitration_lost(SimTime at, uint16_t bit) override;

  void load_next();
  void end_babble();

  SimScheduler& scheduler_;
  CanBus& bus_;
  HostedNodeSettings settings_;
  ControllerEvents* sink_ = nullptr;
  TxSource source_;
  bool running_ = false;
  bool claimed_ = false;
  uint32_t tx_loaded_ = 0;         // frames handed to load() and not yet done or dropped
  std::optional<TxFrame> babble_;  // while babbling: the request it loads again and again
  SimTime babble_until_;
  bool babble_loaded_ = false;  // the loaded frame is a babbled copy
  uint64_t generation_ = 0;     // start() count: a restart scheduled before a stop is void
};

}  // namespace canemu::model
