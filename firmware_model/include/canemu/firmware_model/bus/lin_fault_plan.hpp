// Rule-based faults on a LIN bus (a LinFaultSource): the scenario language's lin_* effects
// compile into these rules (docs/faults.md); tests use them directly. A rule matches frames by
// commander and identifier, in a window of simulated time, after `skip` matching frames and
// for `count` of them.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "canemu/firmware_model/bus/lin_bus.hpp"

namespace canemu::model::lin {

enum class LinEffect : uint8_t {
  header_bit_error,    // lin_bit_error in the header: the commander sees a bit error
  response_bit_error,  // lin_bit_error in the response: the responder sees one and stops
  checksum_error,      // lin_checksum_error: the responder sends a wrong checksum
  parity_error,        // lin_parity_error: the identifier goes with wrong parity bits
  no_response,         // lin_no_response: every responder stays silent
  sync_error,          // lin_sync_error: the sync byte is corrupted
  short_break,         // lin_short_break: a break too short to be one
  responder_off,       // lin_responder_off: `responder` does not answer
};

struct LinFaultRule {
  LinEffect effect = LinEffect::no_response;
  std::optional<LinNodeId> commander;  // who sends the header; none: anyone
  std::optional<uint8_t> id;           // none: every identifier
  LinNodeId responder = kNoNode;       // responder_off: the node switched off
  uint64_t skip = 0;                   // matching frames to let through first
  std::optional<uint64_t> count;       // matching frames to hit; none: every one
  SimTime from;
  std::optional<SimTime> until;

  uint64_t seen = 0;
  uint64_t hits = 0;
  bool enabled = true;
};

class LinFaultPlan final : public LinFaultSource {
 public:
  std::size_t add(const LinFaultRule& rule) {
    rules_.push_back(rule);
    return rules_.size() - 1;
  }
  const LinFaultRule& rule(std::size_t i) const { return rules_[i]; }
  void disable(std::size_t i) { rules_[i].enabled = false; }
  std::size_t size() const { return rules_.size(); }
  void clear() { rules_.clear(); }

  // Every matching rule with hits left adds its effect to the frame (and counts the frame as
  // seen; one that still skips counts it and lets it pass).
  FrameFaults faults_for(SimTime at, uint8_t id, LinNodeId commander) override;

  // Told of every hit: the rule's index (its hit already counted), the frame's instant and ID.
  std::function<void(std::size_t rule, SimTime at, uint8_t id)> on_hit;

 private:
  std::vector<LinFaultRule> rules_;
};

}  // namespace canemu::model::lin
