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
  std::optional<model::SimTime> last_queued;  // when the last frame was queued
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
  model::HostedNode& node() { return node_; }
  const model::HostedNode& node() const { return node_; }

  // Sets a signal's physical value: checked against its minimum..maximum if it has them, else
  // against what its bits hold; unknown names and checksum signals are refused with the reason,
  // and nothing changes. An on_change or cyclic_and_on_change message whose bits changed is
  // queued at once; the others carry the value in their next frame.
  Result<> set_signal(std::string_view message, std::string_view signal, double physical);
  // The signal's current physical value (a counter's: the value of the next frame).
  Result<double> get_signal(std::string_view message, std::string_view signal) const;
  // Switches the node on (a reset controller joins the bus, the schedule starts again from now)
  // or off (it leaves the bus; waiting frames are dropped). Signal values stay.
  void power(bool on);
  bool powered() const { return powered_; }

  Result<MessageCounters> counters(std::string_view message) const;
  // Frames of all its messages sent whole.
  uint64_t frames_sent() const;
  // The payload the message's next frame would carry (counters and checksum as they would be).
  Result<std::vector<uint8_t>> payload(std::string_view message) const;

 private:
  struct Message {
    const CanMessageConfig* config = nullptr;
    std::vector<uint64_t> raw;  // each signal's current raw value
    bool waiting = false;       // a frame waits for the controller
    MessageCounters counters;
    std::optional<model::EventId> next;  // the next schedule instant
    uint64_t due = 0;                    // its index k: delay + k * cycle
  };

  CanEcu(const CanNodeConfig& config, model::HostedNode& node,
         const model::HostedNodeSettings& timing);
  Result<std::size_t> find(std::string_view message) const;
  Result<std::size_t> find_signal(const Message& m, std::string_view signal) const;
  std::vector<uint8_t> build(const Message& m) const;
  bool active(const Message& m) const;
  void schedule(std::size_t i);
  void due(std::size_t i);
  void queue(Message& m);
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
