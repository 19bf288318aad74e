// The CAN FD controller run by a minimal host driver (see hosted_node.hpp): nominal and data
// timing, every frame accepted, one frame at a time in its transmit queue, the receive queue
// emptied after every frame, stopped when the node stops, and bus-off left by restart() (the
// driver asks for it; the controller does not recover on its own here).
#pragma once

#include "canemu/firmware_model/chips/can_fd/can_fd_controller.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"

namespace canemu::model {

class CanFdNode final : public HostedNode {
 public:
  // Puts a stopped controller on `bus`. `scheduler` is the bus's.
  CanFdNode(SimScheduler& scheduler, CanBus& bus);

  CanFdController& chip() { return chip_; }
  NodeId node() const override { return chip_.node(); }
  CanController& controller() override { return chip_; }
  bool fd_capable() const override { return true; }

 private:
  void program(const HostedNodeSettings& settings) override;
  void go_on_bus(const HostedNodeSettings& settings) override;
  void go_off_bus() override;
  void leave_bus_off(const HostedNodeSettings& settings) override;
  bool buffer_free() override { return chip_.tx_queued() == 0; }
  void load(const TxFrame& tx) override { chip_.submit(tx); }
  void abort_tx() override { chip_.abort_pending(); }
  void release_received() override { chip_.receive(); }

  CanFdController chip_;
};

}  // namespace canemu::model
