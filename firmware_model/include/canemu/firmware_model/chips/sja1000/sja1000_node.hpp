// An SJA1000 run by a minimal host driver (see hosted_node.hpp): the bit timing from BTR0/BTR1,
// acceptance of every frame, one frame at a time through the transmit buffer (TR, or SRR for
// self reception, with AT for single shot), the receive FIFO released after every frame, reset
// mode when stopped, and bus-off left by clearing reset mode.
#pragma once

#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"

namespace canemu::model {

class Sja1000Node final : public HostedNode {
 public:
  // Puts a chip on `bus`, in reset mode. `scheduler` is the bus's.
  Sja1000Node(SimScheduler& scheduler, CanBus& bus);

  Sja1000& chip() { return chip_; }
  NodeId node() const override { return chip_.node(); }
  CanController& controller() override { return chip_; }
  bool fd_capable() const override { return false; }

 private:
  void program(const HostedNodeSettings& settings) override;
  void go_on_bus(const HostedNodeSettings& settings) override;
  void go_off_bus() override;
  void leave_bus_off(const HostedNodeSettings& settings) override;
  bool buffer_free() override;
  void load(const TxFrame& tx) override;
  void abort_tx() override;
  void release_received() override;
  void read_arbitration_capture() override;

  Sja1000 chip_;
};

}  // namespace canemu::model
