// ISO 11898-1:2015 fault confinement (12.1.4): the transmit and receive error counters, the
// error state they give, and bus-off recovery.
//
// The rules are methods named after what happened; the bus engine decides which happened (it
// knows the roles, the error types and the bits on the wire), this class only counts. Numbers in
// comments are the rule numbers of ISO 11898-1:2015 12.1.4.2.
#pragma once

#include <cstdint>

#include "canemu/firmware_model/bus/can_error.hpp"

namespace canemu::model {

inline constexpr uint16_t kErrorPassiveLimit = 128;
static_assert((kErrorPassiveLimit & (kErrorPassiveLimit - 1)) == 0,
              "error_passive() tests both counters at once: the limit must be a power of two");
inline constexpr uint16_t kBusOffLimit = 256;
inline constexpr uint8_t kDefaultWarningLimit = 96;
inline constexpr uint32_t kBusOffRecoverySequences = 128;  // of 11 consecutive recessive bits
inline constexpr uint32_t kRecoverySequenceBits = 11;

class FaultConfinement {
 public:
  // `rec_limit`: where the receive error counter stops. ISO 11898-1 sets no upper bound (rule 8
  // takes anything above 127 back to 127), so a counter is as wide as the controller makes it:
  // 8 bits (255) on the SJA1000 (RXERR) and the CAN FD controller; the default only keeps the
  // 16-bit value from wrapping.
  explicit FaultConfinement(uint16_t rec_limit = 0xFFFF) : rec_limit_(rec_limit) {}

  uint16_t tec() const { return tec_; }
  uint16_t rec() const { return rec_; }
  uint16_t rec_limit() const { return rec_limit_; }
  bool bus_off() const { return bus_off_; }
  bool error_passive() const {
    // Either counter at 128 or above: their bits from 7 up, taken together (one test, not two).
    return !bus_off_ && (tec_ | rec_) >= kErrorPassiveLimit;
  }
  ErrorState state() const;
  // A number that changes whenever bus_off() or error_passive() may have changed (and at other
  // times too: every counted error, every direct write, every assignment): a cheap look for
  // whether either still reads as it did (the bus engine keeps a frame's roles while they do).
  uint32_t passive_or_off_changes() const { return changes_.n; }

  // The limit for the warning state (SJA1000 EWLR); 96 unless programmed.
  uint8_t warning_limit() const { return warning_limit_; }
  void set_warning_limit(uint8_t limit) { warning_limit_ = limit; }

  // Rule 1: a receiver detects an error: REC + 1.
  void receiver_detected_error() { add_rec(1); }
  // Rules 2 and 5: a receiver sees a dominant bit right after its error flag, or a bit error
  // while sending an active error flag or overload flag: REC + 8.
  void receiver_severe_error() { add_rec(8); }
  // Rules 3 and 4: a transmitter sends an error flag (the caller has already applied the passive
  // ACK-error and the arbitration stuff-error exceptions), or detects a bit error in its active
  // error flag or overload flag: TEC + 8. May end in bus-off.
  void transmitter_error() { add_tec(8); }
  // Rule 6: 14 consecutive dominant bits after an active error flag (8 after a passive one), and
  // each further 8: + 8 for every transmitter and every receiver.
  void dominant_sequence(ErrorRole role) {
    role == ErrorRole::transmitter ? add_tec(8) : add_rec(8);
  }
  // Rule 7: successful transmission: TEC - 1.
  void transmit_succeeded() {
    if (tec_ > 0) {
      changes_.n += tec_ == kErrorPassiveLimit ? 1u : 0u;
      --tec_;
    }
  }
  // Rule 8: successful reception: REC - 1, or from above 127 back to 127 (ISO allows 119..127;
  // docs/bus-engine.md).
  void receive_succeeded() {
    if (rec_ > 127) {
      rec_ = 127;
      ++changes_.n;
    } else if (rec_ > 0) {
      --rec_;
    }
  }

  // Bus-off recovery: `begin_recovery` starts counting sequences of 11 recessive bits (at once
  // for controllers that recover by themselves, on restart for the others); after 128 of them
  // both counters are 0 and the node is error-active again.
  bool recovering() const { return bus_off_ && recovering_; }
  void begin_recovery() {
    if (bus_off_) {
      recovering_ = true;
      sequences_seen_ = 0;
    }
  }
  uint32_t recovery_sequences_left() const { return kBusOffRecoverySequences - sequences_seen_; }
  // Counts `n` sequences; returns true when recovery completed.
  bool recessive_sequences(uint32_t n);

  // Direct writes: SJA1000 RXERR/TXERR in reset mode, fault injection. A TEC above 255 means
  // bus-off; a REC above the limit is the limit.
  void set_counters(uint16_t tec, uint16_t rec);
  void reset();

 private:
  void add_tec(uint16_t n);
  void add_rec(uint16_t n);

  uint16_t tec_ = 0;
  uint16_t rec_ = 0;
  uint16_t rec_limit_;
  uint8_t warning_limit_ = kDefaultWarningLimit;
  bool bus_off_ = false;
  bool recovering_ = false;
  uint32_t sequences_seen_ = 0;
  // passive_or_off_changes(). An assignment of the whole moves it on rather than copying it,
  // so that a look at it is not fooled by one (the other members are copied as they are).
  struct ChangeCount {
    uint32_t n = 0;
    ChangeCount() = default;
    ChangeCount(const ChangeCount&) = default;
    ChangeCount& operator=(const ChangeCount&) {
      ++n;
      return *this;
    }
  };
  ChangeCount changes_;
};

}  // namespace canemu::model
