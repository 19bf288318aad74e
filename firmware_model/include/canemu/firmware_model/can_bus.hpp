// The CAN bus engine: arbitration, acknowledgement, error signalling and fault confinement
// between the controllers attached to one bus, in simulated time.
//
// What is exact and what is approximated is in docs/bus-engine.md. In short: a frame without
// errors is resolved at its start of frame from the bit sequences of all transmitters
// (arbitration bit by bit, wired-AND), and completes at the end of its EOF; nobody pays per
// bit. When any node detects an error, the bits from the first detection to the end of the
// error delimiter are simulated one by one for every node (error flags, superposition,
// delimiters, the counter rules that depend on what each node sees).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "canemu/firmware_model/can_controller.hpp"
#include "canemu/firmware_model/sim_scheduler.hpp"

namespace canemu::model {

// What an injection does to one frame.
struct FrameFault {
  std::optional<CanErrorType> error;  // corrupt the frame: who detects what, see docs
  std::optional<uint16_t> bit;        // where (frame bit index); a default per type otherwise
  bool suppress_ack = false;          // no node acknowledges this frame
};

struct FrameContext {
  SimTime sof;
  NodeId transmitter;
  const Frame& frame;
  const EncodedFrame& bits;
};

// Consulted by the bus at its injection points. The default does nothing.
class FaultInjector {
 public:
  virtual ~FaultInjector() = default;
  // At every start of frame that wins arbitration.
  virtual FrameFault on_frame(const FrameContext&) { return {}; }
};

struct ErrorCounts {
  uint64_t bit = 0, stuff = 0, form = 0, crc = 0, ack = 0;
  uint64_t& operator[](CanErrorType t);
  uint64_t total() const { return bit + stuff + form + crc + ack; }
};

struct StateChange {
  SimTime at;
  ErrorState state;
};

struct NodeStats {
  uint64_t frames_sent = 0;
  uint64_t frames_received = 0;
  uint64_t arbitration_lost = 0;
  uint64_t tx_dropped = 0;
  ErrorCounts errors_as_transmitter;
  ErrorCounts errors_as_receiver;
  std::vector<StateChange> state_changes;
};

// One line of what happened on the wire, for traces and tests.
struct BusEvent {
  enum class Kind : uint8_t { frame, error_frame, bus_held };
  Kind kind = Kind::frame;
  SimTime start;  // SOF (or start of the dominant hold)
  SimTime end;    // end of EOF, or end of the error delimiter
  NodeId transmitter = 0;
  std::optional<Frame> frame;
  uint16_t error_bit = 0;  // first detection
};

class CanBus {
 public:
  CanBus(SimScheduler& scheduler, std::string name);
  CanBus(const CanBus&) = delete;
  CanBus& operator=(const CanBus&) = delete;

  const std::string& name() const { return name_; }

  NodeId attach(CanController& controller);
  std::size_t node_count() const { return nodes_.size(); }

  // The controller has a new or changed pending_tx() (or wants to try again).
  void tx_changed(NodeId node);
  // A controller with BusOffRecovery::on_restart was restarted: recovery counting begins.
  void restart(NodeId node);

  // --- fault injection (programmatic API) ---
  void set_injector(FaultInjector* injector) { injector_ = injector; }
  // Transceiver unplugged (false) or back (true).
  void set_connected(NodeId node, bool connected);
  bool connected(NodeId node) const { return nodes_[node].connected; }
  void set_oscillator_ppm(NodeId node, int32_t ppm) { nodes_[node].oscillator_ppm = ppm; }
  // No node acknowledges anything from now until `until`.
  void suppress_acks_until(SimTime until) { ack_suppressed_until_ = until; }
  // The bus is held dominant from `from` for `duration` (a shorted or stuck transceiver).
  void hold_dominant(SimTime from, SimDuration duration);

  // --- observation ---
  const NodeStats& stats(NodeId node) const { return nodes_[node].stats; }
  // Busy time (start of frame to end of intermission) over the second before `now`, percent.
  double bus_load_percent(SimTime now) const;
  uint64_t frames_on_bus() const { return frames_on_bus_; }
  uint64_t error_frames_on_bus() const { return error_frames_on_bus_; }
  // Called for every frame and error frame, in order.
  std::function<void(const BusEvent&)> on_bus_event;

 private:
  struct Node {
    CanController* controller = nullptr;
    bool connected = true;
    int32_t oscillator_ppm = 0;
    SimTime ready_at;  // suspend transmission of error-passive transmitters
    bool encoded_valid = false;
    EncodedFrame encoded;
    ErrorState last_state = ErrorState::active;
    // Bus-off recovery bookkeeping.
    SimTime recovery_from;  // recessive bits count from here
    EventId recovery_event = 0;
    NodeStats stats;
  };

  struct Participant;  // a node's view during one frame (can_bus.cpp)

  NodeTiming timing_of(const Node& n) const;
  bool can_transmit(const Node& n) const;
  bool on_bus(const Node& n) const;
  const EncodedFrame& encoded_tx(NodeId id);

  void schedule_attempt(SimTime at);
  void attempt(SimTime now);
  void run_frame(SimTime sof, std::vector<NodeId> contenders);
  void finish_success(SimTime sof, NodeId tx, const std::vector<NodeId>& winners,
                      const std::vector<Participant>& parts, const BitTiming& nominal,
                      const BitTiming& data);
  void run_error_phase(SimTime sof, std::vector<Participant>& parts, const EncodedFrame* bits,
                       const BitTiming& nominal, const BitTiming& data, uint16_t first_bit);
  void run_hold(SimTime now);

  void bus_released(SimTime last_dominant_end, SimTime idle_at);
  void account_recessive(SimTime dominant_start);
  void arm_recovery(NodeId id);
  void recovery_check(NodeId id, SimTime now);
  void report_state(NodeId id, SimTime at);
  void record_busy(SimTime start, SimTime end);

  SimScheduler& scheduler_;
  std::string name_;
  std::vector<Node> nodes_;
  FaultInjector* injector_ = nullptr;
  SimTime ack_suppressed_until_;

  // Bus activity.
  bool busy_ = false;
  SimTime free_at_;            // end of intermission of the last activity
  SimTime last_dominant_end_;  // recessive run on the wire started here
  EventId attempt_event_ = 0;
  bool attempt_pending_ = false;
  std::vector<std::pair<SimTime, SimDuration>> holds_;  // pending dominant holds

  std::deque<std::pair<SimTime, SimTime>> busy_intervals_;
  uint64_t frames_on_bus_ = 0;
  uint64_t error_frames_on_bus_ = 0;
};

}  // namespace canemu::model
