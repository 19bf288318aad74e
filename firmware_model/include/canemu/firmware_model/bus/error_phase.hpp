// The bit-by-bit part of the bus engine (docs/bus-engine.md, "Errors: what is bit-exact"): from
// the first bit at which some node detects an error to the end of the last error delimiter,
// what every node drives, what the wired-AND bus carries, and what each node makes of it
// (detections, error flags and their superposition, delimiters, the fault-confinement rules
// that depend on what a node sees), as a list of timed actions.
//
// ErrorPhase is pure: it neither touches the controllers nor schedules anything. CanBus builds
// the participants at a start of frame (or of a dominant hold), runs the phase, and applies the
// actions at their instants. Numbers in comments are the rule numbers of ISO 11898-1:2015
// 12.1.4.2.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "canemu/firmware_model/bus/can_controller.hpp"

namespace canemu::model {

// One node's part in one bus activity.
struct BusParticipant {
  NodeId id = 0;
  bool transmitter = false;
  bool drives = true;    // false for listen-only nodes
  bool decodes = true;   // timing and format let it follow the frame
  bool acks = false;     // drives the ACK slot dominant (a transmitter: once it lost arbitration)
  bool passive = false;  // error-passive when the activity started: its flags are recessive
  bool self_test = false;
  const EncodedFrame* bits = nullptr;                        // what it sends (transmitters)
  std::optional<std::pair<CanErrorType, uint16_t>> planned;  // detection it will make, at a bit
};

// The bus held dominant from `first` for `second` (a shorted or stuck transceiver).
using DominantHold = std::pair<SimTime, SimDuration>;

class ErrorPhase {
 public:
  struct Setup {
    SimTime sof;                            // start of frame, or of the hold
    const EncodedFrame* frame = nullptr;    // the winner's bits; nullptr for a dominant hold
    BitTiming nominal;                      // error flags and delimiters run at this rate
    BitTiming data;                         // the frame's data phase (BRS) before the error
    uint16_t first_bit = 0;                 // the first bit at which anybody may detect an error
    std::span<const DominantHold> holds{};  // holds known at the start of frame
  };

  // Something that happens to one node at an instant (the end of a bit).
  struct Action {
    enum class Kind : uint8_t {
      error,             // detected an error: counted (rules 1, 3) unless `count` is false
      severe,            // rules 2 and 6, and rule 3 when the passive ACK exception lapses
      arbitration_lost,  // lost arbitration inside the bit simulation: receives from here on
      tx_ok,             // sent the whole frame (rule 7)
      rx_ok,             // received a valid frame; rule 8 only with `count` (ACK sent)
    };
    SimTime at;
    NodeId node = 0;
    Kind kind = Kind::error;
    CanErrorType type = CanErrorType::bit;
    ErrorRole role = ErrorRole::receiver;
    uint16_t bit = 0;
    bool count = true;
    bool in_frame = true;  // false while the bus was held idle
    Field field = Field::sof;
    uint16_t destuffed_bit = 0;
    bool extended = false;
    bool data_phase = false;  // BusErrorEvent::data_phase
  };

  struct Outcome {
    std::vector<Action> actions;  // in time order (stable for one instant)
    uint32_t end_bit = 0;         // the bit that ends the activity (last delimiter or hold)
    SimTime end;                  // end of that bit
    SimTime ifs_end;              // end of the intermission after it: the bus is free
    SimTime dominant_end;         // end of the last dominant bit
    // What became of a transmitter.
    struct Transmitter {
      NodeId id = 0;
      bool sent = false;  // its whole frame, without detecting an error (never after a loss)
      // It lost arbitration on the way: a receiver of the activity from there on (an
      // error-passive one does not suspend its next transmission).
      bool lost_arbitration = false;
      friend bool operator==(const Transmitter&, const Transmitter&) = default;
    };
    std::vector<Transmitter> transmitters;  // every one, in the order of the participants
  };

  ErrorPhase(const Setup& setup, std::span<const BusParticipant> parts);

  // Plays the bits out. Call once.
  Outcome run();

  // Last bit + 1 of the dynamically stuffed part of `frame` (CAN FD: the stuff count begins).
  static uint16_t stuffed_end(const EncodedFrame& frame);

 private:
  enum class Phase : uint8_t { frame, flag, wait_recessive, delimiter, done };
  // One participant's progress.
  struct State {
    Phase phase = Phase::frame;
    bool is_tx = false;
    uint32_t flag_start = 0;
    uint32_t flag_end = 0;   // last bit of the flag
    uint32_t equal_run = 0;  // passive flag: equal bits seen since the flag started
    bool equal_level = true;
    uint32_t dominant_run = 0;  // consecutive dominant bits (rule 6)
    uint32_t delimiter = 0;
    bool passive_ack_pending = false;  // ACK-error exception still possible
    bool detected = false;
  };

  SimTime bit_end(uint32_t i) const;
  bool held(uint32_t i) const;
  bool frame_bit(uint32_t i) const;                    // the bus as the frame and its ACK make it
  bool driven_level(std::size_t k, uint32_t i) const;  // true: recessive
  void detect(std::size_t k, uint32_t i, CanErrorType type, bool count);
  // What participant k makes of bit i, by its phase.
  void in_frame(std::size_t k, uint32_t i, bool bus, bool prev_bus);
  void in_flag(std::size_t k, uint32_t i, bool bus);
  void waiting_recessive(std::size_t k, uint32_t i, bool bus);
  void in_delimiter(std::size_t k, bool bus);

  Setup setup_;
  std::span<const BusParticipant> parts_;
  const EncodedFrame* e_;
  SimTime error_start_;  // end of the bits before first_bit, at the frame's own rates
  SimDuration bit_time_;
  uint16_t length_ = 0;
  uint16_t ack_slot_ = 0;
  uint16_t stuff_end_ = UINT16_MAX;
  bool any_ack_ = false;
  uint32_t run_ = 0;  // equal consecutive bus levels, up to the current bit
  std::vector<State> st_;
  std::vector<Action> actions_;
};

}  // namespace canemu::model
