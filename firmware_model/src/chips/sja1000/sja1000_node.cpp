#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

namespace canemu::model {

using namespace sja1000;

Sja1000Node::Sja1000Node(SimScheduler& scheduler, CanBus& bus) : HostedNode(scheduler, bus) {
  chip_.connect(bus);
  chip_.set_listener(events());
}

void Sja1000Node::program(const HostedNodeSettings& settings) {
  // A reset through the RST pin: whatever the last user left (a request held through bus-off,
  // counters, filters) is gone.
  chip_.hardware_reset();
  chip_.write(BTR0, settings.btr0);
  chip_.write(BTR1, settings.btr1);
  for (uint8_t k = 0; k < 4; ++k) {
    chip_.write(static_cast<uint8_t>(AMR0 + k), 0xFF);  // accept everything
  }
}

void Sja1000Node::go_on_bus(const HostedNodeSettings& settings) {
  chip_.write(MOD, settings.listen_only ? MOD_LOM : 0);
}

void Sja1000Node::go_off_bus() {
  chip_.write(MOD, MOD_RM);
}

void Sja1000Node::leave_bus_off(const HostedNodeSettings& settings) {
  go_on_bus(settings);  // clearing reset mode starts the recovery count
}

bool Sja1000Node::buffer_free() {
  // In reset mode (stopped, or bus-off) the buffer's addresses are the acceptance registers.
  return chip_.transmit_buffer_free();
}

void Sja1000Node::load(const TxFrame& tx) {
  uint8_t cmr = tx.self_reception ? CMR_SRR : CMR_TR;
  if (tx.single_shot) {
    cmr |= CMR_AT;
  }
  chip_.write_transmit(tx.frame, cmr);  // the frame's bytes at FRAME, then CMR
}

void Sja1000Node::abort_tx() {
  chip_.write(CMR, CMR_AT);
}

void Sja1000Node::release_received() {
  chip_.release_receive_buffer();
}

void Sja1000Node::read_arbitration_capture() {
  chip_.read(ALC);
}

}  // namespace canemu::model
