#include "canemu/firmware_model/bus/can_bus.hpp"

#include <algorithm>
#include <cassert>
#include <tuple>

namespace canemu::model {

namespace {

constexpr uint32_t kErrorFlagBits = 6;
constexpr uint32_t kErrorDelimiterBits = 8;
constexpr uint32_t kSuspendBits = 8;
constexpr uint32_t kMaxHeldBits = 1'000'000;

// A duration measured by a node whose oscillator runs `ppm` fast takes proportionally less time.
SimDuration with_ppm(SimDuration d, int32_t ppm) {
  if (ppm == 0) {
    return d;
  }
  const int64_t den = 1'000'000 + ppm;
  return SimDuration((d.ns() * 1'000'000 + den / 2) / den);
}

uint16_t stuffed_end(const EncodedFrame& e) {
  return e.fd ? e.field_begin(Field::stuff_count) : e.crc_delimiter_index;
}

// Default positions of injected errors, clamped to where such an error can be detected.
uint16_t place_injected(const EncodedFrame& e, CanErrorType type, std::optional<uint16_t> bit) {
  const uint16_t ack_slot = static_cast<uint16_t>(e.crc_delimiter_index + 1);
  switch (type) {
    case CanErrorType::bit:
      return std::clamp<uint16_t>(bit.value_or(e.arbitration_end), e.arbitration_end,
                                  static_cast<uint16_t>(e.length - 2));
    case CanErrorType::stuff:
      return std::clamp<uint16_t>(bit.value_or(e.arbitration_end), e.arbitration_end,
                                  static_cast<uint16_t>(stuffed_end(e) - 1));
    case CanErrorType::form: {
      // Fixed-form bits: CRC delimiter, ACK delimiter, EOF but its last bit.
      const uint16_t k = bit.value_or(e.crc_delimiter_index);
      if (k == e.crc_delimiter_index || (k > ack_slot && k + 1 < e.length)) {
        return k;
      }
      return e.crc_delimiter_index;
    }
    case CanErrorType::crc:
      return static_cast<uint16_t>(ack_slot + 1);  // flagged after the ACK delimiter
    case CanErrorType::ack:
      return ack_slot;
  }
  return e.arbitration_end;
}

}  // namespace

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

// One node's part in one bus activity.
struct CanBus::Participant {
  NodeId id = 0;
  bool transmitter = false;
  bool drives = true;   // false for listen-only nodes
  bool decodes = true;  // timing and format let it follow the frame
  bool acks = false;
  bool passive = false;  // error-passive when the activity started: its flags are recessive
  bool self_test = false;
  const EncodedFrame* bits = nullptr;                        // what it sends (transmitters)
  std::optional<std::pair<CanErrorType, uint16_t>> planned;  // detection it will make
};

CanBus::CanBus(SimScheduler& scheduler, std::string name)
    : scheduler_(scheduler), name_(std::move(name)) {}

CanBus::~CanBus() = default;

NodeId CanBus::attach(CanController& controller) {
  Node n;
  n.controller = &controller;
  n.fc = &controller.confinement();
  n.last_state = n.fc->state();
  nodes_.push_back(std::move(n));
  decodes_cache_.clear();
  const NodeId id = static_cast<NodeId>(nodes_.size() - 1);
  if (!busy_) {
    schedule_attempt(scheduler_.now());
  }
  return id;
}

NodeTiming CanBus::timing_of(const Node& n) const {
  NodeTiming t = n.controller->timing();
  t.oscillator_ppm += n.oscillator_ppm;
  return t;
}

bool CanBus::in_flight(NodeId node) const {
  return busy_ && std::find(in_flight_.begin(), in_flight_.end(), node) != in_flight_.end();
}

void CanBus::controller_changed(NodeId node) {
  nodes_[node].props_known = false;
  nodes_[node].timing_known = false;
  decodes_cache_.clear();
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

bool CanBus::decodes_slow(NodeId tx, NodeId rx, bool brs) {
  const std::size_t n = nodes_.size();
  if (decodes_cache_.size() != 2 * n * n) {
    decodes_cache_.assign(2 * n * n, -1);
  }
  int8_t& c = decodes_cache_[(brs ? n * n : 0) + tx * n + rx];
  if (c < 0) {
    c = check_compatibility(refresh_timing(tx).profile, refresh_timing(rx).profile, brs).ok ? 1 : 0;
  }
  return c == 1;
}

const CanBus::Node& CanBus::refresh_timing(NodeId id) {
  Node& n = nodes_[id];
  if (!n.timing_known) {
    n.timing = timing_of(n);
    n.profile = timing_profile(n.timing);
    const BitTiming& t = n.timing.nominal;
    const uint128 ps = uint128{t.prescaler} * t.quanta_per_bit() * 1'000'000'000u;
    n.bit_ns = n.timing.oscillator_ppm == 0 && t.clock_hz != 0 && ps % t.clock_hz == 0
                   ? static_cast<int64_t>(ps / t.clock_hz)
                   : 0;
    n.timing_known = true;
  }
  return n;
}

void CanBus::report_losses() {
  for (const Completion::Loss& loss : completion_.losses) {
    Node& n = nodes_[loss.node];
    const SimTime at = loss.at;
    n.controller->on_arbitration_lost(at, loss.bit, loss.destuffed_bit);
    if (loss.single_shot) {
      n.stats.tx_dropped++;
      forget_tx(n);
      n.controller->on_tx_dropped(at);
    }
  }
  completion_.losses.clear();
}

void CanBus::load_tx(Node& n) {
  n.tx = n.controller->pending_tx();
  n.tx_known = true;
}

void CanBus::load_encoding(Node& n) {
  encode(pending(n)->frame, n.encoded);
  n.encoded_valid = true;
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
  report_state(node, scheduler_.now());
  if (!n.fc->bus_off() && n.last_state != ErrorState::bus_off && !busy_) {
    schedule_attempt(std::max(scheduler_.now(), free_at_));
  }
}

void CanBus::set_oscillator_ppm(NodeId node, int32_t ppm) {
  // Beyond +-50 % no clock deserves the name; clamping keeps durations positive.
  nodes_[node].oscillator_ppm = std::clamp<int32_t>(ppm, -500'000, 500'000);
  nodes_[node].timing_known = false;
  decodes_cache_.clear();
}

void CanBus::set_connected(NodeId node, bool connected) {
  nodes_[node].connected = connected;
  if (connected && !busy_) {
    schedule_attempt(std::max(scheduler_.now(), free_at_));
  }
}

void CanBus::hold_dominant(SimTime from, SimDuration duration) {
  if (duration.ns() <= 0) {
    return;
  }
  holds_.emplace_back(from, duration);
  scheduler_.schedule_at(from, [this](SimTime now) {
    if (!busy_) {
      run_hold(now);
    }
    // A hold that starts during a frame is seen by that frame's error simulation only if it was
    // known at its start of frame; otherwise it takes effect when the bus is next free.
  });
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
}

void CanBus::attempt(SimTime now) {
  if (busy_ || now < free_at_) {
    if (!busy_) {
      schedule_attempt(free_at_);
    }
    return;
  }
  // Holds that are over are forgotten; one that began while the bus was busy starts now.
  std::erase_if(holds_, [&](const auto& h) { return h.first + h.second <= now; });
  for (const auto& [from, duration] : holds_) {
    if (from <= now && now < from + duration) {
      run_hold(now);
      return;
    }
  }
  if (injector_ != nullptr) {
    injector_->before_arbitration(now, *this);
  }
  std::vector<NodeId>& contenders = contenders_;
  contenders.clear();
  std::optional<SimTime> next_ready;
  for (NodeId id = 0; id < nodes_.size(); ++id) {
    Node& n = refresh(id);
    if (!can_transmit(n)) {
      continue;
    }
    if (n.ready_at > now) {
      next_ready = next_ready ? std::min(*next_ready, n.ready_at) : n.ready_at;
      continue;
    }
    contenders.push_back(id);
  }
  if (contenders.empty()) {
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

  // Arbitration. The wired-AND makes the bus carry the lexicographically smallest of the
  // contenders' bit sequences (dominant, 0, wins every comparison), so each contender drops out
  // at its first difference from the winner's: inside its arbitration field that is a lost
  // arbitration, after it a collision (a bit error, which the error simulation plays out).
  std::vector<NodeId>& active = active_;
  std::vector<std::pair<NodeId, uint16_t>>& lost = lost_;
  std::vector<std::pair<NodeId, uint16_t>>& collisions = collisions_;
  active.clear();
  lost.clear();
  collisions.clear();
  NodeId winner = contenders_.front();
  const EncodedFrame* best = &encoded_tx(winner);
  for (std::size_t k = 1; k < contenders_.size(); ++k) {
    const NodeId c = contenders_[k];
    const EncodedFrame& ec = encoded_tx(c);
    // First bit first: comparing words as numbers is comparing bit sequences. (Bits past the
    // end of a frame only count when two frames are equal up to there, that is, identical.)
    std::size_t w = 0;
    while (w + 1 < ec.level.size() && ec.level[w] == best->level[w]) {
      ++w;
    }
    if (ec.level[w] < best->level[w]) {
      winner = c;
      best = &ec;
    }
  }
  active.push_back(winner);
  for (NodeId c : contenders_) {
    if (c == winner) {
      continue;
    }
    const EncodedFrame& ec = encoded_tx(c);
    const auto d = first_difference(ec, *best);
    if (!d) {
      active.push_back(c);  // the same frame: sent together
    } else if (*d < ec.arbitration_end) {
      lost.emplace_back(c, *d);
    } else {
      active.push_back(c);
      collisions.emplace_back(c, *d);
    }
  }

  const NodeId tx = active.front();
  in_flight_.assign(active.begin(), active.end());
  const TxFrame& tx_frame = *pending(nodes_[tx]);
  const EncodedFrame& e = encoded_tx(tx);
  const Node& tx_node = refresh_timing(tx);
  const NodeTiming& tx_timing = tx_node.timing;
  const BitTiming& nominal = tx_timing.nominal;
  const BitTiming& data = tx_timing.has_data_phase ? tx_timing.data : tx_timing.nominal;
  const int64_t tx_bit_ns = tx_node.bit_ns;
  auto bit_end = [&](uint32_t bit) {
    if (tx_bit_ns != 0 && (!e.brs || bit < e.brs_index)) {
      return sof + SimDuration(tx_bit_ns * (int64_t{bit} + 1));
    }
    return sof +
           with_ppm(frame_prefix_duration(e, nominal, data, bit + 1), tx_timing.oscillator_ppm);
  };

  completion_.losses.clear();
  for (const auto& [id, bit] : lost) {
    Node& n = nodes_[id];
    completion_.losses.push_back(Completion::Loss{id, bit, encoded_tx(id).destuffed_index(bit),
                                                  bit_end(bit), pending(n)->single_shot});
    n.stats.arbitration_lost++;
  }

  // Everybody on the bus takes part: the transmitters, and every other node as a receiver.
  FrameFault fault;
  if (injector_ != nullptr) {
    fault = injector_->on_frame(FrameContext{sof, tx, tx_frame.frame, e});
  }
  const bool acks_suppressed = fault.suppress_ack || sof < ack_suppressed_until_ ||
                               (fault.error && *fault.error == CanErrorType::ack);
  std::vector<Participant>& parts = parts_;
  parts.resize(nodes_.size());
  std::size_t count = 0;
  bool any_ack = false;
  bool any_planned = !collisions.empty();
  for (NodeId id = 0; id < nodes_.size(); ++id) {
    Node& n = refresh(id);
    if (!on_bus(n)) {
      continue;
    }
    Participant& p = parts[count++];
    p = Participant{};
    p.id = id;
    p.transmitter = std::find(active.begin(), active.end(), id) != active.end();
    p.drives = !n.listen_only;
    p.passive = n.fc->error_passive();
    p.self_test = n.self_test;
    if (p.transmitter) {
      p.bits = &encoded_tx(id);
      const auto c = std::find_if(collisions.begin(), collisions.end(),
                                  [&](auto& x) { return x.first == id; });
      if (c != collisions.end()) {
        p.planned = std::make_pair(CanErrorType::bit, c->second);
      } else if (fault.error && *fault.error == CanErrorType::bit) {
        p.planned =
            std::make_pair(CanErrorType::bit, place_injected(e, CanErrorType::bit, fault.bit));
      }
    } else {
      if (tx_frame.frame.fd() && !n.fd_capable) {
        p.decodes = false;
        p.planned = std::make_pair(CanErrorType::form,
                                   static_cast<uint16_t>(e.field_begin(Field::fdf) + 1));
      } else if (!decodes(tx, id, tx_frame.frame.brs())) {
        p.decodes = false;
        p.planned = std::make_pair(CanErrorType::stuff, e.arbitration_end);
      } else if (fault.error && *fault.error != CanErrorType::bit &&
                 *fault.error != CanErrorType::ack) {
        p.planned = std::make_pair(*fault.error, place_injected(e, *fault.error, fault.bit));
      }
      p.acks = p.decodes && p.drives && !acks_suppressed &&
               !(p.planned && p.planned->first == CanErrorType::crc);
      any_ack = any_ack || p.acks;
    }
    any_planned = any_planned || p.planned.has_value();
  }
  parts.resize(count);

  // A dominant hold that overlaps the frame disturbs it.
  std::optional<uint16_t> first_bit;
  for (const auto& p : parts) {
    if (p.planned) {
      first_bit = first_bit ? std::min(*first_bit, p.planned->second) : p.planned->second;
    }
  }
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
  const bool self_test = std::any_of(parts.begin(), parts.end(), [](const Participant& p) {
    return p.transmitter && p.self_test;
  });
  if (!any_ack && !self_test) {
    const uint16_t ack_slot = static_cast<uint16_t>(e.crc_delimiter_index + 1);
    first_bit = first_bit ? std::min(*first_bit, ack_slot) : ack_slot;
  }
  if (!first_bit && !any_planned) {
    finish_success(sof, tx, nominal, data);
    return;
  }
  if (!completion_.losses.empty()) {
    SimTime latest = sof;
    for (const auto& loss : completion_.losses) {
      latest = std::max(latest, loss.at);
    }
    scheduler_.schedule_at(latest, [this](SimTime) { report_losses(); });
  }
  run_error_phase(sof, parts, &e, nominal, data, first_bit.value_or(e.crc_delimiter_index));
}

void CanBus::finish_success(SimTime sof, NodeId tx, const BitTiming& nominal,
                            const BitTiming& data) {
  const EncodedFrame& e = encoded_tx(tx);
  Completion& c = completion_;
  c.ppm = nodes_[tx].timing.oscillator_ppm;
  c.nominal = nominal;
  const int64_t bit_ns = nodes_[tx].bit_ns;
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
  record_busy(sof, c.ifs_end);
  if (on_bus_event) {
    on_bus_event(BusEvent{BusEvent::Kind::frame, sof, c.eof_end, tx, c.sent.front()->frame, 0});
  }
  scheduler_.schedule_at(c.eof_end, *this, kFrameEnd);
}

void CanBus::complete_success(SimTime eof_end) {
  Completion& c = completion_;
  report_losses();
  // Receivers first: the frame they get is the transmitter's, which it may drop once told.
  const Frame& frame = c.sent.front()->frame;
  for (const Participant& p : parts_) {
    if (p.transmitter || !p.decodes) {
      continue;
    }
    Node& n = nodes_[p.id];
    if (p.acks && n.fc->rec() > 0) {
      n.fc->receive_succeeded();
      report_state(p.id, eof_end);
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
    report_state(id, eof_end);
  }
  scheduler_.schedule_at(c.ifs_end, *this, kBusFree);
}

void CanBus::run_hold(SimTime now) {
  busy_ = true;
  in_flight_.clear();
  account_recessive(now);
  std::vector<Participant> parts;
  BitTiming nominal;
  bool have_timing = false;
  for (NodeId id = 0; id < nodes_.size(); ++id) {
    Node& n = refresh(id);
    if (!on_bus(n)) {
      continue;
    }
    Participant p;
    p.id = id;
    p.drives = !n.listen_only;
    p.passive = n.fc->error_passive();
    parts.push_back(p);
    if (!have_timing) {
      nominal = timing_of(n).nominal;
      have_timing = true;
    }
  }
  if (!have_timing) {
    // Nobody to see it: the bus is simply unusable until the hold ends.
    SimTime end = now;
    for (const auto& [from, duration] : holds_) {
      if (from <= now && now < from + duration) {
        end = std::max(end, from + duration);
      }
    }
    scheduler_.schedule_at(end, [this, end](SimTime) { bus_released(end, end); });
    return;
  }
  run_error_phase(now, parts, nullptr, nominal, nominal, 0);
}

void CanBus::run_error_phase(SimTime sof, std::vector<Participant>& parts, const EncodedFrame* e,
                             const BitTiming& nominal, const BitTiming& data, uint16_t first_bit) {
  // Bit times: the frame's own (with its rate switch) up to the first detection, then the
  // nominal rate: error flags and delimiters always run at the nominal rate.
  const SimTime error_start =
      e != nullptr ? sof + frame_prefix_duration(*e, nominal, data, first_bit) : sof;
  const SimDuration bit_time = nominal.bits_duration(1);
  auto bit_end = [&](uint32_t i) {
    if (e != nullptr && i < first_bit) {
      return sof + frame_prefix_duration(*e, nominal, data, i + 1);
    }
    return error_start + SimDuration(bit_time.ns() * (int64_t{i} - first_bit + 1));
  };
  auto held = [&](uint32_t i) {
    const SimTime end = bit_end(i);
    const SimTime start = end - (e != nullptr && i < first_bit ? SimDuration(0) : bit_time);
    for (const auto& [from, duration] : holds_) {
      if (from < end && from + duration > start) {
        return true;
      }
    }
    return false;
  };

  enum class Phase : uint8_t { frame, flag, wait_recessive, delimiter, done };
  struct State {
    Phase phase = Phase::frame;
    bool is_tx = false;
    uint32_t flag_start = 0;
    uint32_t flag_end = 0;   // last bit of the flag
    uint32_t equal_run = 0;  // passive flag: equal bits seen since the flag started
    bool equal_level = true;
    uint32_t dominant_run = 0;  // consecutive dominant bits (rule 6)
    uint32_t delimiter = 0;
    bool passive_ack_pending = false;  // ACK-error exception still possible
    bool validated = false;
    bool detected = false;
    uint32_t done_at = 0;
  };
  std::vector<State> st(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    st[k].is_tx = parts[k].transmitter;
  }

  // Timed actions, applied in order when their instant comes.
  struct Action {
    SimTime at;
    NodeId node;
    enum class Kind : uint8_t { error, severe, arbitration_lost, tx_ok, rx_ok } kind;
    CanErrorType type = CanErrorType::bit;
    ErrorRole role = ErrorRole::receiver;
    uint16_t bit = 0;
    bool count = true;  // apply the counter change of the rule
    bool in_frame = true;
    Field field = Field::sof;
    uint16_t destuffed_bit = 0;
    bool extended = false;
  };
  std::vector<Action> actions;

  const uint16_t length = e != nullptr ? e->length : 0;
  const uint16_t ack_slot = e != nullptr ? static_cast<uint16_t>(e->crc_delimiter_index + 1) : 0;
  const uint16_t stuff_end = e != nullptr ? stuffed_end(*e) : UINT16_MAX;

  // The bus before the first detection is the frame as sent, with the ACK if anybody gives it.
  bool any_ack = false;
  for (const auto& p : parts) {
    any_ack = any_ack || p.acks;
  }
  auto frame_bit = [&](uint32_t i) {
    if (e == nullptr || i >= length) {
      return true;
    }
    if (i == ack_slot) {
      return !any_ack;
    }
    return e->level_at(i);
  };
  bool last_level = true;
  uint32_t run = 0;
  for (uint32_t i = 0; i < first_bit; ++i) {
    const bool b = frame_bit(i);
    run = b == last_level ? run + 1 : 1;
    last_level = b;
  }

  auto detect = [&](std::size_t k, uint32_t i, CanErrorType type, bool count) {
    State& s = st[k];
    const Participant& p = parts[k];
    s.detected = true;
    s.phase = Phase::flag;
    s.flag_start = i + 1;
    s.equal_run = 0;
    s.dominant_run = 0;
    const bool passive_ack = s.is_tx && p.passive && type == CanErrorType::ack;
    s.passive_ack_pending = passive_ack;
    const EncodedFrame* seen = s.is_tx && p.bits != nullptr ? p.bits : e;
    const bool inside = seen != nullptr && i < seen->length;
    actions.push_back(Action{
        bit_end(i), p.id, Action::Kind::error, type,
        s.is_tx ? ErrorRole::transmitter : ErrorRole::receiver, static_cast<uint16_t>(i),
        count && p.drives && !passive_ack, e != nullptr, inside ? seen->field_at(i) : Field::eof,
        inside ? seen->destuffed_index(static_cast<uint16_t>(i)) : static_cast<uint16_t>(i),
        seen != nullptr && seen->field_begin(Field::srr) < seen->length});
  };

  const uint32_t max_bits = 4096 + static_cast<uint32_t>(length);
  uint32_t last_dominant = first_bit;  // last bit the bus was dominant
  uint32_t i = first_bit;
  for (;; ++i) {
    // What each node drives.
    bool bus = true;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const State& s = st[k];
      const Participant& p = parts[k];
      if (!p.drives) {
        continue;
      }
      bool out = true;
      if (s.phase == Phase::frame) {
        if (s.is_tx && p.bits != nullptr && i < p.bits->length) {
          out = p.bits->level_at(i);
        } else if (!s.is_tx && p.acks && i == ack_slot && e != nullptr) {
          out = false;
        }
      } else if (s.phase == Phase::flag && !p.passive && i < s.flag_start + kErrorFlagBits) {
        out = false;
      }
      bus = bus && out;
    }
    if (held(i)) {
      bus = false;
    }
    const bool prev_bus = last_level;
    run = bus == last_level ? run + 1 : 1;
    last_level = bus;
    if (!bus) {
      last_dominant = i;
    }

    // What each node makes of it.
    bool all_done = true;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      State& s = st[k];
      const Participant& p = parts[k];
      switch (s.phase) {
        case Phase::frame: {
          if (p.planned && p.planned->second == i) {
            detect(k, i, p.planned->first, true);
            break;
          }
          if (s.is_tx && p.bits != nullptr && i < p.bits->length) {
            const bool sent = p.bits->level_at(i);
            if (i == ack_slot) {
              if (bus && !p.self_test) {
                detect(k, i, CanErrorType::ack, true);
              }
            } else if (sent != bus) {
              if (sent && i < p.bits->arbitration_end) {
                if (p.bits->is_stuff(i)) {
                  // A recessive stuff bit overwritten in arbitration: stuff error, no TEC
                  // increment (rule 3, exception 2).
                  detect(k, i, CanErrorType::stuff, false);
                } else {
                  s.is_tx = false;  // lost arbitration: it receives from here on
                  actions.push_back(Action{bit_end(i), p.id, Action::Kind::arbitration_lost,
                                           CanErrorType::bit, ErrorRole::transmitter,
                                           static_cast<uint16_t>(i), false, true, Field::sof,
                                           p.bits->destuffed_index(static_cast<uint16_t>(i))});
                }
              } else {
                detect(k, i, CanErrorType::bit, true);
              }
            } else if (i + 1u == p.bits->length) {
              s.phase = Phase::done;  // sent the whole frame without seeing an error
              s.done_at = i;
              actions.push_back(Action{bit_end(i), p.id, Action::Kind::tx_ok});
            }
            break;
          }
          // Receiver (or a node that has nothing to send while the bus is held).
          if (i < stuff_end && run >= 6) {
            detect(k, i, CanErrorType::stuff, true);
          } else if (e != nullptr && !bus &&
                     (i == e->crc_delimiter_index || (i > ack_slot && i + 1u < length))) {
            // Fixed-form bits: CRC delimiter, ACK delimiter, EOF up to its last-but-one bit (a
            // dominant last bit is an overload condition for receivers, not modelled).
            detect(k, i, CanErrorType::form, true);
          } else if (e != nullptr && e->fd && i >= stuff_end && i < e->crc_delimiter_index &&
                     e->is_stuff(i) && bus == prev_bus) {
            detect(k, i, CanErrorType::form, true);  // fixed stuff bit with the wrong level
          } else if (e != nullptr && i + 2u == length) {
            // Valid for receivers once the last-but-one bit of EOF is through without error;
            // delivered at the end of EOF like any frame.
            if (p.decodes) {
              s.validated = true;
              // Rule 8 needs the ACK sent: a node that could not give it keeps its counter.
              actions.push_back(Action{bit_end(i + 1), p.id, Action::Kind::rx_ok, CanErrorType::bit,
                                       ErrorRole::receiver, static_cast<uint16_t>(i), p.acks});
            }
            s.phase = Phase::done;
            s.done_at = i;
          }
          break;
        }
        case Phase::flag: {
          if (!p.passive) {
            if (i + 1 >= s.flag_start + kErrorFlagBits) {
              s.phase = Phase::wait_recessive;
              s.flag_end = i;
              s.dominant_run = kErrorFlagBits;
            }
            break;
          }
          // Passive flag: done after six equal consecutive bits, whatever their level.
          if (!bus && s.passive_ack_pending) {
            // A dominant bit during the passive flag: the ACK-error exception no longer holds.
            s.passive_ack_pending = false;
            actions.push_back(Action{bit_end(i), p.id, Action::Kind::severe, CanErrorType::ack,
                                     ErrorRole::transmitter, static_cast<uint16_t>(i), true, true});
          }
          s.equal_run = (s.equal_run > 0 && bus == s.equal_level) ? s.equal_run + 1 : 1;
          s.equal_level = bus;
          if (s.equal_run >= kErrorFlagBits) {
            s.phase = Phase::wait_recessive;
            s.flag_end = i;
            s.dominant_run = 0;
          }
          break;
        }
        case Phase::wait_recessive: {
          if (bus) {
            s.phase = Phase::delimiter;
            s.delimiter = 1;
            break;
          }
          ++s.dominant_run;
          // Rule 2: a receiver sees a dominant bit right after its own error flag.
          if (!s.is_tx && i == s.flag_end + 1 && p.drives) {
            actions.push_back(Action{bit_end(i), p.id, Action::Kind::severe, CanErrorType::bit,
                                     ErrorRole::receiver, static_cast<uint16_t>(i), true, true});
          }
          // Rule 6: 14 dominant bits from an active flag's start (8 after a passive flag), and
          // every 8 more.
          const uint32_t first = p.passive ? 8u : 14u;
          if (s.dominant_run >= first && (s.dominant_run - first) % 8 == 0 && p.drives) {
            actions.push_back(Action{bit_end(i), p.id, Action::Kind::severe, CanErrorType::bit,
                                     s.is_tx ? ErrorRole::transmitter : ErrorRole::receiver,
                                     static_cast<uint16_t>(i), true, true});
          }
          break;
        }
        case Phase::delimiter: {
          if (bus) {
            if (++s.delimiter >= kErrorDelimiterBits) {
              s.phase = Phase::done;
              s.done_at = i;
            }
          } else {
            s.phase = Phase::wait_recessive;  // not modelled: overload after an error frame
            s.dominant_run = 1;
          }
          break;
        }
        case Phase::done:
          break;
      }
      all_done = all_done && s.phase == Phase::done;
    }
    // A hold keeps everybody waiting for recessive bits for as long as it lasts (up to a
    // million bit times per activity; docs/bus-engine.md).
    if ((all_done && !held(i + 1)) || (i >= max_bits && !held(i + 1)) ||
        i >= max_bits + kMaxHeldBits) {
      break;
    }
  }
  // The error frame ends with the last node's delimiter; a hold keeps the bus until it ends.
  const uint32_t end_bit = i;
  const SimTime end = bit_end(end_bit);
  const SimTime ifs_end = end + nominal.bits_duration(kIntermissionBits);
  const SimTime dominant_end = bit_end(last_dominant);
  error_frames_on_bus_++;
  record_busy(sof, ifs_end);
  if (on_bus_event) {
    BusEvent ev{e != nullptr ? BusEvent::Kind::error_frame : BusEvent::Kind::bus_held,
                sof,
                end,
                0,
                std::nullopt,
                first_bit};
    for (const auto& p : parts) {
      if (p.transmitter) {
        ev.transmitter = p.id;
        ev.frame = nodes_[p.id].controller->pending_tx()->frame;
        break;
      }
    }
    on_bus_event(ev);
  }

  std::stable_sort(actions.begin(), actions.end(),
                   [](const Action& a, const Action& b) { return a.at < b.at; });
  // Frames the receivers validated before the error reached them (last EOF bit) are delivered.
  std::optional<Frame> frame;
  std::vector<bool> was_passive(parts.size());
  for (const auto& p : parts) {
    if (p.transmitter && e != nullptr) {
      frame = nodes_[p.id].controller->pending_tx()->frame;
    }
  }
  for (const Action& a : actions) {
    scheduler_.schedule_at(a.at, [this, a, frame, e_present = e != nullptr](SimTime now) {
      Node& n = nodes_[a.node];
      FaultConfinement& fc = n.controller->confinement();
      switch (a.kind) {
        case Action::Kind::error: {
          if (a.count) {
            a.role == ErrorRole::transmitter ? fc.transmitter_error()
                                             : fc.receiver_detected_error();
          }
          (a.role == ErrorRole::transmitter ? n.stats.errors_as_transmitter
                                            : n.stats.errors_as_receiver)[a.type]++;
          BusErrorEvent ev;
          ev.at = now;
          ev.type = a.type;
          ev.role = a.role;
          ev.bit = a.bit;
          ev.in_frame = a.in_frame && e_present;
          ev.field = a.field;
          ev.destuffed_bit = a.destuffed_bit;
          ev.extended_frame = a.extended;
          ev.tec = fc.tec();
          ev.rec = fc.rec();
          n.controller->on_error(ev);
          break;
        }
        case Action::Kind::severe:
          a.role == ErrorRole::transmitter ? fc.dominant_sequence(ErrorRole::transmitter)
                                           : fc.receiver_severe_error();
          break;
        case Action::Kind::arbitration_lost:
          n.stats.arbitration_lost++;
          n.controller->on_arbitration_lost(now, a.bit, a.destuffed_bit);
          break;
        case Action::Kind::tx_ok: {
          fc.transmit_succeeded();
          n.stats.frames_sent++;
          const TxFrame* t = pending(n);
          if (t != nullptr && t->self_reception) {
            n.stats.frames_received++;
            n.controller->on_frame(now, t->frame, true);
          }
          forget_tx(n);
          n.controller->on_tx_done(now);
          break;
        }
        case Action::Kind::rx_ok:
          if (a.count) {
            fc.receive_succeeded();
          }
          if (frame) {
            n.stats.frames_received++;
            n.controller->on_frame(now, *frame, false);
          }
          break;
      }
      report_state(a.node, now);
    });
  }
  // At the end of the error frame: transmitters that did not succeed retry (or drop a single
  // shot); error-passive transmitters suspend; the bus is free after the intermission.
  std::vector<std::pair<NodeId, bool>> transmitters;  // (node, succeeded)
  for (std::size_t k = 0; k < parts.size(); ++k) {
    if (parts[k].transmitter) {
      const bool ok = !st[k].detected && st[k].phase == Phase::done;
      transmitters.emplace_back(parts[k].id, ok);
    }
  }
  scheduler_.schedule_at(end, [this, transmitters, ifs_end, nominal](SimTime now) {
    for (const auto& [id, ok] : transmitters) {
      Node& n = nodes_[id];
      FaultConfinement& fc = n.controller->confinement();
      if (fc.error_passive()) {
        n.ready_at = ifs_end + nominal.bits_duration(kSuspendBits);
      }
      if (ok) {
        continue;
      }
      const TxFrame* p = n.controller->pending_tx();
      if (p != nullptr && p->single_shot) {
        n.stats.tx_dropped++;
        forget_tx(n);
        n.controller->on_tx_dropped(now);
      }
    }
  });
  scheduler_.schedule_at(
      ifs_end, [this, dominant_end, ifs_end](SimTime) { bus_released(dominant_end, ifs_end); });
}

void CanBus::bus_released(SimTime last_dominant_end, SimTime idle_at) {
  busy_ = false;
  in_flight_.clear();
  free_at_ = idle_at;
  last_dominant_end_ = last_dominant_end;
  if (maybe_recovering_) {
    for (NodeId id = 0; id < nodes_.size(); ++id) {
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

// A dominant bit starts at `dominant_start`: every recovering node counts the sequences of 11
// recessive bits it saw since the last dominant bit (or since its recovery began).
void CanBus::account_recessive(SimTime dominant_start) {
  if (!maybe_recovering_) {
    return;
  }
  bool any = false;
  for (NodeId id = 0; id < nodes_.size(); ++id) {
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
  n.controller->on_state_change(at, ErrorState::active);
  if (!busy_) {
    schedule_attempt(std::max(at, free_at_));
  }
}

void CanBus::report_state(NodeId id, SimTime at) {
  Node& n = nodes_[id];
  FaultConfinement& fc = *n.fc;
  if (fc.tec() == n.reported_tec && fc.rec() == n.reported_rec && !fc.bus_off()) {
    return;  // nothing counted since the last report
  }
  n.reported_tec = fc.tec();
  n.reported_rec = fc.rec();
  const ErrorState s = fc.state();
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

void CanBus::record_busy(SimTime start, SimTime end) {
  busy_intervals_.emplace_back(start, end);
  while (!busy_intervals_.empty() && busy_intervals_.front().second < end - seconds(2)) {
    busy_intervals_.pop_front();
  }
}

double CanBus::bus_load_percent(SimTime now) const {
  const SimTime from = now - seconds(1);
  int64_t busy = 0;
  for (const auto& [start, end] : busy_intervals_) {
    const SimTime a = std::max(start, from);
    const SimTime b = std::min(end, now);
    if (b > a) {
      busy += (b - a).ns();
    }
  }
  return 100.0 * static_cast<double>(busy) / 1e9;
}

}  // namespace canemu::model
