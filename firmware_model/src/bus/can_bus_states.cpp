// CanBus: the error states its nodes report and bus-off recovery (128 sequences of 11
// recessive bits, counted in each node's own bit time).
#include <algorithm>

#include "bus/can_bus_detail.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"

namespace canemu::model {

using detail::because;
using detail::with_ppm;

// A dominant bit starts at `dominant_start`: every recovering node counts the sequences of 11
// recessive bits it saw since the last dominant bit (or since its recovery began).
void CanBus::account_recessive(SimTime dominant_start) {
  if (!maybe_recovering_) {
    return;
  }
  bool any = false;
  for (NodeId id = 0; id < node_count_; ++id) {
    Node& n = nodes_[id];
    FaultConfinement& fc = *n.fc;
    if (!fc.recovering()) {
      continue;
    }
    any = true;
    if (n.recovery_event != 0) {
      scheduler_.cancel(n.recovery_event);
      n.recovery_event = 0;
    }
    const SimTime from = std::max(last_dominant_end_, n.recovery_from);
    if (dominant_start > from) {
      const uint64_t bits = bits_in(id, dominant_start - from);
      if (fc.recessive_sequences(static_cast<uint32_t>(bits / kRecoverySequenceBits))) {
        recovered(id, dominant_start);
        continue;
      }
    }
    n.recovery_from = dominant_start;
  }
  maybe_recovering_ = any;
}

void CanBus::arm_recovery(NodeId id) {
  Node& n = nodes_[id];
  FaultConfinement& fc = n.controller->confinement();
  if (!fc.recovering() || busy_) {
    return;
  }
  if (n.recovery_event != 0) {
    scheduler_.cancel(n.recovery_event);
  }
  const SimTime from = std::max(last_dominant_end_, n.recovery_from);
  const NodeTiming t = timing_of(n);
  const SimDuration needed = with_ppm(
      t.nominal.bits_duration(uint64_t{fc.recovery_sequences_left()} * kRecoverySequenceBits),
      t.oscillator_ppm);
  n.recovery_event = scheduler_.schedule_at(from + needed, [this, id](SimTime now) {
    nodes_[id].recovery_event = 0;
    recovery_check(id, now);
  });
}

void CanBus::recovery_check(NodeId id, SimTime now) {
  Node& n = nodes_[id];
  FaultConfinement& fc = n.controller->confinement();
  if (!fc.recovering() || busy_) {
    return;
  }
  const SimTime from = std::max(last_dominant_end_, n.recovery_from);
  const uint64_t bits = bits_in(id, now - from);
  n.recovery_from = now;
  if (fc.recessive_sequences(static_cast<uint32_t>(bits / kRecoverySequenceBits))) {
    recovered(id, now);
    return;
  }
  arm_recovery(id);
}

uint64_t CanBus::bits_in(NodeId id, SimDuration span) {
  // Rounded to the nearest bit: a node whose clock runs a little slow still sees the 11
  // recessive bits between two frames as 11.
  const Node& n = refresh_timing(id);
  const int64_t bit = with_ppm(n.timing.nominal.bits_duration(1), n.timing.oscillator_ppm).ns();
  if (bit <= 0 || span.ns() <= 0) {
    return 0;
  }
  return static_cast<uint64_t>((span.ns() + bit / 2) / bit);
}

// Bus-off recovery completed: both counters are 0 and the node is error-active again.
void CanBus::recovered(NodeId id, SimTime at) {
  Node& n = nodes_[id];
  n.last_state = ErrorState::active;
  n.reported_tec = 0;
  n.reported_rec = 0;
  n.stats.state_changes.push_back(StateChange{at, ErrorState::active});
  CounterSample back = because(CounterCause::recovered);
  back.at = at;
  n.stats.timeline.add(back);
  n.controller->on_state_change(at, ErrorState::active);
  if (!busy_) {
    schedule_attempt(std::max(at, free_at_));
  }
}

void CanBus::report_state(NodeId id, SimTime at, CounterSample why) {
  Node& n = nodes_[id];
  FaultConfinement& fc = *n.fc;
  const bool counted = fc.tec() != n.reported_tec || fc.rec() != n.reported_rec;
  if (!counted && !fc.bus_off()) {
    return;  // nothing counted since the last report
  }
  n.reported_tec = fc.tec();
  n.reported_rec = fc.rec();
  const ErrorState s = fc.state();
  if (counted || s != n.last_state) {
    why.at = at;
    why.tec = static_cast<uint16_t>(fc.tec());
    why.rec = static_cast<uint16_t>(fc.rec());
    why.state = s;
    n.stats.timeline.add(why);
  }
  if (s == n.last_state) {
    return;
  }
  n.last_state = s;
  n.stats.state_changes.push_back(StateChange{at, s});
  if (s == ErrorState::bus_off) {
    forget_tx(n);
    if (refresh(id).recovery == BusOffRecovery::automatic) {
      fc.begin_recovery();
      maybe_recovering_ = true;
      n.recovery_from = at;
    }
  }
  n.controller->on_state_change(at, s);
}

}  // namespace canemu::model
