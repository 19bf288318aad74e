#include "canemu/daemon/world/scenario_runner.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "world/fault_label.hpp"

namespace canemu::daemon {

using namespace canemu::model;

namespace {

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

void ScenarioRunner::add_bus(CanBus* can, const BusConfig& config, lin::LinBus* lin) {
  Bus& b = buses_.emplace_back(Bus{can, config, nullptr, lin, nullptr});
  const std::size_t index = buses_.size() - 1;
  if (can != nullptr) {
    b.faults = std::make_unique<FaultPlan>();
    can->set_injector(b.faults.get());
    b.faults->on_hit = [this, index](std::size_t rule, const FrameContext& ctx, const FrameFault&) {
      frame_fault_hit(index, rule, ctx);
    };
  }
  if (lin != nullptr) {
    b.lin_faults = std::make_unique<lin::LinFaultPlan>();
    lin->set_fault_source(b.lin_faults.get());
    b.lin_faults->on_hit = [this, index](std::size_t rule, SimTime at, uint8_t id) {
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
    if (is_restbus_effect(f.effect)) {
      const auto ecu = find_can_message ? find_can_message(f.bus, f.message) : std::nullopt;
      if (!ecu) {
        where(fmt::format("no simulated CAN node sends a message named \"{}\" on {}", f.message,
                          f.bus));
        continue;
      }
      if (auto problem = restbus_problem(f, *ecu->ecu); !problem.empty()) {
        where(problem);
        continue;
      }
      r.ecu = ecu->ecu;
      plan.push_back(r);
      continue;
    }
    const std::string& node_name = !f.node.empty() ? f.node : f.match.from;
    if (!node_name.empty()) {
      r.node = find_node(node_name);
      if (!r.node) {
        where(fmt::format(
            "no node named \"{}\" (configured nodes are DEVICE:N; simulated CAN nodes NAME, or "
            "BUS/NAME where several buses have that NAME)",
            node_name));
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
    const std::size_t on_bus = (buses_[b].faults ? buses_[b].faults->size() : 0) +
                               (buses_[b].lin_faults ? buses_[b].lin_faults->size() : 0);
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
                         std::nullopt,
                         nullptr,
                         nullptr};
    if (r.ecu != nullptr) {  // a message or signal of a simulated CAN node
      applied.ecu = r.ecu;
      applied.node = &r.ecu->node();
      applied.target =
          fmt::format("{}/{}{}{}", f.bus, f.message, f.signal.empty() ? "" : ".", f.signal);
      // `fault list` shows the message's frames as the fault's MATCH.
      if (const CanMessageConfig* m = r.ecu->message_config(f.message)) {
        applied.spec.match.id = m->id;
        applied.spec.match.mask = 0x1FFFFFFF;
        applied.spec.match.ext = m->extended;
      }
    }
    arm(s.name, r, k, seed, applied);
    loaded.faults.push_back(std::move(applied));
  }
  scenarios_.push_back(std::move(loaded));
  return {};
}

}  // namespace canemu::daemon
