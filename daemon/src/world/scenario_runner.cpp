#include "canemu/daemon/world/scenario_runner.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"

namespace canemu::daemon {

using namespace canemu::model;

namespace {

// How the log names a fault: its scenario, line and effect.
std::string fault_label(std::string_view scenario, const FaultSpec& f) {
  return fmt::format("scenario \"{}\" line {}: {}", scenario, f.line, to_string(f.effect));
}

// The effects that become a rule in their bus's FaultPlan (or a LIN bus's LinFaultPlan).
bool is_frame_rule(FaultEffect e) {
  if (is_lin_frame_effect(e)) {
    return true;
  }
  switch (e) {
    case FaultEffect::bit_error:
    case FaultEffect::stuff_error:
    case FaultEffect::form_error:
    case FaultEffect::crc_error:
    case FaultEffect::ack_error:
    case FaultEffect::random_errors:
      return true;
    default:
      return false;
  }
}

}  // namespace

void ScenarioRunner::add_bus(CanBus& bus, const BusConfig& config, lin::LinBus* lin) {
  buses_.push_back(Bus{&bus, config, std::make_unique<FaultPlan>(), lin, nullptr});
  bus.set_injector(buses_.back().faults.get());
  const std::size_t index = buses_.size() - 1;
  buses_.back().faults->on_hit = [this, index](std::size_t rule, const FrameContext& ctx,
                                               const FrameFault&) {
    frame_fault_hit(index, rule, ctx);
  };
  if (lin != nullptr) {
    buses_.back().lin_faults = std::make_unique<lin::LinFaultPlan>();
    lin->set_fault_source(buses_.back().lin_faults.get());
    buses_.back().lin_faults->on_hit = [this, index](std::size_t rule, SimTime at, uint8_t id) {
      lin_fault_hit(index, rule, at, id);
    };
  }
}

void ScenarioRunner::lin_fault_hit(std::size_t bus, std::size_t rule, SimTime, uint8_t id) {
  const lin::LinFaultRule& r = buses_[bus].lin_faults->rule(rule);
  log_progress(bus, rule, true, r.hits, r.count, [id] { return fmt::format("frame {:02X}", id); });
}

void ScenarioRunner::log_progress(std::size_t bus, std::size_t rule, bool lin, uint64_t hits,
                                  const std::optional<uint64_t>& count,
                                  const std::function<std::string()>& what_was_hit) const {
  const bool first = hits == 1;
  const bool done = count && hits == *count;
  if (!first && !done) {
    return;  // single hits are in the trace and the counts
  }
  std::string label;
  for (const LoadedScenario& sc : scenarios_) {
    for (const AppliedFault& a : sc.faults) {
      if (a.bus == bus && (lin ? a.lin_rule : a.rule) == rule) {
        label = fault_label(sc.name, a.spec);
      }
    }
  }
  if (first) {
    log(fmt::format("{}: first hit, {}", label, what_was_hit()));
  }
  if (done) {
    log(fmt::format("{}: done, {} hit{}", label, hits, hits == 1 ? "" : "s"));
  }
}

std::optional<std::size_t> ScenarioRunner::bus_index(std::string_view name) const {
  for (std::size_t i = 0; i < buses_.size(); ++i) {
    if (buses_[i].config.name == name) {
      return i;
    }
  }
  return std::nullopt;
}

std::string ScenarioRunner::node_name(std::size_t bus, NodeId node) const {
  if (auto name = devices_.node_name(bus, node)) {
    return *name;
  }
  return fmt::format("node {} of {}", node, buses_[bus].config.name);
}

void ScenarioRunner::log(const std::string& text) const {
  log::info(log::At{"fault", scheduler_.now()}, "{}", text);
}

void ScenarioRunner::frame_fault_hit(std::size_t bus, std::size_t rule, const FrameContext& ctx) {
  const FaultRule& r = buses_[bus].faults->rule(rule);
  log_progress(bus, rule, false, r.hits, r.count, [&] {
    return fmt::format("{} {:X} from {}", ctx.frame.extended() ? "frame (29-bit)" : "frame",
                       ctx.frame.id(), node_name(bus, ctx.transmitter));
  });
}

tl::expected<std::vector<ScenarioRunner::Resolved>, std::vector<std::string>>
ScenarioRunner::resolve(const Scenario& s) const {
  std::vector<Resolved> plan;
  std::vector<std::string> errors;
  for (const FaultSpec& f : s.faults) {
    Resolved r{&f, 0, std::nullopt, std::nullopt};
    const auto where = [&](std::string_view what) {
      errors.push_back(fmt::format("{}:{}: {}: {}", s.source, f.line, to_string(f.effect), what));
    };
    const bool lin_effect = is_lin_frame_effect(f.effect) || f.effect == FaultEffect::lin_wakeup;
    if (!f.bus.empty()) {
      if (auto b = bus_index(f.bus)) {
        r.bus = *b;
        if (buses_[*b].config.kind == BusKind::lin && !lin_effect) {
          where(fmt::format("bus {} is a LIN bus; CAN faults need a CAN bus", f.bus));
          continue;
        }
        if (buses_[*b].config.kind != BusKind::lin && lin_effect) {
          where(fmt::format("bus {} is a CAN bus; LIN faults need a LIN bus", f.bus));
          continue;
        }
      } else {
        where(fmt::format("no bus named \"{}\"", f.bus));
        continue;
      }
    }
    if (lin_effect) {
      // LIN nodes: a LIN controller ("DEVICE:N") or a simulated node, by name.
      // Simulated nodes' names are scoped by bus: the rule's bus picks among nodes of one name.
      const std::string& lin_name = !f.node.empty() ? f.node : f.match.from;
      if (!lin_name.empty()) {
        const bool bare = lin_name.find_first_of("/:") == std::string::npos;
        if (find_lin_node && bare && !f.bus.empty()) {
          r.lin_node = find_lin_node(f.bus + "/" + lin_name);
        }
        if (!r.lin_node && find_lin_node) {
          r.lin_node = find_lin_node(lin_name);
        }
        if (!r.lin_node) {
          where(
              fmt::format("no LIN node named \"{}\" (a LIN controller DEVICE:N or a "
                          "[[lin_node]]; one of a name several buses have: with the rule's bus, "
                          "or as BUS/NAME)",
                          lin_name));
          continue;
        }
        if (!f.bus.empty() && r.lin_node->bus != r.bus) {
          where(fmt::format("node {} is not on bus {}", lin_name, f.bus));
          continue;
        }
        r.bus = r.lin_node->bus;
      }
      plan.push_back(r);
      continue;
    }
    const std::string& node_name = !f.node.empty() ? f.node : f.match.from;
    if (!node_name.empty()) {
      r.node = devices_.find_node(node_name);
      if (!r.node) {
        where(fmt::format("no node named \"{}\" (configured nodes are DEVICE:N)", node_name));
        continue;
      }
      if (!f.bus.empty() && r.node->bus != r.bus) {
        where(fmt::format("node {} is not on bus {}", node_name, f.bus));
        continue;
      }
      r.bus = r.node->bus;
      if (f.effect == FaultEffect::babble && r.node->node == nullptr) {
        where(
            fmt::format("node {} is {}; its driver sends only what its objects ask for, so it "
                        "cannot babble",
                        node_name, r.node->xcan ? "an X-CAN-2i interface" : "an SL-CANi S-Link"));
        continue;
      }
      if (f.effect == FaultEffect::line_error && !buses_[r.bus].config.low_speed) {
        where(
            fmt::format("node {} is on {}, a high-speed bus; wire faults are emulated on "
                        "low-speed buses (transceiver = \"low-speed\")",
                        node_name, buses_[r.bus].config.name));
        continue;
      }
    }
    plan.push_back(r);
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  return plan;
}

tl::expected<void, std::vector<std::string>> ScenarioRunner::apply(const Scenario& s, SimTime start,
                                                                   Owner owner) {
  auto plan = resolve(s);  // all or nothing
  if (!plan) {
    return tl::unexpected(plan.error());
  }
  const auto in_force = static_cast<std::size_t>(std::count_if(
      scenarios_.begin(), scenarios_.end(), [](const LoadedScenario& l) { return !l.cleared; }));
  if (in_force >= kMaxScenarios) {
    return tl::unexpected(std::vector<std::string>{
        fmt::format("{}: {} scenarios are in force already, the most canemud holds; clear one "
                    "first (canemu fault clear NAME)",
                    s.source, in_force)});
  }
  if (owner) {
    const auto mine = static_cast<std::size_t>(
        std::count_if(scenarios_.begin(), scenarios_.end(),
                      [&](const LoadedScenario& l) { return !l.cleared && l.owner == owner; }));
    if (mine >= kMaxScenariosPerUser) {
      return tl::unexpected(std::vector<std::string>{fmt::format(
          "{}: uid {} has {} scenarios in force, the most one user may; clear one first "
          "(canemu fault clear NAME)",
          s.source, *owner, mine)});
    }
  }
  std::vector<std::size_t> new_rules(buses_.size(), 0);
  std::size_t adding = 0;
  for (const Resolved& r : *plan) {
    new_rules[r.bus] += is_frame_rule(r.spec->effect) ? 1 : 0;
    adding += is_frame_rule(r.spec->effect) ? 1 : 0;
  }
  if (owner) {
    std::size_t held = 0;  // frame rules of the user's scenarios still matching frames
    for (const LoadedScenario& l : scenarios_) {
      if (!l.cleared && l.owner == owner) {
        held += static_cast<std::size_t>(
            std::count_if(l.faults.begin(), l.faults.end(),
                          [](const AppliedFault& f) { return f.rule || f.lin_rule; }));
      }
    }
    if (held + adding > kMaxRulesPerUser) {
      return tl::unexpected(std::vector<std::string>{
          fmt::format("{}: uid {} would have {} frame fault rules in force; one user may have {}",
                      s.source, *owner, held + adding, kMaxRulesPerUser)});
    }
  }
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    const std::size_t on_bus =
        buses_[b].faults->size() + (buses_[b].lin_faults ? buses_[b].lin_faults->size() : 0);
    if (on_bus + new_rules[b] > kMaxRulesPerBus) {
      return tl::unexpected(std::vector<std::string>{fmt::format(
          "{}: bus {} would have {} frame fault rules; at most {} are in force on a bus", s.source,
          buses_[b].config.name, on_bus + new_rules[b], kMaxRulesPerBus)});
    }
  }
  const uint64_t seed = s.seed.value_or(default_seed_);
  log(fmt::format("scenario \"{}\" ({}) applied: {} fault{}, seed {}", s.name, s.source,
                  s.faults.size(), s.faults.size() == 1 ? "" : "s", seed));
  LoadedScenario loaded{s.name, {}, false, owner};
  for (std::size_t k = 0; k < plan->size(); ++k) {
    const Resolved& r = (*plan)[k];
    const FaultSpec& f = *r.spec;
    AppliedFault applied{f,
                         r.bus,
                         !f.node.empty() ? f.node : buses_[r.bus].config.name,
                         start,
                         std::nullopt,
                         std::make_shared<FaultSwitch>(),
                         r.node ? r.node->node : nullptr,
                         0,
                         0,
                         std::nullopt};
    arm(s.name, r, k, seed, applied);
    loaded.faults.push_back(std::move(applied));
  }
  scenarios_.push_back(std::move(loaded));
  return {};
}

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
  CanBus& b = *buses_[r.bus].bus;
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
      when(at, state, [this, &b, until, what] {
        b.suppress_acks_until(until);
        log(what);
      });
      break;
    }
    case FaultEffect::stuck_dominant: {
      const SimDuration d(f.duration_ns);
      when(at, state, [this, &b, d, what] {
        b.hold_dominant(scheduler_.now(), d);
        log(what);
      });
      break;
    }
    case FaultEffect::node_off:
    case FaultEffect::node_on: {
      const NodeId node = r.node->id;
      const bool on = f.effect == FaultEffect::node_on;
      when(at, state, [this, &b, node, on, what] {
        b.set_connected(node, on);
        log(what);
      });
      if (!on && f.until_ns) {
        when(start + SimDuration(*f.until_ns), state, [this, &b, node, what] {
          b.set_connected(node, true);
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
      when(at, state, [this, &b, controller, node, off, tec, rec, what] {
        FaultConfinement& fc = controller->confinement();
        fc.set_counters(off ? kBusOffLimit : tec, off ? fc.rec() : rec);
        b.counters_changed(node);
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
      when(at, state, [this, &b, node, weak_line, weak_xcan, iface, both, what] {
        if (auto line = weak_line.lock()) {
          line->set_bus_coupling_error(true);
        }
        if (auto xcan = weak_xcan.lock()) {
          xcan->module().set_line_error(iface, true);
        }
        if (both) {
          b.set_connected(node, false);
        }
        log(what);
      });
      if (f.until_ns) {
        when(start + SimDuration(*f.until_ns), state,
             [this, &b, node, weak_line, weak_xcan, iface, both, what] {
               if (auto line = weak_line.lock()) {
                 line->set_bus_coupling_error(false);
               }
               if (auto xcan = weak_xcan.lock()) {
                 xcan->module().set_line_error(iface, false);
               }
               if (both) {
                 b.set_connected(node, true);
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
    case FaultEffect::oscillator: {
      const NodeId node = r.node->id;
      const int32_t ppm = f.ppm;
      when(at, state, [this, &b, node, ppm, what] {
        b.set_oscillator_ppm(node, ppm);
        log(what);
      });
      if (f.until_ns) {
        when(start + SimDuration(*f.until_ns), state, [this, &b, node, what] {
          b.set_oscillator_ppm(node, 0);
          log(what + " ends");
        });
      }
      break;
    }
  }
}

std::vector<ScenarioRunner::FaultStatus> ScenarioRunner::status() const {
  using State = FaultStatus::State;
  std::vector<FaultStatus> out;
  const SimTime now = scheduler_.now();
  for (const LoadedScenario& sc : scenarios_) {
    for (const AppliedFault& a : sc.faults) {
      const FaultSpec& f = a.spec;
      FaultStatus st{sc.name,
                     f.line,
                     f.effect,
                     a.target,
                     (a.start + SimDuration(f.at_ns)).ns(),
                     std::nullopt,
                     0,
                     a.state->fired,
                     State::pending};
      if (f.effect <= FaultEffect::ack_error) {
        st.frames = FaultStatus::Frames::can;
        st.match = f.match;
      } else if (is_lin_frame_effect(f.effect)) {
        st.frames = FaultStatus::Frames::lin;
        st.match = f.match;
      } else if (f.effect == FaultEffect::babble) {
        st.frames = FaultStatus::Frames::babble;
        st.match.id = f.id;
        st.match.mask = f.ext ? 0x1FFFFFFF : 0x7FF;
        st.match.ext = f.ext;
      }
      if (f.until_ns) {
        st.until_ns = (a.start + SimDuration(*f.until_ns)).ns();
      } else if (f.duration_ns > 0) {
        st.until_ns = st.at_ns + f.duration_ns;
      }
      bool over = st.until_ns && now.ns() >= *st.until_ns;
      if (a.rule || is_lin_frame_effect(f.effect)) {
        if (a.rule) {
          const FaultPlan& plan = *buses_[a.bus].faults;
          const bool live = plan.contains(*a.rule);
          st.seen = live ? plan.rule(*a.rule).seen : a.final_seen;
          st.hits = live ? plan.rule(*a.rule).hits : a.final_hits;
        } else {
          const lin::LinFaultPlan& plan = *buses_[a.bus].lin_faults;
          st.seen = a.lin_rule ? plan.rule(*a.lin_rule).seen : a.final_seen;
          st.hits = a.lin_rule ? plan.rule(*a.lin_rule).hits : a.final_hits;
        }
        over = over || (a.spec.count && st.hits >= *a.spec.count);
        st.state = now.ns() < st.at_ns ? State::pending : over ? State::done : State::active;
      } else if (now.ns() < st.at_ns) {
        st.state = State::pending;
      } else {  // fired (or found nothing to act on: a babble on a node off the bus)
        st.state = st.until_ns && !over && a.state->fired > 0 ? State::active : State::done;
      }
      if (a.state->cleared && st.state != State::done) {
        st.state = State::cleared;
      }
      out.push_back(st);
    }
  }
  return out;
}

std::size_t ScenarioRunner::clear(std::string_view name, const MayClear& may,
                                  std::size_t* refused) {
  std::size_t cleared = 0;
  for (LoadedScenario& sc : scenarios_) {
    if (sc.cleared || (!name.empty() && sc.name != name)) {
      continue;
    }
    if (may && !may(sc.owner)) {
      if (refused != nullptr) {
        ++*refused;
      }
      continue;
    }
    sc.cleared = true;
    ++cleared;
    for (AppliedFault& a : sc.faults) {
      a.state->cleared = true;
      retire(a);
    }
    log(fmt::format("scenario \"{}\" cleared", sc.name));
  }
  // Cleared scenarios stay for `fault list`, the newest kKeptCleared of them.
  std::size_t kept = 0;
  for (auto it = scenarios_.rbegin(); it != scenarios_.rend(); ++it) {
    kept += it->cleared ? 1 : 0;
  }
  for (auto it = scenarios_.begin(); it != scenarios_.end() && kept > kKeptCleared;) {
    if (it->cleared) {
      it = scenarios_.erase(it);
      --kept;
    } else {
      ++it;
    }
  }
  return cleared;
}

void ScenarioRunner::retire(AppliedFault& a) {
  FaultPlan& plan = *buses_[a.bus].faults;
  if (a.rule && plan.contains(*a.rule)) {
    a.final_seen = plan.rule(*a.rule).seen;
    a.final_hits = plan.rule(*a.rule).hits;
    plan.remove(*a.rule);
  }
  if (a.lin_rule) {
    lin::LinFaultPlan& lin_plan = *buses_[a.bus].lin_faults;
    a.final_seen = lin_plan.rule(*a.lin_rule).seen;
    a.final_hits = lin_plan.rule(*a.lin_rule).hits;
    lin_plan.disable(*a.lin_rule);
    a.lin_rule.reset();
    // Rules are kept by index while any is in force; when none is, the plan starts afresh (so
    // cleared scenarios cost no scanning).
    bool any = false;
    for (std::size_t i = 0; i < lin_plan.size(); ++i) {
      any = any || lin_plan.rule(i).enabled;
    }
    if (!any) {
      lin_plan.clear();
    }
  }
}

void ScenarioRunner::device_gone(std::string_view device, std::size_t bus, const HostedNode& node) {
  for (LoadedScenario& sc : scenarios_) {
    for (AppliedFault& a : sc.faults) {
      if (a.node != &node || a.state->cleared) {
        continue;
      }
      a.state->cleared = true;
      retire(a);
      log(fmt::format("{}: ends, device {} is gone", fault_label(sc.name, a.spec), device));
    }
  }
  CanBus& b = *buses_[bus].bus;
  b.set_connected(node.node(), true);
  b.set_oscillator_ppm(node.node(), 0);
}

}  // namespace canemu::daemon
