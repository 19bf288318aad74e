#include "canemu/firmware_model/bus/can_bus.hpp"

#include <algorithm>

#include "bus/can_bus_detail.hpp"

namespace canemu::model {

using detail::because;
using detail::kSuspendBits;
using detail::with_ppm;

uint64_t& ErrorCounts::operator[](CanErrorType t) {
  switch (t) {
    case CanErrorType::bit:
      return bit;
    case CanErrorType::stuff:
      return stuff;
    case CanErrorType::form:
      return form;
    case CanErrorType::crc:
      return crc;
    case CanErrorType::ack:
      return ack;
  }
  return bit;
}

CanBus::CanBus(SimScheduler& scheduler, std::string name)
    : scheduler_(scheduler), name_(std::move(name)) {}

CanBus::~CanBus() = default;

NodeId CanBus::attach(CanController& controller) {
  Node n;
  n.controller = &controller;
  n.fc = &controller.confinement();
  n.last_state = n.fc->state();
  nodes_.push_back(std::move(n));
  node_count_ = nodes_.size();
  completion_.sent.fit(node_count_);
  // The arbitration's lists are read until the bus is free (their room would move): room for
  // the new node is made then, before the next arbitration.
  if (busy_) {
    arbitration_room_due_ = true;
  } else {
    arbitration_.reserve(node_count_);
  }
  // nodes_ may have moved: the receivers of a frame on the wire point into it anew, in place (a
  // controller may attach from a callback while the frame's end walks the list, so its room
  // grows only where the list is filled: plain_roles(), general_roles()).
  for (std::size_t k = 0; k < receivers_.size(); ++k) {
    receivers_[k].node = &nodes_[receivers_[k].id];
  }
  decodes_cache_.clear();
  members_changed();
  const NodeId id = static_cast<NodeId>(node_count_ - 1);
  if (!busy_) {
    schedule_attempt(scheduler_.now());
  }
  return id;
}

bool CanBus::in_flight(NodeId node) const {
  return busy_ && std::find(in_flight_.begin(), in_flight_.end(), node) != in_flight_.end();
}

SimTime CanBus::arbitration_bit_end_slow(uint16_t bit) const {
  const Completion& c = completion_;
  return c.sof + with_ppm(c.nominal.bits_duration(uint64_t{bit} + 1), c.ppm);
}

void CanBus::report_losses() {
  // The list's room stays while the bus is busy (attach()); a node is looked up again after a
  // controller's call, which may attach a node and move them.
  for (const Arbitration::AtBit& loss : arbitration_.lost()) {
    const SimTime at = arbitration_bit_end(loss.bit);
    nodes_[loss.node].controller->on_arbitration_lost(at, loss.bit, loss.destuffed_bit);
    if (loss.single_shot && still_pending(nodes_[loss.node])) {
      Node& n = nodes_[loss.node];
      n.stats.tx_dropped++;
      forget_tx(n);
      n.controller->on_tx_dropped(at);
    }
  }
  arbitration_.forget_lost();
}

bool CanBus::still_pending(Node& n) {
  if (n.tx_known) {
    return true;  // the controller has not changed its pending frame since the frame's start
  }
  // It has (tx_changed): an abort, a new frame, or only a look again at the same one. The frame
  // that lost is the one its encoding was made of, which only the next arbitration replaces.
  const TxFrame* p = pending(n);
  if (p == nullptr || !p->single_shot || !n.encoded_frame) {
    return false;
  }
  // A CAN FD controller sets ESI to its error state whenever it offers the frame: with the other
  // ESI it is still the frame that lost.
  return p->frame == n.encoded_frame->with_esi(p->frame.esi());
}

void CanBus::tx_changed(NodeId node) {
  forget_tx(nodes_[node]);
  if (!busy_) {
    schedule_attempt(std::max(scheduler_.now(), free_at_));
  }
}

void CanBus::restart(NodeId node) {
  Node& n = nodes_[node];
  FaultConfinement& fc = n.controller->confinement();
  if (!fc.bus_off() || fc.recovering()) {
    return;
  }
  fc.begin_recovery();
  maybe_recovering_ = true;
  n.recovery_from = std::max(scheduler_.now(), busy_ ? free_at_ : scheduler_.now());
  arm_recovery(node);
}

void CanBus::counters_changed(NodeId node) {
  Node& n = nodes_[node];
  n.reported_tec = static_cast<uint16_t>(~n.fc->tec());  // force a fresh report
  report_state(node, scheduler_.now(), because(CounterCause::written));
  if (!n.fc->bus_off() && n.last_state != ErrorState::bus_off && !busy_) {
    schedule_attempt(std::max(scheduler_.now(), free_at_));
  }
}

void CanBus::schedule_attempt(SimTime at) {
  at = std::max(at, scheduler_.now());
  if (attempt_pending_) {
    if (at >= attempt_at_) {
      return;
    }
    scheduler_.cancel(attempt_event_);  // an earlier request: look for transmitters sooner
  }
  attempt_pending_ = true;
  attempt_at_ = at;
  attempt_event_ = scheduler_.schedule_at(at, *this, kAttempt);
}

void CanBus::on_event(SimTime now, uint64_t tag) {
  const bool outer = handling_;
  handling_ = true;
  for (;;) {
    switch (tag) {
      case kAttempt:
        attempt_pending_ = false;
        attempt(now);
        break;
      case kFrameEnd:
        complete_success(now);
        break;
      case kBusFree:
        bus_released(completion_.last_dominant_end, completion_.ifs_end);
        break;
      default:
        break;
    }
    if (follow_tag_ == 0) {
      break;
    }
    tag = follow_tag_;
    follow_tag_ = 0;
    if (!scheduler_.run_inline(follow_at_)) {
      scheduler_.schedule_at(follow_at_, *this, tag);
      break;
    }
    now = follow_at_;
  }
  handling_ = outer;
}

void CanBus::attempt(SimTime now) {
  if (busy_ || now < free_at_) {
    if (!busy_) {
      schedule_attempt(free_at_);
    }
    return;
  }
  // Holds that are over are forgotten; one that began while the bus was busy starts now. (Most
  // buses never have one: the empty list is not walked.)
  if (!holds_.empty()) {
    std::erase_if(holds_, [&](const auto& h) { return h.first + h.second <= now; });
    for (const auto& [from, duration] : holds_) {
      if (from <= now && now < from + duration) {
        run_hold(now);
        return;
      }
    }
  }
  if (injector_ != nullptr) {
    injector_->before_arbitration(now, *this);
  }
  Arbitration& arbitration = arbitration_;
  arbitration.begin();
  std::optional<SimTime> next_ready;
  for (const Member& m : members()) {
    Node& n = *m.node;
    if (n.fc->bus_off() || m.listen_only || pending(n) == nullptr) {
      continue;
    }
    if (n.ready_at > now) {
      next_ready = next_ready ? std::min(*next_ready, n.ready_at) : n.ready_at;
      continue;
    }
    if (!n.encoded_valid) {
      load_encoding(n);
    }
    arbitration.add(Arbitration::Contender{m.id, &n.encoded, n.tx->single_shot});
  }
  if (arbitration.empty()) {
    if (next_ready) {
      schedule_attempt(*next_ready);
    }
    return;
  }
  run_frame(now);
}

void CanBus::run_frame(SimTime sof) {
  busy_ = true;
  account_recessive(sof);

  if (!arbitration_.resolve_in_first_word()) {
    // The long walk compares whole frames.
    for (const Arbitration::Contender& c : arbitration_.contenders()) {
      whole_encoding(nodes_[c.node]);
    }
    arbitration_.resolve_walk();
  }
  const std::vector<NodeId>& active = arbitration_.senders();
  const NodeId tx = active.front();
  in_flight_ = active;  // the arbitration's list stays as it is until the bus is free again
  // The winner contended: its pending frame and encoding are known (attempt()).
  const TxFrame& tx_frame = *nodes_[tx].tx;
  const EncodedFrame& e = nodes_[tx].encoded;
  const Node& tx_node = refresh_timing(tx);
  const NodeTiming& tx_timing = tx_node.timing;
  const BitTiming& nominal = tx_timing.nominal;
  const BitTiming& data = tx_timing.has_data_phase ? tx_timing.data : tx_timing.nominal;
  const int64_t tx_bit_ns = tx_node.bit_ns;
  Completion& c = completion_;
  c.sof = sof;
  c.nominal = nominal;
  c.ppm = tx_timing.oscillator_ppm;
  c.bit_ns = tx_bit_ns;
  auto bit_end = [&](uint32_t bit) {
    if (tx_bit_ns != 0 && (!e.brs || bit < e.brs_index)) {
      return sof + SimDuration(tx_bit_ns * (int64_t{bit} + 1));
    }
    return sof +
           with_ppm(frame_prefix_duration(e, nominal, data, bit + 1), tx_timing.oscillator_ppm);
  };

  // Everybody on the bus takes part: the transmitters, and every other node as a receiver.
  FrameFault fault;
  if (injector_ != nullptr && injector_->frames_wanted()) {
    fault = injector_->on_frame(FrameContext{sof, tx, tx_frame.frame, whole_encoding(nodes_[tx])});
  }
  const bool alone = active.size() == 1;
  const bool acks_suppressed = sof < ack_suppressed_until_;
  std::optional<uint16_t> first_bit;
  if (alone && !fault.error && !fault.suppress_ack && !acks_suppressed) {
    const bool fd = tx_frame.frame.fd();
    const bool brs = tx_frame.frame.brs();
    first_bit = plain_roles_kept(tx, fd, brs) ? std::nullopt : plain_roles(tx, e, fd, brs);
  } else {
    first_bit = general_roles(tx, e, fault, acks_suppressed);
  }

  // A dominant hold that overlaps the frame disturbs it.
  const SimTime frame_end = holds_.empty() ? sof : bit_end(e.length - 1u);
  for (const auto& [from, duration] : holds_) {
    if (from < frame_end && from + duration > sof) {
      // First bit whose end lies after the hold's start.
      uint16_t k = 0;
      while (k + 1u < e.length && bit_end(k) <= from) {
        ++k;
      }
      first_bit = first_bit ? std::min(*first_bit, k) : k;
    }
  }
  if (!first_bit) {
    // The losers' statistics count from the frame's start, their reports come at its end.
    for (const Arbitration::AtBit& loss : arbitration_.lost()) {
      nodes_[loss.node].stats.arbitration_lost++;
    }
    finish_success(sof, tx, nominal, data);
    return;
  }
  join_late_contenders(tx, fault, acks_suppressed, *first_bit);
  if (!arbitration_.lost().empty()) {
    SimTime latest = sof;
    for (const Arbitration::AtBit& loss : arbitration_.lost()) {
      latest = std::max(latest, arbitration_bit_end(loss.bit));
    }
    scheduler_.schedule_at(latest, [this](SimTime) { report_losses(); });
  }
  senders_whole();  // the error phase reads their bits (parts_ and `e` point at them)
  run_error_phase(sof, parts_, &e, nominal, data, *first_bit);
}

std::optional<uint16_t> CanBus::general_roles(NodeId tx, const EncodedFrame& e,
                                              const FrameFault& fault, bool acks_suppressed) {
  const std::span<const NodeId> active = in_flight_;  // (join_late_contenders: and more)
  const Frame& frame = pending(nodes_[tx])->frame;
  const FrameRoles roles(e, fault, acks_suppressed);
  std::vector<BusParticipant>& parts = parts_;
  parts.clear();
  receivers_.clear();
  receivers_.fit(node_count_);
  plain_valid_ = false;
  const bool alone = active.size() == 1;
  for (NodeId id = 0; id < node_count_; ++id) {
    Node& n = refresh(id);
    if (!on_bus(n)) {
      continue;
    }
    const NodeFacts facts{id, n.listen_only, n.fc->error_passive(), n.self_test};
    BusParticipant& p = parts.emplace_back();
    if (alone ? id == tx : std::find(active.begin(), active.end(), id) != active.end()) {
      p = roles.sender(facts, encoded_tx(id), alone ? std::nullopt : arbitration_.collision_of(id));
    } else if (frame.fd() && !n.fd_capable) {
      p = roles.receiver(facts, FrameRoles::Decoding::not_fd);
    } else {
      p = roles.receiver(facts, decodes(tx, id, frame.brs()) ? FrameRoles::Decoding::ok
                                                             : FrameRoles::Decoding::timing);
    }
    if (!p.transmitter && p.decodes) {
      receivers_.push_back(Receiver{&n, id, p.acks});
    }
  }
  return roles.first_detection(parts);
}

std::optional<uint16_t> CanBus::plain_roles(NodeId tx, const EncodedFrame& e, bool fd, bool brs) {
  const std::vector<Member>& ms = members();
  plain_valid_ = false;
  std::vector<BusParticipant>& parts = parts_;
  parts.clear();
  receivers_.clear();
  receivers_.fit(node_count_);
  // FrameRoles without a fault: the sender plans nothing; a receiver that cannot follow the
  // frame plans its error (and does not acknowledge), one that can acknowledges if it drives.
  uint16_t first = UINT16_MAX;
  bool acked = false;
  const int8_t* row = decodes_row(tx, brs);
  for (const Member& m : ms) {
    const FaultConfinement& fc = *m.node->fc;
    if (fc.bus_off()) {
      continue;
    }
    BusParticipant& p = parts.emplace_back(m.receiver);
    p.passive = fc.error_passive();
    if (m.id == tx) {
      p.transmitter = true;
      p.acks = false;
      p.bits = &e;
      acked = acked || m.self_test;
      continue;
    }
    bool decodes = false;
    if (fd && !m.fd_capable) {
      const auto bit = static_cast<uint16_t>(e.field_begin(Field::fdf) + 1);
      p.planned = std::make_pair(CanErrorType::form, bit);
      first = std::min(first, bit);
    } else if (row != nullptr && row[m.id] >= 0) {
      decodes = row[m.id] == 1;
    } else {
      decodes = decodes_slow(tx, m.id, brs);
      row = decodes_row(tx, brs);
    }
    if (!decodes && !p.planned) {
      p.planned = std::make_pair(CanErrorType::stuff, e.arbitration_end);
      first = std::min(first, e.arbitration_end);
    }
    p.decodes = decodes;
    p.acks = decodes && p.drives;
    acked = acked || p.acks;
    if (decodes) {
      receivers_.push_back(Receiver{m.node, m.id, p.acks});
    }
  }
  if (!acked) {
    first = std::min(first, static_cast<uint16_t>(e.crc_delimiter_index + 1));
  }
  if (first == UINT16_MAX) {
    // Nothing here depends on the frame beyond its sender, fd and brs: kept for the next one.
    plain_checks_.clear();
    plain_changes_ = 0;
    for (const Member& m : ms) {
      plain_checks_.push_back(m.node->fc);
      plain_changes_ += m.node->fc->passive_or_off_changes();
    }
    plain_valid_ = true;
    plain_tx_ = tx;
    plain_fd_ = fd;
    plain_brs_ = brs;
    return std::nullopt;
  }
  return first;
}

void CanBus::finish_success(SimTime sof, NodeId tx, const BitTiming& nominal,
                            const BitTiming& data) {
  const EncodedFrame& e = encoded_tx(tx);
  Completion& c = completion_;
  const int64_t bit_ns = c.bit_ns;
  if (bit_ns != 0 && !e.brs) {
    c.eof_end = sof + SimDuration(bit_ns * e.length);
    c.ifs_end = c.eof_end + SimDuration(bit_ns * kIntermissionBits);
    c.last_dominant_end = c.eof_end - SimDuration(bit_ns * (1 + kEofBits));
  } else {
    c.eof_end = sof + with_ppm(frame_duration(e, nominal, data), c.ppm);
    // The last dominant bit is the ACK slot; then ACK delimiter, EOF and intermission.
    c.ifs_end = c.eof_end + with_ppm(intermission_duration(nominal), c.ppm);
    c.last_dominant_end = c.eof_end - with_ppm(nominal.bits_duration(1 + kEofBits), c.ppm);
  }
  c.sent.clear();
  for (NodeId id : in_flight_) {
    c.sent.push_back(pending(nodes_[id]));
  }
  frames_on_bus_++;
  bus_load_.record(sof, c.ifs_end);
  if (on_bus_event) {
    on_bus_event(BusEvent{BusEvent::Kind::frame, sof, c.eof_end, tx, c.sent[0]->frame, 0});
  }
  follow_up(c.eof_end, kFrameEnd);
}

void CanBus::complete_success(SimTime eof_end) {
  Completion& c = completion_;
  report_losses();
  // Receivers first: the frame they get is the transmitter's, which it may drop once told.
  const Frame& frame = c.sent[0]->frame;
  for (const Receiver& r : receivers_) {
    Node& n = *r.node;
    if (r.acks && n.fc->rec() > 0) {
      n.fc->receive_succeeded();
      report_state(r.id, eof_end);
    }
    n.stats.frames_received++;
    n.controller->on_frame(eof_end, frame, false);
  }
  for (std::size_t k = 0; k < in_flight_.size(); ++k) {
    const NodeId id = in_flight_[k];
    Node& n = nodes_[id];
    FaultConfinement& fc = *n.fc;
    const bool was_passive = fc.error_passive();
    fc.transmit_succeeded();
    n.stats.frames_sent++;
    forget_tx(n);
    // An error-passive transmitter waits 8 more bits after the intermission (suspend
    // transmission) before it may start again.
    n.ready_at = was_passive ? c.ifs_end + with_ppm(c.nominal.bits_duration(kSuspendBits), c.ppm)
                             : c.ifs_end;
    if (c.sent[k]->self_reception) {
      n.stats.frames_received++;
      n.controller->on_frame(eof_end, c.sent[k]->frame, true);
    }
    n.controller->on_tx_done(eof_end);
    report_if_changed(id, eof_end);
  }
  follow_up(c.ifs_end, kBusFree);
}

void CanBus::bus_released(SimTime last_dominant_end, SimTime idle_at) {
  busy_ = false;
  if (arbitration_room_due_) {
    arbitration_room_due_ = false;
    arbitration_.reserve(node_count_);
  }
  in_flight_ = {};
  free_at_ = idle_at;
  last_dominant_end_ = last_dominant_end;
  if (maybe_recovering_) {
    for (NodeId id = 0; id < node_count_; ++id) {
      if (nodes_[id].fc->recovering()) {
        arm_recovery(id);
      }
    }
  }
  if (idle_at <= scheduler_.now() && !attempt_pending_) {
    attempt(scheduler_.now());
  } else {
    schedule_attempt(idle_at);
  }
}

bool withdraw_tx(CanBus* bus, NodeId node, std::optional<TxFrame>& tx) {
  if (!tx) {
    return false;
  }
  if (bus != nullptr && bus->in_flight(node)) {
    tx->single_shot = true;
    return false;
  }
  tx.reset();
  if (bus != nullptr) {
    bus->tx_changed(node);
  }
  return true;
}

void CounterTimeline::add(const CounterSample& s) {
  // Every change, count-downs by good frames too: a run of them kept as its ends only would be
  // drawn as a flat line and a cliff (TEC held at 127 for the whole run, then 96).
  if (samples_.size() == kSamples) {
    samples_.pop_front();
    ++forgotten_;
  }
  samples_.push_back(s);
}

}  // namespace canemu::model
