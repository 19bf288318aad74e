// A simulated CAN node: its messages' payloads, their schedules, counters and checksums.
#include "canemu/daemon/restbus/can_ecu.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "canemu/daemon/restbus/signal_codec.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "restbus/can_ecu_detail.hpp"

namespace canemu::daemon::restbus {

using namespace canemu::model;
using detail::mask;
using detail::ramp_at;
using detail::settable;

namespace {

bool cyclic(const CanMessageConfig& m) {
  return m.send != CanMessageConfig::Send::on_change;
}
bool on_change(const CanMessageConfig& m) {
  return m.send == CanMessageConfig::Send::on_change ||
         m.send == CanMessageConfig::Send::cyclic_and_on_change;
}

// Arbitration order: the lower the key, the earlier the frame wins the bus (a standard frame
// before an extended one of the same base identifier).
uint64_t priority(const CanMessageConfig& m) {
  return m.extended ? (uint64_t{m.id} << 1) | 1 : uint64_t{m.id} << 19;
}

// The byte of a one-byte checksum signal.
uint32_t byte_of(const SignalLayout& s) {
  return s.start / 8;
}

}  // namespace

Result<> CanEcu::check(const CanNodeConfig& config) {
  for (const CanMessageConfig& m : config.messages) {
    for (const CanSignalConfig& s : m.signals) {
      if (auto raw = to_raw(s.layout, s.initial); !raw) {
        return fail(Errc::bad_argument,
                    fmt::format("can_node {}: message {}: signal {}: initial value {}: {}",
                                config.name, m.name, s.name, s.initial, raw.error().text));
      }
    }
  }
  return {};
}

Result<std::unique_ptr<CanEcu>> CanEcu::start(const CanNodeConfig& config, HostedNode& node,
                                              const HostedNodeSettings& timing) {
  if (auto ok = check(config); !ok) {
    return tl::unexpected(ok.error());
  }
  std::unique_ptr<CanEcu> ecu(new CanEcu(config, node, timing));
  for (Message& m : ecu->messages_) {
    for (const CanSignalConfig& s : m.config->signals) {
      m.raw.push_back(*to_raw(s.layout, s.initial));
      // Checked to fit by the reader, as the initial value is: read once, not every cycle.
      m.inactive.push_back(s.inactive ? to_raw(s.layout, *s.inactive).value_or(0)
                                      : std::optional<uint64_t>());
    }
  }
  node.claim(true);
  if (config.powered) {
    ecu->power(true);
  }
  return ecu;
}

CanEcu::CanEcu(const CanNodeConfig& config, HostedNode& node, const HostedNodeSettings& timing)
    : config_(config), node_(node), timing_(timing) {
  timing_.listen_only = false;
  timing_.restart_delay = SimDuration{};  // bus-off: it stays off the bus until powered again
  messages_.resize(config_.messages.size());
  for (std::size_t i = 0; i < messages_.size(); ++i) {
    messages_[i].config = &config_.messages[i];
  }
}

CanEcu::~CanEcu() {
  stop_schedule();
  if (powered_) {
    node_.stop();
  }
  node_.claim(false);
}

void CanEcu::power(bool on) {
  if (on == powered_) {
    return;
  }
  powered_ = on;
  if (!on) {
    stop_schedule();
    for (Message& m : messages_) {
      drop(m);
    }
    node_.stop();
    return;
  }
  node_.start(timing_, this, [this] { return next_tx(); });
  started_ = node_.now();
  for (std::size_t i = 0; i < messages_.size(); ++i) {
    messages_[i].due = 0;
    schedule(i);
  }
}

void CanEcu::stop_schedule() {
  for (Message& m : messages_) {
    if (m.next) {
      node_.scheduler().cancel(*m.next);
      m.next.reset();
    }
  }
}

void CanEcu::schedule(std::size_t i) {
  Message& m = messages_[i];
  if (!cyclic(*m.config)) {
    return;
  }
  const SimTime at = started_ + SimDuration(m.config->delay_ns) +
                     SimDuration(static_cast<int64_t>(m.due) * m.config->cycle_ns);
  m.next = node_.scheduler().schedule_at(at, [this, i](SimTime) { due(i); });
}

void CanEcu::due(std::size_t i) {
  Message& m = messages_[i];
  m.next.reset();
  if (m.silent || node_.controller().confinement().bus_off() ||
      (m.config->send == CanMessageConfig::Send::cyclic_if_active && !active(m))) {
    ++m.counters.skipped;
  } else {
    queue(m);
  }
  ++m.due;
  schedule(i);
}

bool CanEcu::active(const Message& m) const {
  for (std::size_t k = 0; k < m.inactive.size(); ++k) {
    if (m.inactive[k] && *m.inactive[k] != m.raw[k]) {
      return true;
    }
  }
  return false;
}

void CanEcu::drop(Message& m) {
  if (m.waiting) {
    m.waiting = false;
    ++m.counters.dropped;
  }
}

void CanEcu::queue(Message& m) {
  if (m.waiting) {
    ++m.counters.replaced;
  }
  m.waiting = true;
  ++m.counters.queued;
  m.counters.last_queued = node_.now();
  node_.kick();
}

std::vector<uint8_t> CanEcu::build(const Message& m) const {
  std::vector<uint8_t> payload(m.config->length, 0);
  const auto& signals = m.config->signals;
  std::optional<uint64_t> mux;
  for (std::size_t k = 0; k < signals.size(); ++k) {
    if (signals[k].multiplexer) {
      mux = m.raw[k];
    }
  }
  std::optional<std::size_t> check;
  for (std::size_t k = 0; k < signals.size(); ++k) {
    const CanSignalConfig& s = signals[k];
    if (s.checksum != ChecksumKind::none) {
      check = k;
      continue;
    }
    const auto& ids = s.multiplexer_ids;
    if (ids.empty() || (mux && std::find(ids.begin(), ids.end(), *mux) != ids.end())) {
      put_raw(payload, s.layout, m.raw[k]);
    }
  }
  if (check) {
    const CanSignalConfig& s = signals[*check];
    uint8_t sum = checksum(s.checksum, s.data_id, payload, byte_of(s.layout));
    if (m.bad_checksum && m.bad_checksum->frames.value_or(1) > 0) {
      sum = static_cast<uint8_t>(~sum);  // checksum_error: wrong in every bit
    }
    put_raw(payload, s.layout, sum);
  }
  return payload;
}

std::optional<TxFrame> CanEcu::next_tx() {
  Message* first = nullptr;
  for (Message& m : messages_) {
    if (m.waiting && (first == nullptr || priority(*m.config) < priority(*first->config))) {
      first = &m;
    }
  }
  if (first == nullptr) {
    return std::nullopt;
  }
  first->waiting = false;
  apply_ramps(*first, node_.now());
  const std::vector<uint8_t> payload = build(*first);
  if (const auto& bad = first->bad_checksum; bad && bad->frames.value_or(1) > 0) {
    ++bad->hits;
    if (bad->frames) {
      --*bad->frames;
    }
  }
  // The frame carries the counters' values; the next one carries them plus 1 (unless frozen).
  for (std::size_t k = 0; k < first->config->signals.size(); ++k) {
    const CanSignalConfig& s = first->config->signals[k];
    if (s.counter &&
        std::find(first->frozen.begin(), first->frozen.end(), k) == first->frozen.end()) {
      first->raw[k] = (first->raw[k] + 1) & mask(s.layout.length);
    }
  }
  FrameSpec spec;
  spec.id = first->config->id;
  spec.extended = first->config->extended;
  spec.fd = first->config->fd;
  spec.brs = first->config->brs;
  spec.data = payload;
  auto frame = Frame::create(spec);
  if (!frame) {
    return std::nullopt;  // the reader checked identifier, length and fd: cannot happen
  }
  return TxFrame{*frame, false, false};
}

void CanEcu::frame_transmitted(SimTime, const Frame& frame) {
  for (Message& m : messages_) {
    if (m.config->id == frame.id() && m.config->extended == frame.extended()) {
      ++m.counters.sent;
      return;
    }
  }
}

void CanEcu::state_changed(SimTime, ErrorState state, uint16_t, uint16_t) {
  if (state == ErrorState::bus_off) {
    for (Message& m : messages_) {
      drop(m);  // a controller in bus-off sends nothing; the schedule skips
    }
  }
}

const CanMessageConfig* CanEcu::message_config(std::string_view message) const {
  auto i = find(message);
  return i ? messages_[*i].config : nullptr;
}

Result<std::size_t> CanEcu::find(std::string_view message) const {
  for (std::size_t i = 0; i < messages_.size(); ++i) {
    if (messages_[i].config->name == message) {
      return i;
    }
  }
  return fail(Errc::not_found,
              fmt::format("CAN node {} sends no message named \"{}\"", config_.name, message));
}

Result<std::size_t> CanEcu::find_signal(const Message& m, std::string_view signal) const {
  const auto& signals = m.config->signals;
  for (std::size_t k = 0; k < signals.size(); ++k) {
    if (signals[k].name == signal) {
      return k;
    }
  }
  return fail(Errc::not_found,
              fmt::format("message {} has no signal named \"{}\"", m.config->name, signal));
}

Result<CanEcu::Place> CanEcu::find_both(std::string_view message, std::string_view signal) const {
  auto i = find(message);
  if (!i) {
    return tl::unexpected(i.error());
  }
  auto k = find_signal(messages_[*i], signal);
  if (!k) {
    return tl::unexpected(k.error());
  }
  return std::pair{*i, *k};
}

Result<uint64_t> CanEcu::value_raw(std::size_t i, std::size_t k, double physical,
                                   bool check_range) const {
  const Message& m = messages_[i];
  const CanSignalConfig& s = m.config->signals[k];
  if (auto ok = settable(*m.config, s); !ok) {
    return tl::unexpected(ok.error());
  }
  if (check_range && s.minimum && !(physical >= *s.minimum && physical <= *s.maximum)) {
    return fail(Errc::bad_argument,
                fmt::format("{} is outside the range of {}.{}: {}..{}{}", physical, m.config->name,
                            s.name, *s.minimum, *s.maximum, s.unit.empty() ? "" : " " + s.unit));
  }
  auto raw = to_raw(s.layout, physical);
  if (!raw) {
    return fail(Errc::bad_argument, fmt::format("{} cannot be the value of {}.{}: {}", physical,
                                                m.config->name, s.name, raw.error().text));
  }
  return *raw;
}

Result<> CanEcu::check_value(std::string_view message, std::string_view signal, double physical,
                             bool check_range) const {
  auto at = find_both(message, signal);
  if (!at) {
    return tl::unexpected(at.error());
  }
  if (auto raw = value_raw(at->first, at->second, physical, check_range); !raw) {
    return tl::unexpected(raw.error());
  }
  return {};
}

Result<> CanEcu::set_signal(std::string_view message, std::string_view signal, double physical,
                            bool check_range) {
  auto at = find_both(message, signal);
  if (!at) {
    return tl::unexpected(at.error());
  }
  auto raw = value_raw(at->first, at->second, physical, check_range);
  if (!raw) {
    return tl::unexpected(raw.error());
  }
  change(at->first, at->second, *raw);
  return {};
}

Result<CanEcu::Place> CanEcu::check_raw(std::string_view message, std::string_view signal,
                                        uint64_t raw) const {
  auto at = find_both(message, signal);
  if (!at) {
    return at;
  }
  const CanMessageConfig& m = *messages_[at->first].config;
  const CanSignalConfig& s = m.signals[at->second];
  if (auto ok = settable(m, s); !ok) {
    return tl::unexpected(ok.error());
  }
  if ((raw & ~mask(s.layout.length)) != 0) {
    return fail(Errc::bad_argument, fmt::format("raw value {} does not fit the {} bits of {}.{}",
                                                raw, s.layout.length, m.name, s.name));
  }
  return at;
}

Result<> CanEcu::set_raw_signal(std::string_view message, std::string_view signal, uint64_t raw) {
  auto at = check_raw(message, signal, raw);
  if (!at) {
    return tl::unexpected(at.error());
  }
  change(at->first, at->second, raw);
  return {};
}

void CanEcu::change(std::size_t i, std::size_t k, uint64_t raw) {
  Message& m = messages_[i];
  std::erase_if(m.ramps, [k](const Ramp& r) { return r.signal == k; });
  if (raw == m.raw[k]) {
    return;
  }
  m.raw[k] = raw;
  if (!on_change(*m.config) || !powered_ || m.silent ||
      node_.controller().confinement().bus_off()) {
    return;
  }
  // Nothing is sent before the message's delay: a change before it goes at the delay (the
  // first cyclic frame carries it anyway).
  const SimTime first = started_ + SimDuration(m.config->delay_ns);
  if (node_.now() >= first) {
    queue(m);
  } else if (m.config->send == CanMessageConfig::Send::on_change && !m.next) {
    m.next = node_.scheduler().schedule_at(first, [this, i](SimTime) {
      messages_[i].next.reset();
      queue(messages_[i]);
    });
  }
}

Result<double> CanEcu::get_signal(std::string_view message, std::string_view signal) const {
  auto at = find_both(message, signal);
  if (!at) {
    return tl::unexpected(at.error());
  }
  const auto [i, k] = *at;
  const Message& m = messages_[i];
  const CanSignalConfig& s = m.config->signals[k];
  if (s.checksum != ChecksumKind::none) {
    return to_physical(s.layout, get_raw(build(m), s.layout));
  }
  for (const Ramp& r : m.ramps) {
    if (r.signal == k) {  // the value a frame built now would carry
      return to_physical(s.layout, to_raw(s.layout, ramp_at(r, node_.now())).value_or(m.raw[k]));
    }
  }
  return to_physical(s.layout, m.raw[k]);
}

Result<uint64_t> CanEcu::raw_signal(std::string_view message, std::string_view signal) const {
  auto at = find_both(message, signal);
  if (!at) {
    return tl::unexpected(at.error());
  }
  return messages_[at->first].raw[at->second];
}

Result<MessageCounters> CanEcu::counters(std::string_view message) const {
  auto i = find(message);
  if (!i) {
    return tl::unexpected(i.error());
  }
  return messages_[*i].counters;
}

uint64_t CanEcu::frames_sent() const {
  uint64_t n = 0;
  for (const Message& m : messages_) {
    n += m.counters.sent;
  }
  return n;
}

Result<std::vector<uint8_t>> CanEcu::payload(std::string_view message) const {
  auto i = find(message);
  if (!i) {
    return tl::unexpected(i.error());
  }
  return build(messages_[*i]);
}

}  // namespace canemu::daemon::restbus
