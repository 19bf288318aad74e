// What a controller model reports to the adapter firmware model above it, besides its
// registers and interrupt line: one interface for every chip.
#pragma once

#include <cstdint>

#include "canemu/firmware_model/bus/can_controller.hpp"

namespace canemu::model {

class ControllerEvents {
 public:
  virtual ~ControllerEvents() = default;
  // A frame was accepted (passed the acceptance filter) and stored. `own`: self reception.
  virtual void frame_received(SimTime /*at*/, const Frame& /*frame*/, bool /*own*/) {}
  virtual void frame_transmitted(SimTime /*at*/, const Frame& /*frame*/) {}
  // A transmission ended without success and will not be retried (single shot, abort).
  virtual void transmission_dropped(SimTime /*at*/, const Frame& /*frame*/) {}
  virtual void bus_error(const BusErrorEvent& /*event*/) {}
  virtual void state_changed(SimTime /*at*/, ErrorState /*state*/, uint16_t /*tec*/,
                             uint16_t /*rec*/) {}
  // A received frame was lost because the receive buffer was full.
  virtual void overrun(SimTime /*at*/, const Frame& /*lost*/) {}
  virtual void arbitration_lost(SimTime /*at*/, uint16_t /*bit*/) {}
};

}  // namespace canemu::model
