// The bus-facing side of a CAN controller model: what the bus asks of it and what it tells it.
//
// A chip model (SJA1000, the CAN FD controller, later the 82527) implements this interface; the
// bus engine (can_bus.hpp) runs the protocol: arbitration, acknowledgement, error signalling and
// fault confinement, on the counters the controller owns. All calls happen on the simulation
// island's scheduler, in simulated time.
#pragma once

#include <cstdint>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/bus/can_error.hpp"
#include "canemu/firmware_model/bus/fault_confinement.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model {

using NodeId = uint32_t;

// A frame a controller wants to send.
struct TxFrame {
  Frame frame;
  bool single_shot = false;     // no retransmission after an error or lost arbitration
  bool self_reception = false;  // the transmitter receives its own frame when it succeeds
};

enum class BusOffRecovery : uint8_t {
  automatic,   // counting the 128 x 11 recessive bits starts at bus-off
  on_restart,  // counting starts when the controller is restarted (SJA1000: reset mode left)
};

struct BusErrorEvent {
  SimTime at;  // end of the bit where the error was detected
  CanErrorType type = CanErrorType::bit;
  ErrorRole role = ErrorRole::receiver;
  uint16_t bit = 0;            // index in the frame (SOF = 0), as the detecting node saw it
  uint16_t destuffed_bit = 0;  // the same position without stuff bits
  Field field = Field::sof;
  bool extended_frame = false;
  bool in_frame = true;  // false when the bus was idle (e.g. held dominant)
  // CAN FD with bit-rate switch: detected in the fast data phase (after the sample point of BRS,
  // before that of the CRC delimiter), at the data bit rate.
  bool data_phase = false;
  uint16_t tec = 0;  // counters after the error was counted
  uint16_t rec = 0;
};

class CanController {
 public:
  virtual ~CanController() = default;

  // --- asked by the bus ---
  virtual NodeTiming timing() const = 0;
  // Taking part in bus traffic at all (not in reset, initialisation or sleep).
  virtual bool participating() const = 0;
  // Never drives the bus: no ACK, no error flags, counters frozen (SJA1000 listen-only mode).
  virtual bool listen_only() const { return false; }
  // Succeeds without an acknowledgement (SJA1000 self-test mode).
  virtual bool self_test() const { return false; }
  // Decodes CAN FD frames (a classic controller detects a form error in them).
  virtual bool fd_capable() const { return false; }
  virtual BusOffRecovery bus_off_recovery() const = 0;
  // The frame to send next, or nullptr. Must stay valid and unchanged until the bus reports it
  // done or dropped, or the controller calls CanBus::tx_changed().
  virtual const TxFrame* pending_tx() = 0;
  virtual FaultConfinement& confinement() = 0;

  // --- told by the bus ---
  // A valid frame, at the end of its EOF. `own`: the controller's own frame (self reception).
  virtual void on_frame(SimTime at, const Frame& frame, bool own) = 0;
  // pending_tx() went out successfully (end of EOF).
  virtual void on_tx_done(SimTime at) = 0;
  // pending_tx() will not be retried (single shot after an error or lost arbitration).
  virtual void on_tx_dropped(SimTime at) = 0;
  // Lost arbitration at frame bit `bit` (SOF = 0, stuff bits counted), which is bit
  // `destuffed_bit` of the frame without its stuff bits.
  virtual void on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed_bit) = 0;
  virtual void on_error(const BusErrorEvent& event) = 0;
  virtual void on_state_change(SimTime at, ErrorState state) = 0;
};

}  // namespace canemu::model
