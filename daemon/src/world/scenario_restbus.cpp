// A scenario's faults on simulated CAN nodes ([[can_node]], docs/faults.md "Simulated CAN
// nodes"): the node effects find them by name, and the message and signal effects act on the
// node that sends the message.
#include <fmt/format.h>

#include "canemu/daemon/world/scenario_runner.hpp"

namespace canemu::daemon {

using namespace canemu::model;

std::optional<DeviceRegistry::NodeRef> ScenarioRunner::find_node(std::string_view name) const {
  if (auto device = devices_.find_node(name)) {
    return device;
  }
  const auto can = find_can_node ? find_can_node(name) : std::nullopt;
  if (!can) {
    return std::nullopt;
  }
  HostedNode& node = can->ecu->node();
  return DeviceRegistry::NodeRef{can->bus, &node, node.node(), &node.controller(), nullptr, 0};
}

std::string ScenarioRunner::restbus_problem(const FaultSpec& f, const restbus::CanEcu& ecu) {
  Result<> ok;
  const auto keep = [&ok](const auto& result) {
    if (!result) {
      ok = tl::unexpected(result.error());
    }
  };
  switch (f.effect) {
    case FaultEffect::message_timeout:
      break;  // the message was found
    case FaultEffect::checksum_error:
      keep(ecu.check_checksum(f.message));
      break;
    case FaultEffect::counter_freeze:
      keep(ecu.check_counter(f.message, f.signal));
      break;
    case FaultEffect::counter_jump:
      keep(ecu.check_jump(f.message, f.signal, f.by));
      break;
    case FaultEffect::signal_step:
      keep(ecu.check_value(f.message, f.signal, *f.value));
      break;
    case FaultEffect::signal_ramp:
      keep(ecu.check_ramp(f.message, f.signal, *f.value));
      break;
    case FaultEffect::signal_invalid:
      if (f.raw) {
        keep(ecu.check_raw(f.message, f.signal, *f.raw));
      } else {
        keep(ecu.check_value(f.message, f.signal, *f.value, false));
      }
      break;
    default:
      break;
  }
  return ok ? std::string() : ok.error().text;
}

void ScenarioRunner::arm_restbus(AppliedFault& applied, const std::string& what) {
  const FaultSpec& f = applied.spec;
  restbus::CanEcu* ecu = applied.ecu;
  const std::shared_ptr<FaultSwitch>& state = applied.state;
  const SimTime at = applied.start + SimDuration(f.at_ns);
  const bool ends = f.until_ns.has_value();  // at `until`
  const SimTime until = applied.start + SimDuration(f.until_ns.value_or(f.at_ns));
  // Checked when the scenario was applied, against a node that stays until the fault is
  // cleared: an error here is a fault that did nothing, and the log says why.
  const auto done = [this, what, state](const Result<>& ok, std::string_view suffix = "") {
    if (!ok) {
      --state->fired;
      log(fmt::format("{}: {}", what, ok.error().text));
    } else {
      log(what + std::string(suffix));
    }
  };
  const std::string message = f.message;
  const std::string signal = f.signal;
  switch (f.effect) {
    case FaultEffect::message_timeout:
      when(at, state, [=] { done(ecu->silence(message, true)); });
      if (ends) {
        when(until, state, [=] { done(ecu->silence(message, false), " ends"); });
      }
      break;
    case FaultEffect::checksum_error: {
      applied.checksum = std::make_shared<restbus::ChecksumFault>();
      applied.checksum->frames = f.count;
      const std::shared_ptr<restbus::ChecksumFault> fault = applied.checksum;
      when(at, state, [=] { done(ecu->corrupt_checksum(message, fault)); });
      if (ends) {
        when(until, state, [=] { done(ecu->corrupt_checksum(message, nullptr), " ends"); });
      }
      break;
    }
    case FaultEffect::counter_freeze:
      when(at, state, [=] { done(ecu->freeze_counter(message, signal, true)); });
      if (ends) {
        when(until, state, [=] { done(ecu->freeze_counter(message, signal, false), " ends"); });
      }
      break;
    case FaultEffect::counter_jump: {
      const uint64_t by = f.by;
      when(at, state, [=] { done(ecu->jump_counter(message, signal, by)); });
      break;
    }
    case FaultEffect::signal_step: {
      const double value = *f.value;
      when(at, state, [=] { done(ecu->set_signal(message, signal, value)); });
      break;
    }
    case FaultEffect::signal_ramp: {
      const double to = *f.value;
      when(at, state, [=] { done(ecu->ramp_signal(message, signal, until, to)); });
      break;
    }
    case FaultEffect::signal_invalid: {
      // The value before the fault, for its end.
      auto before = std::make_shared<std::optional<uint64_t>>();
      const std::optional<double> value = f.value;
      const std::optional<uint64_t> raw = f.raw;
      when(at, state, [=] {
        *before = *ecu->raw_signal(message, signal);
        done(raw ? ecu->set_raw_signal(message, signal, *raw)
                 : ecu->set_signal(message, signal, *value, false));
      });
      if (ends) {
        when(until, state, [=] {
          if (*before) {
            done(ecu->set_raw_signal(message, signal, **before), " ends");
          }
        });
      }
      break;
    }
    default:
      break;
  }
}

}  // namespace canemu::daemon
