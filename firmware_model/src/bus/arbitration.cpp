#include "canemu/firmware_model/bus/arbitration.hpp"

namespace canemu::model {

void Arbitration::resolve(std::span<const Contender> contenders) {
  senders_.clear();
  lost_.clear();
  collisions_.clear();
  const Contender* winner = &contenders.front();
  for (std::size_t k = 1; k < contenders.size(); ++k) {
    const EncodedFrame& ec = *contenders[k].bits;
    const EncodedFrame& best = *winner->bits;
    // First bit first: comparing words as numbers is comparing bit sequences. (Bits past the
    // end of a frame only count when two frames are equal up to there, that is, identical.)
    std::size_t w = 0;
    while (w + 1 < ec.level.size() && ec.level[w] == best.level[w]) {
      ++w;
    }
    if (ec.level[w] < best.level[w]) {
      winner = &contenders[k];
    }
  }
  winning_bits_ = winner->bits;
  senders_.push_back(winner->node);
  for (const Contender& c : contenders) {
    if (&c == winner) {
      continue;
    }
    const auto d = first_difference(*c.bits, *winning_bits_);
    if (!d) {
      senders_.push_back(c.node);  // the same frame: sent together
    } else if (*d < c.bits->arbitration_end) {
      lost_.push_back(AtBit{c.node, *d});
    } else {
      senders_.push_back(c.node);
      collisions_.push_back(AtBit{c.node, *d});
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
