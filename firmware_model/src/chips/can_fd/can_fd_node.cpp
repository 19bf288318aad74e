#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"

namespace canemu::model {

CanFdNode::CanFdNode(SimScheduler& scheduler, CanBus& bus) : HostedNode(scheduler, bus) {
  chip_.connect(bus);
  chip_.set_listener(events());
}

void CanFdNode::program(const HostedNodeSettings& settings) {
  chip_.stop();
  chip_.abort_pending();
  while (chip_.receive()) {
  }
  chip_.clear_overrun();
  CanFdConfig c;
  c.nominal = settings.nominal;
  c.data = settings.data;
  c.listen_only = settings.listen_only;
  c.fd_enabled = settings.fd;
  c.recovery = BusOffRecovery::on_restart;
  chip_.configure(c);
  chip_.confinement().reset();
  bus().counters_changed(chip_.node());
}

void CanFdNode::go_on_bus(const HostedNodeSettings&) {
  chip_.start();
}

void CanFdNode::go_off_bus() {
  chip_.stop();
  chip_.abort_pending();
}

void CanFdNode::leave_bus_off(const HostedNodeSettings&) {
  chip_.restart();
}

}  // namespace canemu::model
