// A simulated CAN node's faults (docs/faults.md, "Simulated CAN nodes"): messages silenced,
// counters frozen or jumping, checksums spoiled, signals ramped.
#include <fmt/format.h>

#include "canemu/daemon/restbus/can_ecu.hpp"
#include "canemu/daemon/restbus/signal_codec.hpp"
#include "restbus/can_ecu_detail.hpp"

namespace canemu::daemon::restbus {

using namespace canemu::model;
using detail::mask;
using detail::ramp_at;

Result<> CanEcu::silence(std::string_view message, bool silent) {
  auto i = find(message);
  if (!i) {
    return tl::unexpected(i.error());
  }
  Message& m = messages_[*i];
  m.silent = silent;
  if (silent) {
    drop(m);
  }
  return {};
}

Result<CanEcu::Place> CanEcu::check_counter(std::string_view message,
                                            std::string_view signal) const {
  auto at = find_both(message, signal);
  if (at && !messages_[at->first].config->signals[at->second].counter) {
    return fail(Errc::bad_argument, fmt::format("{}.{} is not a counter", message, signal));
  }
  return at;
}

Result<> CanEcu::freeze_counter(std::string_view message, std::string_view signal, bool frozen) {
  auto at = check_counter(message, signal);
  if (!at) {
    return tl::unexpected(at.error());
  }
  std::vector<std::size_t>& list = messages_[at->first].frozen;
  std::erase(list, at->second);
  if (frozen) {
    list.push_back(at->second);
  }
  return {};
}

Result<CanEcu::Place> CanEcu::check_jump(std::string_view message, std::string_view signal,
                                         uint64_t by) const {
  auto at = check_counter(message, signal);
  if (!at) {
    return at;
  }
  const uint32_t bits = messages_[at->first].config->signals[at->second].layout.length;
  if ((by & ~mask(bits)) != 0) {
    return fail(Errc::bad_argument,
                fmt::format("by = {} is not below 2^{}: the {}-bit counter would skip a whole "
                            "turn or more",
                            by, bits, bits));
  }
  return at;
}

Result<> CanEcu::jump_counter(std::string_view message, std::string_view signal, uint64_t by) {
  auto at = check_jump(message, signal, by);
  if (!at) {
    return tl::unexpected(at.error());
  }
  const Message& m = messages_[at->first];
  const uint32_t bits = m.config->signals[at->second].layout.length;
  change(at->first, at->second, (m.raw[at->second] + by) & mask(bits));
  return {};
}

Result<std::size_t> CanEcu::check_checksum(std::string_view message) const {
  auto i = find(message);
  if (!i) {
    return i;
  }
  const auto& signals = messages_[*i].config->signals;
  if (std::none_of(signals.begin(), signals.end(),
                   [](const CanSignalConfig& s) { return s.checksum != ChecksumKind::none; })) {
    return fail(Errc::bad_argument, fmt::format("message {} has no checksum signal", message));
  }
  return i;
}

Result<> CanEcu::corrupt_checksum(std::string_view message, std::shared_ptr<ChecksumFault> fault) {
  auto i = check_checksum(message);
  if (!i) {
    return tl::unexpected(i.error());
  }
  messages_[*i].bad_checksum = std::move(fault);
  return {};
}

Result<CanEcu::Place> CanEcu::check_ramp(std::string_view message, std::string_view signal,
                                         double to) const {
  auto at = find_both(message, signal);
  if (!at) {
    return at;
  }
  const CanMessageConfig& m = *messages_[at->first].config;
  if (m.send == CanMessageConfig::Send::on_change) {
    return fail(
        Errc::bad_argument,
        fmt::format("message {} is sent on change only: a ramp needs a cyclic message", m.name));
  }
  if (m.signals[at->second].counter) {
    return fail(Errc::bad_argument,
                fmt::format("{}.{} is a counter: it counts by itself", m.name, signal));
  }
  if (auto ok = value_raw(at->first, at->second, to, true); !ok) {  // as a value to set
    return tl::unexpected(ok.error());
  }
  return at;
}

Result<> CanEcu::ramp_signal(std::string_view message, std::string_view signal, SimTime until,
                             double to) {
  auto at = check_ramp(message, signal, to);
  if (!at) {
    return tl::unexpected(at.error());
  }
  const std::size_t k = at->second;  // a variable of its own: lambdas capture it
  Message& m = messages_[at->first];
  std::erase_if(m.ramps, [k](const Ramp& r) { return r.signal == k; });
  const double start = to_physical(m.config->signals[k].layout, m.raw[k]);
  m.ramps.push_back(Ramp{k, node_.now(), until, start, to});
  return {};
}

void CanEcu::apply_ramps(Message& m, SimTime now) {
  for (const Ramp& r : m.ramps) {
    const CanSignalConfig& s = m.config->signals[r.signal];
    m.raw[r.signal] = to_raw(s.layout, ramp_at(r, now)).value_or(m.raw[r.signal]);
  }
  std::erase_if(m.ramps, [now](const Ramp& r) { return now >= r.until; });
}

}  // namespace canemu::daemon::restbus
