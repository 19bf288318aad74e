// What runs of the scenarios (`canemu fault list`), scenarios cleared, and faults that end
// because their device went.
#include <algorithm>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/world/scenario_runner.hpp"
#include "world/fault_label.hpp"

namespace canemu::daemon {

using namespace canemu::model;

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
      if (f.effect <= FaultEffect::ack_error || a.ecu != nullptr) {
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
      } else if (a.checksum) {  // checksum_error: the frames it made wrong
        st.hits = a.checksum->hits;
        over = over || (f.count && st.hits >= *f.count);
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
      ++generation_;
    } else {
      ++it;
    }
  }
  return cleared;
}

void ScenarioRunner::retire(AppliedFault& a) {
  if (a.rule && buses_[a.bus].faults->contains(*a.rule)) {
    FaultPlan& plan = *buses_[a.bus].faults;
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

void ScenarioRunner::device_gone(std::string_view what, std::size_t bus, const HostedNode& node) {
  for (LoadedScenario& sc : scenarios_) {
    for (AppliedFault& a : sc.faults) {
      if (a.node != &node || a.state->cleared) {
        continue;
      }
      a.state->cleared = true;
      retire(a);
      log(fmt::format("{}: ends, {} is gone", fault_label(sc.name, a.spec), what));
    }
  }
  CanBus& b = *buses_[bus].bus;
  b.set_connected(node.node(), true);
  b.set_oscillator_ppm(node.node(), 0);
}

}  // namespace canemu::daemon
