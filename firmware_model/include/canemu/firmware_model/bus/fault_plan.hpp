// A rule-based FaultInjector: frame faults chosen by matching transmitter, identifier with mask,
// format and occurrence. The scenario language of the daemon compiles into these rules; tests
// use them directly.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"

namespace canemu::model {

struct FrameMatch {
  std::optional<NodeId> transmitter;
  uint32_t id = 0;
  uint32_t mask = 0;  // bits of the identifier that must equal `id`; 0 matches every frame
  std::optional<bool> extended;
  std::optional<bool> remote;

  bool matches(NodeId tx, const Frame& frame) const {
    return (!transmitter || *transmitter == tx) && ((frame.id() ^ id) & mask) == 0 &&
           (!extended || *extended == frame.extended()) && (!remote || *remote == frame.remote());
  }
};

struct FaultRule {
  FrameMatch match;
  FrameFault fault;
  uint64_t skip = 0;              // matching frames to let through first (nth occurrence)
  std::optional<uint64_t> count;  // matching frames to hit; none: every one
  SimTime from;                   // window in simulated time
  std::optional<SimTime> until;
  double probability = 1.0;  // per matching frame, drawn from the rule's own generator
  // Above 0: random bit errors instead of `fault`. Every bit of a matching frame is hit with
  // this probability; the first bit hit becomes a bit error there (frames with no bit hit pass).
  double bit_error_rate = 0;
  uint64_t seed = 1;  // of that generator: the same seed gives the same draws

  uint64_t seen = 0;    // matching frames so far
  uint64_t hits = 0;    // frames hit so far
  uint64_t rng = 0;     // generator state, from `seed` when the rule is added
  bool enabled = true;  // a cleared rule stays (its counts with it) but matches nothing
};

// Rules are named by the id add() gives (0, 1, 2, ... in the order they were added), which
// stays theirs when others are removed.
class FaultPlan final : public FaultInjector {
 public:
  FaultPlan() { set_frames_wanted(false); }
  std::size_t add(FaultRule rule) {
    rule.rng = rule.seed;
    rules_.push_back(rule);
    ids_.push_back(next_id_);
    set_frames_wanted(true);
    return next_id_++;
  }
  // The rule `id` (it must be there).
  const FaultRule& rule(std::size_t id) const { return rules_[index_of(id)]; }
  bool contains(std::size_t id) const;
  // A disabled rule stays (its counts with it) but matches nothing.
  void disable(std::size_t id) { rules_[index_of(id)].enabled = false; }
  // Gone: no frame scans it any more.
  void remove(std::size_t id);
  std::size_t size() const { return rules_.size(); }
  void clear() {
    rules_.clear();
    ids_.clear();
    set_frames_wanted(false);
  }

  // The first rule that matches, still has hits left and wins its draw decides; every matching
  // rule counts the frame as seen.
  FrameFault on_frame(const FrameContext& ctx) override;

  // Told of every hit: the rule's id (its hit already counted) and the frame it hits.
  std::function<void(std::size_t rule, const FrameContext& ctx, const FrameFault& fault)> on_hit;

 private:
  static double draw(FaultRule& rule);  // uniform in [0, 1), splitmix64
  std::size_t index_of(std::size_t id) const;

  std::vector<FaultRule> rules_;
  std::vector<std::size_t> ids_;  // ascending, beside rules_
  std::size_t next_id_ = 0;
};

}  // namespace canemu::model
