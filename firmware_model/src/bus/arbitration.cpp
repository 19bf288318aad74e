#include "canemu/firmware_model/bus/arbitration.hpp"

namespace canemu::model {

namespace {

constexpr uint16_t kSame = 0xFFFF;

// The first bit at which the frames `a` and `b` differ, or kSame if they do not differ before
// the shorter one ends; `a_smaller`: whether `a` carries the dominant bit there (first bit first:
// comparing words as numbers is comparing bit sequences). Bits past a frame's end are left alone:
// the encoder does not define them, and identical frames must tie whatever they hold.
inline uint16_t first_split(const EncodedFrame& a, const EncodedFrame& b, bool& a_smaller) {
  const uint32_t len = std::min(a.length, b.length);
  for (uint32_t w = 0; w * 64 < len; ++w) {
    const uint64_t x = a.level[w] ^ b.level[w];
    if (x != 0) {
      const uint32_t at = w * 64 + static_cast<uint32_t>(__builtin_clzll(x));
      if (at >= len) {
        break;
      }
      a_smaller = a.level[w] < b.level[w];
      return static_cast<uint16_t>(at);
    }
  }
  a_smaller = false;
  return kSame;
}

}  // namespace

void Arbitration::resolve(std::span<const Contender> contenders) {
  begin(contenders.size());
  for (const Contender& c : contenders) {
    add(c);
  }
  resolve();
}

void Arbitration::resolve() {
  // Nearly always the identifiers decide within the first 64 bits of the frames.
  if (!resolve_in_first_word()) {
    resolve_walk();
  }
}

void Arbitration::resolve_walk() {
  clear_results();
  // One pass: the winner so far, and where every other contender departs from it. Identical
  // frames tie, and of them the first in `contenders` stays the winner.
  const std::span<const Contender> contenders = contenders_.span();
  const std::size_t n = contenders.size();
  if (split_.size() < n) {
    split_.resize(n);
  }
  std::size_t best = 0;
  for (std::size_t k = 1; k < n; ++k) {
    bool smaller = false;
    const uint16_t d = first_split(*contenders[k].bits, *contenders[best].bits, smaller);
    if (!smaller) {
      split_[k] = d;
      continue;
    }
    // k wins over the old winner, departing from it at d (so d is a real bit): the others followed
    // the old winner up to their own split. Those that split before d split from k there too;
    // those that split after d (or never) share the old winner's bit at d, which k does not; those
    // that split at d too carry k's bit there, and their split from k lies further on.
    for (std::size_t i = 0; i < k; ++i) {
      if (i == best) {
        continue;
      }
      if (split_[i] > d) {
        split_[i] = d;
      } else if (split_[i] == d) {
        bool ignored = false;
        split_[i] = first_split(*contenders[i].bits, *contenders[k].bits, ignored);
      }
    }
    split_[best] = d;
    best = k;
  }
  const Contender& winner = contenders[best];
  winning_bits_ = winner.bits;
  senders_.push_back(winner.node);
  for (std::size_t k = 0; k < n; ++k) {
    if (k == best) {
      continue;
    }
    const Contender& c = contenders[k];
    const uint16_t d = split_[k];
    if (d >= std::min(c.bits->length, winning_bits_->length)) {
      senders_.push_back(c.node);  // the same frame: sent together
    } else if (d < c.bits->arbitration_end) {
      lost_.push_back(AtBit{c.node, d, c.bits->destuffed_index(d), c.single_shot});
    } else {
      senders_.push_back(c.node);
      collisions_.push_back(AtBit{c.node, d});  // only the node and the bit are read
    }
  }
}

std::optional<uint16_t> Arbitration::collision_of(NodeId node) const {
  for (const AtBit& c : collisions_) {
    if (c.node == node) {
      return c.bit;
    }
  }
  return std::nullopt;
}

}  // namespace canemu::model
