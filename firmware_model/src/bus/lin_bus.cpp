#include "canemu/firmware_model/bus/lin_bus.hpp"

#include <algorithm>

namespace canemu::model::lin {

namespace {
constexpr uint8_t kSleepData[kMaxData] = {0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
}  // namespace

LinBus::LinBus(SimScheduler& scheduler, Layout layout) : scheduler_(scheduler), layout_(layout) {
  inactivity_ = scheduler_.schedule_at(scheduler_.now() + kInactivity, *this, tag_inactive);
}

LinBus::~LinBus() {
  for (auto* id : {&step_, &inactivity_}) {
    if (*id) {
      scheduler_.cancel(**id);
    }
  }
  for (EventId id : bit_error_events_) {
    scheduler_.cancel(id);
  }
}

LinNodeId LinBus::attach(LinNode& node) {
  nodes_.push_back(Slot{&node, false});
  return static_cast<LinNodeId>(nodes_.size() - 1);
}

void LinBus::detach(LinNodeId node) {
  if (node >= nodes_.size()) {
    return;
  }
  nodes_[node] = Slot{};
  std::erase_if(queue_, [node](const Request& r) { return r.from == node; });
}

bool LinBus::pending(LinNodeId node) const {
  return node < nodes_.size() && nodes_[node].pending;
}

void LinBus::withdraw(LinNodeId node) {
  const auto before = queue_.size();
  std::erase_if(queue_, [node](const Request& r) { return r.from == node; });
  if (queue_.size() != before) {
    nodes_[node].pending = false;
  }
}

bool LinBus::send_header(LinNodeId from, uint8_t id, std::optional<uint8_t> expected_size) {
  Request r;
  r.kind = RequestKind::header;
  r.from = from;
  r.id = id & kMaxId;
  r.expected_size = expected_size;
  return enqueue(r);
}

bool LinBus::send_frame(LinNodeId from, uint8_t id, const Response& response) {
  Request r;
  r.kind = RequestKind::frame;
  r.from = from;
  r.id = id & kMaxId;
  r.response = response;
  return enqueue(r);
}

bool LinBus::send_sleep(LinNodeId from) {
  Response r;
  std::copy(std::begin(kSleepData), std::end(kSleepData), r.data.begin());
  r.size = kMaxData;
  r.checksum = Checksum::classic;
  return send_frame(from, kMasterRequestId, r);
}

bool LinBus::send_wakeup(LinNodeId from, SimDuration pulse) {
  Request r;
  r.kind = RequestKind::wakeup;
  r.from = from;
  r.pulse = pulse;
  return enqueue(r);
}

bool LinBus::enqueue(Request r) {
  if (r.from >= nodes_.size() || nodes_[r.from].node == nullptr || nodes_[r.from].pending) {
    return false;
  }
  nodes_[r.from].pending = true;
  queue_.push_back(std::move(r));
  start_next(scheduler_.now());
  return true;
}

bool LinBus::synchronizes(LinNodeId node, uint32_t rate) const {
  const uint32_t own = nodes_[node].node->lin_bitrate();
  if (own == 0) {
    return true;  // detects the rate from the sync byte
  }
  const uint64_t diff = own > rate ? own - rate : rate - own;
  return diff * 100 <= uint64_t{kSyncTolerancePercent} * rate;
}

std::vector<LinNodeId> LinBus::live_nodes() const {
  std::vector<LinNodeId> out;
  for (LinNodeId n = 0; n < nodes_.size(); ++n) {
    if (nodes_[n].node != nullptr) {
      out.push_back(n);
    }
  }
  return out;
}

void LinBus::deliver(const Event& event, const std::vector<LinNodeId>& to) {
  Event e = event;
  e.bitrate = e.kind == Event::Kind::error && e.error == ErrorKind::inactive ? 0 : rate_;
  for (LinNodeId n : to) {
    if (n < nodes_.size() && nodes_[n].node != nullptr) {
      nodes_[n].node->on_lin_event(e);
    }
  }
}

void LinBus::start_next(SimTime now) {
  if (busy_ || queue_.empty()) {
    return;
  }
  current_ = queue_.front();
  queue_.pop_front();
  busy_ = true;
  started_ = now;
  const uint32_t own = nodes_[current_.from].node->lin_bitrate();
  rate_ = own != 0 ? own : layout_.bitrate;
  synced_.clear();
  wire_.clear();
  bit_errors_.clear();
  responder_ = kNoNode;
  responders_.clear();
  if (current_.kind == RequestKind::wakeup) {
    frame_faults_ = {};
    step_ = scheduler_.schedule_at(now + current_.pulse, *this, tag_wakeup_end);
    return;
  }
  ++stats_.headers;
  frame_faults_ =
      faults_ != nullptr ? faults_->faults_for(now, current_.id, current_.from) : FrameFaults{};
  const FrameBits bits = frame_bits(layout_, 0);
  step_ = scheduler_.schedule_at(after_bits(now, bits.header_end, rate_), *this, tag_header_end);
}

void LinBus::on_event(SimTime now, uint64_t tag) {
  switch (static_cast<Tag>(tag)) {
    case tag_header_end:
      step_.reset();
      header_end(now);
      return;
    case tag_response_end:
      step_.reset();
      response_end(now);
      return;
    case tag_no_response: {
      step_.reset();
      Event e;
      e.kind = Event::Kind::error;
      e.at = now;
      e.id = current_.id;
      e.sender = current_.from;
      e.error = ErrorKind::no_response;
      ++stats_.errors;
      deliver(e, synced_);
      finish(now);
      return;
    }
    case tag_wakeup_end: {
      step_.reset();
      ++stats_.wakeups;
      if (current_.pulse >= kMinWakeup) {
        Event e;
        e.kind = Event::Kind::wakeup;
        e.at = now;
        e.sender = current_.from;
        std::vector<LinNodeId> others = live_nodes();
        std::erase(others, current_.from);
        deliver(e, others);
      }
      finish(now);
      return;
    }
    case tag_inactive: {
      inactivity_.reset();
      Event e;
      e.kind = Event::Kind::error;
      e.at = now;
      e.error = ErrorKind::inactive;
      deliver(e, live_nodes());
      return;
    }
    case tag_next:
      step_.reset();
      start_next(now);
      return;
  }
}

void LinBus::header_end(SimTime now) {
  std::vector<LinNodeId> listeners = live_nodes();
  std::erase(listeners, current_.from);
  Event e;
  e.kind = Event::Kind::error;
  e.at = now;
  e.sender = current_.from;
  auto fail = [&](ErrorKind kind, const std::vector<LinNodeId>& to, bool known_id) {
    e.error = kind;
    e.id = known_id ? current_.id : Event::kNoId;
    deliver(e, to);
  };
  const FrameFaults& f = frame_faults_;
  if (f.short_break || f.sync_error || f.parity_error || f.header_bit_error) {
    ++stats_.errors;
    if (f.header_bit_error) {
      fail(ErrorKind::bit, {current_.from}, true);
    }
    fail(f.short_break  ? ErrorKind::other
         : f.sync_error ? ErrorKind::sync
                        : ErrorKind::parity,
         listeners, false);
    finish(now);
    return;
  }
  synced_.push_back(current_.from);
  std::vector<LinNodeId> lost;
  for (LinNodeId n : listeners) {
    (synchronizes(n, rate_) ? synced_ : lost).push_back(n);
  }
  if (!lost.empty()) {
    fail(ErrorKind::sync, lost, false);
  }
  std::sort(synced_.begin(), synced_.end());

  // The responders, in node order: the commander publishing, and every response table with
  // the identifier.
  struct Tx {
    LinNodeId node;
    std::vector<uint8_t> chars;
  };
  std::vector<Tx> txs;
  if (!f.no_response) {
    for (LinNodeId n : synced_) {
      if (n == f.silent) {
        continue;
      }
      std::optional<Response> r = n == current_.from && current_.response
                                      ? current_.response
                                      : nodes_[n].node->respond(current_.id);
      if (!r || r->size == 0 || r->size > kMaxData) {
        continue;
      }
      Tx tx{n, {r->data.begin(), r->data.begin() + r->size}};
      uint8_t cs = checksum(r->checksum, current_.id, {r->data.data(), r->size});
      if (f.checksum_error) {
        cs ^= 0x01;  // the faulty responder's wrong checksum
      }
      tx.chars.push_back(cs);
      txs.push_back(std::move(tx));
    }
  }
  const FrameBits bits = frame_bits(layout_, 0);
  if (txs.empty()) {
    const uint32_t expected = current_.expected_size.value_or(kMaxData);
    step_ = scheduler_.schedule_at(
        after_bits(started_, bits.header_end + maximum_response_bits(expected), rate_), *this,
        tag_no_response);
    return;
  }
  // The characters on the wire: wired-AND of those still sending; a responder that reads back
  // another character has a bit error and stops after it.
  std::vector<bool> active(txs.size(), true);
  for (std::size_t k = 0;; ++k) {
    bool any = false;
    uint8_t c = 0xFF;
    for (std::size_t t = 0; t < txs.size(); ++t) {
      if (active[t] && k < txs[t].chars.size()) {
        any = true;
        c &= txs[t].chars[k];
      }
    }
    if (!any) {
      break;
    }
    if (k == 0 && f.response_bit_error) {
      c ^= 0x01;
    }
    for (std::size_t t = 0; t < txs.size(); ++t) {
      if (!active[t] || k >= txs[t].chars.size()) {
        continue;
      }
      if (txs[t].chars[k] != c) {
        // It reads the character back at its stop bit, reports the bit error then and sends
        // nothing more.
        const LinNodeId node = txs[t].node;
        const uint8_t id = current_.id;
        const LinNodeId sender = current_.from;
        const uint32_t rate = rate_;
        const SimTime at = after_bits(started_, bits.byte_end(static_cast<uint32_t>(k)), rate_);
        bit_error_events_.push_back(
            scheduler_.schedule_at(at, [this, node, id, sender, rate](SimTime when) {
              Event bit;
              bit.kind = Event::Kind::error;
              bit.at = when;
              bit.id = id;
              bit.sender = sender;
              bit.error = ErrorKind::bit;
              bit.bitrate = rate;
              if (node < nodes_.size() && nodes_[node].node != nullptr) {
                nodes_[node].node->on_lin_event(bit);
              }
            }));
        bit_errors_.push_back(node);
        active[t] = false;
      } else if (k + 1 == txs[t].chars.size()) {
        active[t] = false;
        if (responder_ == kNoNode) {
          responder_ = txs[t].node;
        }
        responders_.push_back(txs[t].node);
      }
    }
    wire_.push_back(c);
  }
  const FrameBits with = frame_bits(layout_, static_cast<uint32_t>(wire_.size() - 1));
  step_ = scheduler_.schedule_at(
      after_bits(started_, with.byte_end(static_cast<uint32_t>(wire_.size() - 1)), rate_), *this,
      tag_response_end);
}

void LinBus::response_end(SimTime now) {
  Event e;
  e.at = now;
  e.id = current_.id;
  e.sender = current_.from;
  std::vector<LinNodeId> listeners = synced_;
  std::erase_if(listeners, [&](LinNodeId n) {
    return std::find(bit_errors_.begin(), bit_errors_.end(), n) != bit_errors_.end();
  });
  // The last character is the checksum; the kind is the one that matches.
  std::optional<Checksum> kind;
  if (wire_.size() >= 2) {
    const std::span<const uint8_t> data(wire_.data(), wire_.size() - 1);
    for (Checksum k : {Checksum::enhanced, Checksum::classic}) {
      if (checksum(k, current_.id, data) == wire_.back()) {
        kind = effective_checksum(k, current_.id);
        break;
      }
    }
  }
  e.checksum_byte = wire_.back();
  if (!kind || responder_ == kNoNode) {
    ++stats_.errors;
    e.kind = Event::Kind::error;
    e.error = ErrorKind::checksum;
    e.responder = kNoNode;
    e.response.size = static_cast<uint8_t>(wire_.size() - 1);
    std::copy(wire_.begin(), wire_.end() - 1, e.response.data.begin());
    deliver(e, listeners);
    finish(now);
    return;
  }
  ++stats_.frames;
  e.kind = Event::Kind::frame;
  e.responder = responder_;
  e.responders = responders_;
  e.response.size = static_cast<uint8_t>(wire_.size() - 1);
  std::copy(wire_.begin(), wire_.end() - 1, e.response.data.begin());
  e.response.checksum = *kind;
  deliver(e, listeners);
  if (current_.id == kMasterRequestId && e.response.data[0] == 0x00) {
    Event sleep;
    sleep.kind = Event::Kind::sleep;
    sleep.at = now;
    sleep.sender = current_.from;
    deliver(sleep, listeners);
  }
  finish(now);
}

void LinBus::finish(SimTime now) {
  busy_ = false;
  bit_error_events_.clear();  // they ran: none is later than the response's end
  stats_.busy_ns += static_cast<uint64_t>((now - started_).ns());
  load_.record(started_, now);
  if (current_.from < nodes_.size()) {
    nodes_[current_.from].pending = false;
  }
  if (inactivity_) {
    scheduler_.cancel(*inactivity_);
  }
  inactivity_ = scheduler_.schedule_at(now + kInactivity, *this, tag_inactive);
  if (!queue_.empty()) {
    step_ = scheduler_.schedule_at(now, *this, tag_next);
  }
}

}  // namespace canemu::model::lin
