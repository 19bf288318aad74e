// CanBus: what it keeps of its nodes (their controllers' properties, the member list, bit
// timings and which pairs can decode each other, pending frames and their encodings) and the
// calls that change it.
#include <algorithm>

#include "bus/can_bus_detail.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"

namespace canemu::model {

NodeTiming CanBus::timing_of(const Node& n) const {
  NodeTiming t = n.controller->timing();
  t.oscillator_ppm += n.oscillator_ppm;
  return t;
}

void CanBus::controller_changed(NodeId node) {
  nodes_[node].props_known = false;
  nodes_[node].timing_known = false;
  decodes_cache_.clear();
  members_changed();
  if (!busy_) {
    schedule_attempt(std::max(scheduler_.now(), free_at_));
  }
}

void CanBus::load_props(Node& n) {
  n.participating = n.controller->participating();
  {
    // A controller without a usable bit time cannot take part (its bits would take no time).
    const NodeTiming t = n.controller->timing();
    n.timing_valid = t.nominal.clock_hz != 0 && t.nominal.prescaler != 0 &&
                     (!t.has_data_phase || (t.data.clock_hz != 0 && t.data.prescaler != 0));
  }
  n.listen_only = n.controller->listen_only();
  n.self_test = n.controller->self_test();
  n.fd_capable = n.controller->fd_capable();
  n.recovery = n.controller->bus_off_recovery();
  n.props_known = true;
}

void CanBus::load_members() {
  members_.clear();
  for (NodeId id = 0; id < node_count_; ++id) {
    Node& n = refresh(id);
    if (n.connected && n.participating && n.timing_valid) {
      Member& m = members_.emplace_back();
      m.node = &n;
      m.id = id;
      m.listen_only = n.listen_only;
      m.self_test = n.self_test;
      m.fd_capable = n.fd_capable;
      m.receiver.id = id;
      m.receiver.drives = !n.listen_only;
      m.receiver.self_test = n.self_test;
      m.receiver.acks = m.receiver.drives;
    }
  }
  members_valid_ = true;
}

bool CanBus::decodes_slow(NodeId tx, NodeId rx, bool brs) {
  const std::size_t n = node_count_;
  if (decodes_cache_.size() != 2 * n * n) {
    decodes_cache_.assign(2 * n * n, -1);
  }
  int8_t& c = decodes_cache_[(brs ? n * n : 0) + tx * n + rx];
  if (c < 0) {
    c = check_compatibility(refresh_timing(tx).profile, refresh_timing(rx).profile, brs).ok ? 1 : 0;
  }
  return c == 1;
}

const CanBus::Node& CanBus::load_timing(NodeId id) {
  Node& n = nodes_[id];
  n.timing = timing_of(n);
  n.profile = timing_profile(n.timing);
  const BitTiming& t = n.timing.nominal;
  const uint128 ps = uint128{t.prescaler} * t.quanta_per_bit() * 1'000'000'000u;
  n.bit_ns = n.timing.oscillator_ppm == 0 && t.clock_hz != 0 && ps % t.clock_hz == 0
                 ? static_cast<int64_t>(ps / t.clock_hz)
                 : 0;
  n.timing_known = true;
  return n;
}

void CanBus::load_tx(Node& n) {
  n.tx = n.controller->pending_tx();
  n.tx_known = true;
}

void CanBus::load_encoding(Node& n) {
  // A node that sends again the frame it sent last (a babbling node, a cyclic message whose
  // payload did not change) keeps its encoding: the same frame has the same bits. (The inline
  // identifier check spares most differing frames the call to operator==.)
  const Frame& f = pending(n)->frame;
  if (!n.encoded_frame || n.encoded_frame->id() != f.id() || !(*n.encoded_frame == f)) {
    n.encoded_whole = encode_head(f, n.encoded);
    n.encoded_frame = f;
  }
  n.encoded_valid = true;
}

void CanBus::make_whole(Node& n) {
  encode(*n.encoded_frame, n.encoded);
  n.encoded_whole = true;
}

void CanBus::senders_whole() {
  for (const NodeId id : arbitration_.senders()) {
    whole_encoding(nodes_[id]);
  }
}

void CanBus::set_oscillator_ppm(NodeId node, int32_t ppm) {
  // Beyond +-50 % no clock deserves the name; clamping keeps durations positive.
  nodes_[node].oscillator_ppm = std::clamp<int32_t>(ppm, -500'000, 500'000);
  nodes_[node].timing_known = false;
  decodes_cache_.clear();
  plain_valid_ = false;
}

void CanBus::set_connected(NodeId node, bool connected) {
  nodes_[node].connected = connected;
  members_changed();
  if (connected && !busy_) {
    schedule_attempt(std::max(scheduler_.now(), free_at_));
  }
}

}  // namespace canemu::model
