// Arbitration at one start of frame (docs/bus-engine.md, "Timeline of a frame").
//
// The wired-AND makes the bus carry the lexicographically smallest of the contenders' bit
// sequences (dominant, 0, wins every comparison), so each contender drops out at its first
// difference from the winner's: inside its arbitration field that is a lost arbitration, after
// it a collision (a bit error, which ErrorPhase plays out). A contender whose frame is the
// winner's, bit for bit, sends it together with the winner.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "canemu/firmware_model/bus/can_controller.hpp"
#include "canemu/firmware_model/bus/node_list.hpp"

namespace canemu::model {

class Arbitration {
 public:
  struct Contender {
    NodeId node = 0;
    const EncodedFrame* bits = nullptr;  // what it sends; must outlive the results
    bool single_shot = false;            // the caller's, kept with a loss (AtBit)
  };
  struct AtBit {
    NodeId node = 0;
    uint16_t bit = 0;            // frame bit index, SOF = 0, stuff bits counted
    uint16_t destuffed_bit = 0;  // the same without the stuff bits before it
    bool single_shot = false;    // the contender's
  };

  // Resolves one start of frame among `contenders` (at least one). Of identical frames, the
  // first in `contenders` is the winner. The results below stay until the next call.
  void resolve(std::span<const Contender> contenders);

  // The same in steps, as a bus walks its nodes: begin() with room for `most` contenders, add()
  // each (in order; their first words are compared as they come, so that the common case needs
  // no second look at them), then resolve() (at least one added).
  void begin(std::size_t most) {
    reserve(most);
    begin();
  }
  // begin() for at most as many contenders as reserve() made room for.
  void reserve(std::size_t most) {
    contenders_.fit(most);
    lost_.fit(most);
  }
  void begin() {
    contenders_.clear();
    smallest_ = 0;
    smallest_word_ = ~uint64_t{0};
    tie_ = false;
  }
  void add(const Contender& c) {
    // A frame's first bit, SOF, is dominant, so a first word is never all ones: the first one
    // added is the smallest so far. (Were it, the tie would only send resolve() the long way.)
    const uint64_t word = c.bits->level[0];
    if (word <= smallest_word_) {
      tie_ = word == smallest_word_;  // a smaller one ends any tie
      smallest_word_ = word;
      smallest_ = contenders_.size();
    }
    contenders_.push_back(c);
  }
  bool empty() const { return contenders_.empty(); }
  void resolve();
  // resolve() in its two parts, for a caller that must prepare the long walk: the common case,
  // decided by the first words of the frames (a single smallest one, every other departing
  // from it within its arbitration field; false, with nothing recorded, if not), and the walk
  // over the whole frames (ties, collisions after the arbitration field), which decides any
  // case on its own and is what resolve() does when the first returns false.
  [[gnu::always_inline]] inline bool resolve_in_first_word();
  void resolve_walk();
  std::span<const Contender> contenders() const { return contenders_.span(); }

  // The nodes that send: the winner first, then, in contender order, those with the winner's
  // frame and those that collide with it.
  const std::vector<NodeId>& senders() const { return senders_; }
  NodeId winner() const { return senders_.front(); }
  const EncodedFrame& winning_bits() const { return *winning_bits_; }
  // Contenders that lost arbitration, with the bit at which they did, in contender order; kept
  // until forget_lost() or the next begin().
  std::span<const AtBit> lost() const { return lost_.span(); }
  void forget_lost() { lost_.clear(); }
  // Forgets the losses after `bit`: an error came first (CanBus's error path).
  void forget_lost_after(uint16_t bit) {
    lost_.erase_if([bit](const AtBit& a) { return a.bit > bit; });
  }
  // Senders whose frame departs from the winner's after the arbitration field, at that bit.
  const std::vector<AtBit>& collisions() const { return collisions_; }
  // The bit at which `node`'s frame collides with the winner's, if it does.
  std::optional<uint16_t> collision_of(NodeId node) const;

  // First bit where two frames differ, within the shorter one.
  static std::optional<uint16_t> first_difference(const EncodedFrame& a, const EncodedFrame& b) {
    const uint32_t len = std::min(a.length, b.length);
    for (uint32_t w = 0; w * 64 < len; ++w) {
      const uint64_t x = a.level[w] ^ b.level[w];
      if (x != 0) {
        const uint32_t at = w * 64 + static_cast<uint32_t>(__builtin_clzll(x));
        if (at < len) {
          return static_cast<uint16_t>(at);
        }
        return std::nullopt;
      }
    }
    return std::nullopt;
  }

 private:
  // Both resolve steps start afresh.
  void clear_results() {
    senders_.clear();
    lost_.clear();
    collisions_.clear();
  }

  // What add() gathered.
  NodeList<Contender> contenders_;
  std::size_t smallest_ = 0;  // of the smallest first word: the last one to have it (tie_)
  uint64_t smallest_word_ = ~uint64_t{0};
  bool tie_ = false;

  std::vector<NodeId> senders_;
  const EncodedFrame* winning_bits_ = nullptr;
  NodeList<AtBit> lost_;
  std::vector<AtBit> collisions_;
  std::vector<uint16_t> split_;  // scratch: where each contender departs from the winner
};

// Inline: the bus calls it at every start of frame, and it is a handful of compares.
inline bool Arbitration::resolve_in_first_word() {
  clear_results();
  // The smallest first word wins if no other contender has it too.
  if (tie_) {
    return false;
  }
  const std::span<const Contender> contenders = contenders_.span();
  const std::size_t best = smallest_;
  const uint64_t best_word = smallest_word_;
  // Every other contender must lose within its arbitration field (the first word holds it).
  for (std::size_t k = 0; k < contenders.size(); ++k) {
    if (k == best) {
      continue;
    }
    const EncodedFrame& bits = *contenders[k].bits;
    const auto at = static_cast<uint16_t>(__builtin_clzll(bits.level[0] ^ best_word));
    if (at >= bits.arbitration_end) {
      lost_.clear();
      return false;
    }
    lost_.push_back(
        AtBit{contenders[k].node, at, bits.destuffed_index(at), contenders[k].single_shot});
  }
  winning_bits_ = contenders[best].bits;
  senders_.push_back(contenders[best].node);
  return true;
}

}  // namespace canemu::model
