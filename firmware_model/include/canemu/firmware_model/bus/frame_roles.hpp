// The part each node on the bus takes in one frame, decided at its start of frame
// (docs/bus-engine.md): whether it sends (Arbitration decides who) or receives, whether it
// follows the frame and acknowledges it, and which error it will detect at which bit, if any:
// a collision, a format or timing it cannot decode, an injected fault. When nobody acknowledges
// (and no sender is in self-test) the senders will detect an ACK error at the ACK slot.
// ErrorPhase plays these decisions out bit by bit; without any, the frame simply succeeds.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>

#include "canemu/firmware_model/bus/error_phase.hpp"

namespace canemu::model {

// What an injection does to one frame.
struct FrameFault {
  std::optional<CanErrorType> error;  // corrupt the frame: who detects what, see docs
  std::optional<uint16_t> bit;        // where (frame bit index); a default per type otherwise
  bool suppress_ack = false;          // no node acknowledges this frame
};

// What the bus knows of a node on it when a frame starts.
struct NodeFacts {
  NodeId id = 0;
  bool listen_only = false;
  bool error_passive = false;
  bool self_test = false;
};

class FrameRoles {
 public:
  // Why a receiver cannot follow the frame, if it cannot.
  enum class Decoding : uint8_t {
    ok,
    not_fd,  // a classic controller and an FD frame: form error at the bit after FDF
    timing,  // bit timing it cannot decode (check_compatibility): stuff error after arbitration
  };

  // `frame`: the winner's bits, which the bus carries (kept by reference: it must outlive this
  // object). `acks_suppressed`: no node acknowledges anything now (CanBus::suppress_acks_until);
  // `fault` may suppress them for this frame too.
  FrameRoles(const EncodedFrame& frame, const FrameFault& fault, bool acks_suppressed);

  // A node that sends `own`, which collides with the frame at `collision` (Arbitration). An
  // injected bit error is detected by every sender.
  BusParticipant sender(const NodeFacts& node, const EncodedFrame& own,
                        std::optional<uint16_t> collision) const;
  // A node that receives. Injected stuff, form and CRC errors are detected by every receiver
  // that follows the frame; one that will detect a CRC error does not acknowledge.
  BusParticipant receiver(const NodeFacts& node, Decoding decoding) const;

  // The first bit at which any participant will detect an error: the earliest planned
  // detection, or the ACK slot when no receiver acknowledges and no sender is in self-test;
  // nothing when the frame will succeed.
  std::optional<uint16_t> first_detection(std::span<const BusParticipant> parts) const;

  // Where an injected error of `type` is detected in `frame`: at `bit` when such an error can
  // be detected there, clamped into that range or a default otherwise.
  static uint16_t place_injected(const EncodedFrame& frame, CanErrorType type,
                                 std::optional<uint16_t> bit);

 private:
  const EncodedFrame& frame_;
  FrameFault fault_;
  bool acks_suppressed_;
};

// Inline: called for every node at every start of frame.

inline FrameRoles::FrameRoles(const EncodedFrame& frame, const FrameFault& fault,
                              bool acks_suppressed)
    : frame_(frame),
      fault_(fault),
      acks_suppressed_(acks_suppressed || fault.suppress_ack ||
                       (fault.error && *fault.error == CanErrorType::ack)) {}

inline BusParticipant FrameRoles::sender(const NodeFacts& node, const EncodedFrame& own,
                                         std::optional<uint16_t> collision) const {
  BusParticipant p;
  p.id = node.id;
  p.transmitter = true;
  p.drives = !node.listen_only;
  p.passive = node.error_passive;
  p.self_test = node.self_test;
  p.bits = &own;
  // Should it lose arbitration in the error phase (a hold), it receives from there and
  // acknowledges as a receiver does.
  p.acks = p.drives && !acks_suppressed_;
  if (collision) {
    p.planned = std::make_pair(CanErrorType::bit, *collision);
  } else if (fault_.error && *fault_.error == CanErrorType::bit) {
    p.planned =
        std::make_pair(CanErrorType::bit, place_injected(frame_, CanErrorType::bit, fault_.bit));
  }
  return p;
}

inline BusParticipant FrameRoles::receiver(const NodeFacts& node, Decoding decoding) const {
  BusParticipant p;
  p.id = node.id;
  p.drives = !node.listen_only;
  p.passive = node.error_passive;
  p.self_test = node.self_test;
  switch (decoding) {
    case Decoding::not_fd:
      p.decodes = false;
      p.planned = std::make_pair(CanErrorType::form,
                                 static_cast<uint16_t>(frame_.field_begin(Field::fdf) + 1));
      break;
    case Decoding::timing:
      p.decodes = false;
      p.planned = std::make_pair(CanErrorType::stuff, frame_.arbitration_end);
      break;
    case Decoding::ok:
      if (fault_.error && *fault_.error != CanErrorType::bit &&
          *fault_.error != CanErrorType::ack) {
        p.planned =
            std::make_pair(*fault_.error, place_injected(frame_, *fault_.error, fault_.bit));
      }
      break;
  }
  p.acks = p.decodes && p.drives && !acks_suppressed_ &&
           !(p.planned && p.planned->first == CanErrorType::crc);
  return p;
}

inline std::optional<uint16_t> FrameRoles::first_detection(
    std::span<const BusParticipant> parts) const {
  std::optional<uint16_t> first;
  bool acked = false;
  for (const BusParticipant& p : parts) {
    if (p.planned) {
      first = first ? std::min(*first, p.planned->second) : p.planned->second;
    }
    acked = acked || (!p.transmitter && p.acks) || (p.transmitter && p.self_test);
  }
  if (!acked) {
    const uint16_t ack_slot = static_cast<uint16_t>(frame_.crc_delimiter_index + 1);
    first = first ? std::min(*first, ack_slot) : ack_slot;
  }
  return first;
}

}  // namespace canemu::model
