// A simulated CAN node ([[can_node]], docs/restbus.md "Simulated CAN nodes in canemud"): an ECU
// that canemud runs itself on a node of the bus. It keeps every message's signals at their
// current values and queues the message's frame to its controller on the message's schedule:
// cyclic frames at delay + k * cycle after the node starts, on-change frames when a signal's
// bits change. Alive counters count and checksums are computed as each frame goes to the
// controller. It is a real node of the bus: its frames arbitrate, are acknowledged and retried,
// and its controller goes error-passive and bus-off.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/config/can_node_config.hpp"
#include "canemu/firmware_model/bus/controller_events.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::daemon::restbus {

// What one message of the node did.
struct MessageCounters {
  uint64_t queued = 0;    // frames queued to the controller (schedule instants and changes)
  uint64_t replaced = 0;  // of them, frames that replaced one still waiting (one per message)
  uint64_t sent = 0;      // frames the controller sent successfully
  uint64_t skipped = 0;   // schedule instants with nothing sent: bus-off, or not active
  uint64_t dropped = 0;   // frames that waited in the node and were dropped (bus-off, power off,
                          // message_timeout)
  std::optional<model::SimTime> last_queued;  // when the last frame was queued
};

// A wrong checksum on a message's frames (a scenario's checksum_error): while it is set, the
// frames carry their checksum with every bit inverted, the next `frames` of them (nothing: every
// frame until it is lifted). Shared with the scenario that set it, which reads `hits`.
struct ChecksumFault {
  std::optional<uint64_t> frames;  // frames still to carry a wrong checksum
  uint64_t hits = 0;               // frames that went to the controller with one
};

class CanEcu : private model::ControllerEvents {
 public:
  // The node `config` on `node` (a spare node of its bus, claimed from now on until the ECU
  // goes), started now with `timing` (the bus's) if the configuration powers it. An error
  // (bad_argument, nothing started) if a signal's initial value cannot be encoded.
  static Result<std::unique_ptr<CanEcu>> start(const CanNodeConfig& config, model::HostedNode& node,
                                               const model::HostedNodeSettings& timing);
  // What start() would refuse of `config` (its initial values), without starting anything.
  static Result<> check(const CanNodeConfig& config);
  ~CanEcu() override;
  CanEcu(const CanEcu&) = delete;
  CanEcu& operator=(const CanEcu&) = delete;

  const CanNodeConfig& config() const { return config_; }
  const std::string& name() const { return config_.name; }
  // The message named `message`, or nullptr.
  const CanMessageConfig* message_config(std::string_view message) const;
  model::HostedNode& node() { return node_; }
  const model::HostedNode& node() const { return node_; }

  // Sets a signal's physical value: checked against its minimum..maximum if it has them, else
  // against what its bits hold; unknown names and checksum signals are refused with the reason,
  // and nothing changes. An on_change or cyclic_and_on_change message whose bits changed is
  // queued at once; the others carry the value in their next frame.
  // `check_range` false (a scenario's signal_invalid) checks the value against the bits only.
  // Setting a signal ends a ramp of it.
  Result<> set_signal(std::string_view message, std::string_view signal, double physical,
                      bool check_range = true);
  // The signal's current physical value (a counter's: the value of the next frame).
  Result<double> get_signal(std::string_view message, std::string_view signal) const;
  // Switches the node on (a reset controller joins the bus, the schedule starts again from now)
  // or off (it leaves the bus; waiting frames are dropped). Signal values stay.
  void power(bool on);
  bool powered() const { return powered_; }

  // Faults of a scenario on the node's messages (docs/faults.md, "Simulated CAN nodes"). Each
  // refuses an unknown message or signal, or a signal of the wrong kind, and changes nothing;
  // check_* says what it would refuse, and where the message and signal are.
  using Place = std::pair<std::size_t, std::size_t>;  // a message's index, its signal's
  // message_timeout: while `silent`, the message sends nothing: its cyclic instants are skipped,
  // its changes queue nothing and a frame waiting in the node is dropped (one the controller
  // holds already still goes).
  Result<> silence(std::string_view message, bool silent);
  // counter_freeze: while `frozen`, every frame carries the counter's current value.
  Result<Place> check_counter(std::string_view message, std::string_view signal) const;
  Result<> freeze_counter(std::string_view message, std::string_view signal, bool frozen);
  // counter_jump: the next frame's counter `by` further on than it would have been, wrapping at
  // its width; `by` must be below 2^width (a whole turn would change nothing).
  Result<Place> check_jump(std::string_view message, std::string_view signal, uint64_t by) const;
  Result<> jump_counter(std::string_view message, std::string_view signal, uint64_t by);
  // checksum_error: `fault` on the message's checksum from now (nullptr lifts it).
  Result<std::size_t> check_checksum(std::string_view message) const;
  Result<> corrupt_checksum(std::string_view message, std::shared_ptr<ChecksumFault> fault);
  // A signal's raw bits (a counter's: those of the next frame), and setting them: checked
  // against the signal's width only, queued at once for an on-change message as set_signal
  // does (counter_jump, signal_invalid's raw values and their restoring).
  Result<uint64_t> raw_signal(std::string_view message, std::string_view signal) const;
  Result<Place> check_raw(std::string_view message, std::string_view signal, uint64_t raw) const;
  Result<> set_raw_signal(std::string_view message, std::string_view signal, uint64_t raw);
  // What set_signal would refuse.
  Result<> check_value(std::string_view message, std::string_view signal, double physical,
                       bool check_range = true) const;
  // signal_ramp: from now until `until`, each frame carries the value on the straight line from
  // the signal's current value to `to` at the instant its payload is built, rounded to the
  // bits; from `until` on, `to`. `to` is checked as set_signal checks a value; a counter and a
  // message sent only on change are refused (a ramp changes the frames a cycle sends).
  Result<Place> check_ramp(std::string_view message, std::string_view signal, double to) const;
  Result<> ramp_signal(std::string_view message, std::string_view signal, model::SimTime until,
                       double to);

  Result<MessageCounters> counters(std::string_view message) const;
  // Frames of all its messages sent whole.
  uint64_t frames_sent() const;
  // The payload the message's next frame would carry (counters and checksum as they would be).
  Result<std::vector<uint8_t>> payload(std::string_view message) const;

 private:
  // A signal on its way from one value to another (signal_ramp).
  struct Ramp {
    std::size_t signal;
    model::SimTime from;
    model::SimTime until;
    double start;
    double to;
  };
  struct Message {
    const CanMessageConfig* config = nullptr;
    std::vector<uint64_t> raw;                      // each signal's current raw value
    std::vector<std::optional<uint64_t>> inactive;  // each signal's inactive raw value, if any
    bool waiting = false;                           // a frame waits for the controller
    MessageCounters counters;
    std::optional<model::EventId> next;  // the next schedule instant
    uint64_t due = 0;                    // its index k: delay + k * cycle
    // Scenario faults
    bool silent = false;                          // message_timeout
    std::vector<std::size_t> frozen;              // counter_freeze: the counters frozen
    std::shared_ptr<ChecksumFault> bad_checksum;  // checksum_error
    std::vector<Ramp> ramps;                      // signal_ramp
  };

  CanEcu(const CanNodeConfig& config, model::HostedNode& node,
         const model::HostedNodeSettings& timing);
  Result<std::size_t> find(std::string_view message) const;
  Result<std::size_t> find_signal(const Message& m, std::string_view signal) const;
  // The message `message`'s index and the index of its signal `signal`.
  Result<Place> find_both(std::string_view message, std::string_view signal) const;
  // The raw bits of `physical` for signal `k` of message `i`, checked as set_signal checks.
  Result<uint64_t> value_raw(std::size_t i, std::size_t k, double physical, bool check_range) const;
  std::vector<uint8_t> build(const Message& m) const;
  // Stores a signal's new raw value; an on-change message whose bits changed is queued.
  void change(std::size_t i, std::size_t k, uint64_t raw);
  // The ramps' values at `now` into the message's raw values (ended ramps are dropped).
  void apply_ramps(Message& m, model::SimTime now);
  bool active(const Message& m) const;
  void schedule(std::size_t i);
  void due(std::size_t i);
  void queue(Message& m);
  // The message's waiting frame, if any, is dropped (and counted).
  void drop(Message& m);
  std::optional<model::TxFrame> next_tx();
  void stop_schedule();

  void frame_transmitted(model::SimTime at, const model::Frame& frame) override;
  void state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                     uint16_t rec) override;

  CanNodeConfig config_;
  model::HostedNode& node_;
  model::HostedNodeSettings timing_;
  std::vector<Message> messages_;
  bool powered_ = false;
  model::SimTime started_;
};

}  // namespace canemu::daemon::restbus
