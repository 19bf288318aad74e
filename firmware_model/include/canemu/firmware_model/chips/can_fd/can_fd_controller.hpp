// A CAN FD controller (ISO CAN FD, ISO 11898-1:2015) for the VCI "2" interfaces: nominal and
// data-phase timing, FDF/BRS/ESI frames up to 64 bytes, a transmit queue sent in order, a receive
// queue with real overrun, listen-only and self-test modes.
//
// The vendor documentation of this controller's registers is not available, so it is modelled
// at the level its users observe: the adapter firmware calls configure/start/stop/submit and
// reads the receive queue. Decision (docs/bus-engine.md): it recovers from bus-off by itself
// (BusOffRecovery::automatic by default; configurable), unlike the SJA1000.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/controller_events.hpp"

namespace canemu::model {

struct CanFdConfig {
  BitTiming nominal;
  BitTiming data;          // used for frames with BRS
  bool fd_enabled = true;  // false: behaves as a classic controller (form errors on FD frames)
  bool listen_only = false;
  bool self_test = false;        // transmissions need no ACK
  std::size_t rx_capacity = 64;  // frames
  std::size_t tx_capacity = 16;  // frames
  BusOffRecovery recovery = BusOffRecovery::automatic;
};

struct ReceivedFrame {
  SimTime at;
  Frame frame;
  bool own = false;
};

class CanFdController final : public CanController {
 public:
  explicit CanFdController(CanFdConfig config = {});

  void connect(CanBus& bus);
  NodeId node() const { return node_; }

  // Changes take effect at once; the bus re-reads timing and modes.
  void configure(const CanFdConfig& config);
  const CanFdConfig& config() const { return config_; }
  void start();
  void stop();  // leaves the bus; queued transmissions stay queued
  bool running() const { return running_; }
  // From bus-off with BusOffRecovery::on_restart: starts the recovery count.
  void restart();

  // Queues a frame for transmission; false if the queue is full or the frame is an FD frame and
  // FD is disabled.
  bool submit(const TxFrame& tx);
  // Drops queued frames that have not started (one on the wire completes). Returns how many.
  std::size_t abort_pending();
  std::size_t tx_queued() const { return tx_.size(); }

  std::optional<ReceivedFrame> receive();
  std::size_t rx_queued() const { return rx_.size(); }
  uint64_t rx_overruns() const { return overruns_; }
  bool overrun_flag() const { return overrun_flag_; }
  void clear_overrun() { overrun_flag_ = false; }
  ErrorState state() const { return fc_.state(); }

  void set_listener(ControllerEvents* listener) { listener_ = listener; }

  // --- CanController ---
  NodeTiming timing() const override;
  bool participating() const override { return running_; }
  bool listen_only() const override { return config_.listen_only; }
  bool self_test() const override { return config_.self_test; }
  bool fd_capable() const override { return config_.fd_enabled; }
  BusOffRecovery bus_off_recovery() const override { return config_.recovery; }
  const TxFrame* pending_tx() override;
  FaultConfinement& confinement() override { return fc_; }
  void on_frame(SimTime at, const Frame& frame, bool own) override;
  void on_tx_done(SimTime at) override;
  void on_tx_dropped(SimTime at) override;
  void on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed_bit) override;
  void on_error(const BusErrorEvent& event) override;
  void on_state_change(SimTime at, ErrorState state) override;

 private:
  void changed();
  Frame take_tx();  // the frame at the head of the queue, removed, and the next one offered

  CanFdConfig config_;
  CanBus* bus_ = nullptr;
  NodeId node_ = 0;
  bool running_ = false;
  FaultConfinement fc_{255};  // an 8-bit receive error count
  ControllerEvents* listener_ = nullptr;
  std::deque<TxFrame> tx_;
  std::deque<ReceivedFrame> rx_;
  uint64_t overruns_ = 0;
  bool overrun_flag_ = false;
};

}  // namespace canemu::model
