// A scenario's faults put in place: frame and LIN rules in their bus's fault plan, and the
// faults that switch at their instants (bus and node effects) on the scheduler.
#include <algorithm>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/world/scenario_runner.hpp"
#include "world/fault_label.hpp"

namespace canemu::daemon {

using namespace canemu::model;

void ScenarioRunner::when(SimTime at, const std::shared_ptr<FaultSwitch>& state,
                          std::function<void()> fire) {
  // A fault due now takes effect at once (before any frame that starts now); later ones when
  // due, unless cleared by then.
  auto guarded = [state, fire = std::move(fire)] {
    if (!state->cleared) {
      ++state->fired;
      fire();
    }
  };
  if (at <= scheduler_.now()) {
    guarded();
  } else {
    scheduler_.schedule_at(at, [guarded](SimTime) { guarded(); });
  }
}

void ScenarioRunner::add_frame_rule(const Resolved& r, std::size_t k, uint64_t seed,
                                    const std::string& what, AppliedFault& applied) {
  const FaultSpec& f = *r.spec;
  FaultRule rule;
  if (r.node) {
    rule.match.transmitter = r.node->id;
  }
  rule.match.id = f.match.id;
  rule.match.mask = f.match.mask;
  rule.match.extended = f.match.ext;
  rule.match.remote = f.match.rtr;
  if (f.effect == FaultEffect::random_errors) {
    rule.bit_error_rate = f.bit_error_rate;  // the rule picks the bit per frame
  } else if (f.effect == FaultEffect::ack_error) {
    rule.fault.suppress_ack = true;
  } else {
    rule.fault.error = f.effect == FaultEffect::bit_error     ? CanErrorType::bit
                       : f.effect == FaultEffect::stuff_error ? CanErrorType::stuff
                       : f.effect == FaultEffect::form_error  ? CanErrorType::form
                                                              : CanErrorType::crc;
    rule.fault.bit = f.bit;
  }
  rule.count = f.count;
  rule.from = applied.start + SimDuration(f.at_ns);
  if (f.until_ns) {
    rule.until = applied.start + SimDuration(*f.until_ns);
  }
  rule.probability = f.probability;
  rule.seed = seed * 0x9E3779B97F4A7C15ull + k + 1;  // each fault its own draws
  FaultPlan& faults = *buses_[r.bus].faults;
  applied.rule = faults.add(rule);
  if (rule.until) {  // the end of its window, with what it did
    const std::size_t index = *applied.rule;
    when(*rule.until, applied.state, [this, &faults, index, what] {
      const uint64_t hits = faults.rule(index).hits;
      const auto& count = faults.rule(index).count;
      if (!count || hits < *count) {
        log(fmt::format("{}: window over, {} hit{}", what, hits, hits == 1 ? "" : "s"));
      }
    });
  }
}

void ScenarioRunner::add_lin_rule(const Resolved& r, AppliedFault& applied) {
  const FaultSpec& f = *r.spec;
  lin::LinFaultRule rule;
  switch (f.effect) {
    case FaultEffect::lin_bit_error:
      rule.effect =
          f.lin_header ? lin::LinEffect::header_bit_error : lin::LinEffect::response_bit_error;
      break;
    case FaultEffect::lin_checksum_error:
      rule.effect = lin::LinEffect::checksum_error;
      break;
    case FaultEffect::lin_parity_error:
      rule.effect = lin::LinEffect::parity_error;
      break;
    case FaultEffect::lin_sync_error:
      rule.effect = lin::LinEffect::sync_error;
      break;
    case FaultEffect::lin_short_break:
      rule.effect = lin::LinEffect::short_break;
      break;
    case FaultEffect::lin_responder_off:
      rule.effect = lin::LinEffect::responder_off;
      rule.responder = r.lin_node->node;
      break;
    default:
      rule.effect = lin::LinEffect::no_response;
      break;
  }
  if (f.effect != FaultEffect::lin_responder_off && r.lin_node) {
    rule.commander = r.lin_node->node;  // match.from: the header's sender
  }
  if (f.match.mask != 0) {
    rule.id = static_cast<uint8_t>(f.match.id);
  }
  rule.count = f.count;
  rule.from = applied.start + SimDuration(f.at_ns);
  if (f.until_ns) {
    rule.until = applied.start + SimDuration(*f.until_ns);
  }
  applied.lin_rule = buses_[r.bus].lin_faults->add(rule);
}

void ScenarioRunner::arm(const std::string& name, const Resolved& r, std::size_t k, uint64_t seed,
                         AppliedFault& applied) {
  const FaultSpec& f = *r.spec;
  const std::shared_ptr<FaultSwitch>& state = applied.state;
  CanBus* const b = buses_[r.bus].bus;  // nullptr on a LIN bus (LIN effects use none)
  const SimTime start = applied.start;
  const SimTime at = start + SimDuration(f.at_ns);
  const std::string what = fault_label(name, f);
  switch (f.effect) {
    case FaultEffect::bit_error:
    case FaultEffect::stuff_error:
    case FaultEffect::form_error:
    case FaultEffect::crc_error:
    case FaultEffect::ack_error:
    case FaultEffect::random_errors:
      add_frame_rule(r, k, seed, what, applied);
      break;
    case FaultEffect::ack_suppress: {
      const SimTime until = at + SimDuration(f.duration_ns);
      when(at, state, [this, b, until, what] {
        b->suppress_acks_until(until);
        log(what);
      });
      break;
    }
    case FaultEffect::stuck_dominant: {
      const SimDuration d(f.duration_ns);
      when(at, state, [this, b, d, what] {
        b->hold_dominant(scheduler_.now(), d);
        log(what);
      });
      break;
    }
    case FaultEffect::node_off:
    case FaultEffect::node_on: {
      const NodeId node = r.node->id;
      const bool on = f.effect == FaultEffect::node_on;
      when(at, state, [this, b, node, on, what] {
        b->set_connected(node, on);
        log(what);
      });
      if (!on && f.until_ns) {
        when(start + SimDuration(*f.until_ns), state, [this, b, node, what] {
          b->set_connected(node, true);
          log(what + " ends");
        });
      }
      break;
    }
    case FaultEffect::bus_off:
    case FaultEffect::error_counters: {
      model::CanController* controller = r.node->controller;
      const NodeId node = r.node->id;
      const bool off = f.effect == FaultEffect::bus_off;
      const uint16_t tec = f.tec;
      const uint16_t rec = f.rec;
      when(at, state, [this, b, controller, node, off, tec, rec, what] {
        FaultConfinement& fc = controller->confinement();
        fc.set_counters(off ? kBusOffLimit : tec, off ? fc.rec() : rec);
        b->counters_changed(node);
        log(what);
      });
      break;
    }
    case FaultEffect::babble: {
      HostedNode* hosted = r.node->node;
      const Frame frame = *Frame::classic(f.id, f.data, f.ext);  // checked by the parser
      const SimDuration d(f.duration_ns);
      when(at, state, [this, hosted, frame, d, what, state] {
        if (hosted->babble(frame, scheduler_.now() + d)) {
          log(what);
        } else {
          --state->fired;  // it did nothing
          log(what +
              ": the node is not on the bus (its line is not started); nothing "
              "babbles");
        }
      });
      break;
    }
    case FaultEffect::line_error: {
      // The fault-tolerant transceiver sees the wire fault and says so (BUSCERR on a VCI
      // adapter). With one wire it goes on in single-wire mode; with both it is cut off.
      const NodeId node = r.node->id;
      // Held weakly: the adapter (and its line) may go before the fault ends, and a queued
      // event must not keep a line alive past its device or the simulation.
      const std::weak_ptr<model::ixxat::CanLine> weak_line =
          r.node->node != nullptr ? devices_.vci_line_of(r.node->node) : nullptr;
      // An X-CAN-2i interface: its module's transceiver reports it (XCAN_LINE_ERROR).
      const std::weak_ptr<XcanDevice> weak_xcan = r.node->xcan;
      const unsigned iface = r.node->iface;
      const bool both = f.both_wires;
      when(at, state, [this, b, node, weak_line, weak_xcan, iface, both, what] {
        if (auto line = weak_line.lock()) {
          line->set_bus_coupling_error(true);
        }
        if (auto xcan = weak_xcan.lock()) {
          xcan->module().set_line_error(iface, true);
        }
        if (both) {
          b->set_connected(node, false);
        }
        log(what);
      });
      if (f.until_ns) {
        when(start + SimDuration(*f.until_ns), state,
             [this, b, node, weak_line, weak_xcan, iface, both, what] {
               if (auto line = weak_line.lock()) {
                 line->set_bus_coupling_error(false);
               }
               if (auto xcan = weak_xcan.lock()) {
                 xcan->module().set_line_error(iface, false);
               }
               if (both) {
                 b->set_connected(node, true);
               }
               log(what + " ends");
             });
      }
      break;
    }
    case FaultEffect::lin_bit_error:
    case FaultEffect::lin_checksum_error:
    case FaultEffect::lin_parity_error:
    case FaultEffect::lin_sync_error:
    case FaultEffect::lin_no_response:
    case FaultEffect::lin_short_break:
    case FaultEffect::lin_responder_off:
      add_lin_rule(r, applied);
      break;
    case FaultEffect::lin_wakeup: {
      lin::LinBus* bus = buses_[r.bus].lin;
      const lin::LinNodeId node = r.lin_node->node;
      const SimDuration pulse(f.pulse_ns);
      when(at, state, [this, bus, node, pulse, what, state] {
        if (bus->send_wakeup(node, pulse)) {
          log(what);
        } else {
          --state->fired;  // it did nothing
          log(what + ": the node has a frame of its own pending; no wake-up pulse");
        }
      });
      break;
    }
    case FaultEffect::message_timeout:
    case FaultEffect::checksum_error:
    case FaultEffect::counter_freeze:
    case FaultEffect::counter_jump:
    case FaultEffect::signal_step:
    case FaultEffect::signal_ramp:
    case FaultEffect::signal_invalid:
      arm_restbus(applied, what);
      break;
    case FaultEffect::oscillator: {
      const NodeId node = r.node->id;
      const int32_t ppm = f.ppm;
      when(at, state, [this, b, node, ppm, what] {
        b->set_oscillator_ppm(node, ppm);
        log(what);
      });
      if (f.until_ns) {
        when(start + SimDuration(*f.until_ns), state, [this, b, node, what] {
          b->set_oscillator_ppm(node, 0);
          log(what + " ends");
        });
      }
      break;
    }
  }
}

}  // namespace canemu::daemon
