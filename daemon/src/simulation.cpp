#include "canemu/daemon/simulation.hpp"

#include <cmath>

#include <fmt/format.h>

#include "canemu/daemon/log.hpp"

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

namespace canemu::daemon {

using namespace canemu::model;

std::optional<HostedNodeSettings> controller_timing(bool fd, uint32_t bitrate,
                                                    uint32_t data_bitrate, uint32_t sample_point) {
  HostedNodeSettings s;
  if (!fd) {
    const auto btr = sja1000::btr_for(bitrate, sample_point);
    if (!btr) {
      return std::nullopt;
    }
    s.btr0 = btr->btr0;
    s.btr1 = btr->btr1;
    s.nominal = *sja1000::decode_btr(btr->btr0, btr->btr1);
    return s;
  }
  const auto nominal =
      ixxat::timing_for(bitrate, sample_point, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  const auto data =
      ixxat::timing_for(data_bitrate, sample_point, ixxat::kFdDataRange, ixxat::Phase::data);
  if (!nominal || !data) {
    return std::nullopt;
  }
  s.nominal = *nominal;
  s.data = *data;
  return s;
}

tl::expected<std::unique_ptr<Simulation>, std::vector<std::string>> Simulation::build(
    const Config& config) {
  std::unique_ptr<Simulation> sim(new Simulation(config));
  std::vector<std::string> errors;
  for (const BusConfig& b : sim->config_.buses) {
    sim->add_bus(b);
  }
  for (const DeviceConfig& d : sim->config_.devices) {
    if (auto error = sim->add_device(d)) {
      errors.push_back(*error);
    }
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  return sim;
}

void Simulation::add_bus(const BusConfig& b) {
  buses_.push_back(
      Bus{std::make_unique<CanBus>(scheduler_, b.name), std::make_unique<FaultPlan>()});
  buses_.back().bus->set_injector(buses_.back().faults.get());
  const std::size_t index = buses_.size() - 1;
  buses_.back().faults->on_hit = [this, index](std::size_t rule, const FrameContext& ctx,
                                               const FrameFault&) {
    frame_fault_hit(index, rule, ctx);
  };
  pools_.emplace_back();
}

std::string Simulation::node_name(std::size_t bus, NodeId node) const {
  for (const Controller& c : controllers_) {
    if (c.bus == bus && c.node->node() == node) {
      return c.name;
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.bus == bus && e.node->node() == node) {
      return e.name + ":0";
    }
  }
  return fmt::format("node {} of {}", node, config_.buses[bus].name);
}

namespace {

// How the log names a fault: its scenario, line and effect.
std::string fault_label(std::string_view scenario, const FaultSpec& f) {
  return fmt::format("scenario \"{}\" line {}: {}", scenario, f.line, to_string(f.effect));
}

}  // namespace

void Simulation::frame_fault_hit(std::size_t bus, std::size_t rule, const FrameContext& ctx) {
  const FaultRule& r = buses_[bus].faults->rule(rule);
  const bool first = r.hits == 1;
  const bool done = r.count && r.hits == *r.count;
  if (!first && !done) {
    return;  // single hits are in the trace and the counts
  }
  std::string label;
  for (const LoadedScenario& sc : scenarios_) {
    for (const AppliedFault& a : sc.faults) {
      if (a.bus == bus && a.rule == rule) {
        label = fault_label(sc.name, a.spec);
      }
    }
  }
  if (first) {
    fault_log(fmt::format("{}: first hit, {} {:X} from {}", label,
                          ctx.frame.extended() ? "frame (29-bit)" : "frame", ctx.frame.id(),
                          node_name(bus, ctx.transmitter)));
  }
  if (done) {
    fault_log(fmt::format("{}: done, {} hit{}", label, r.hits, r.hits == 1 ? "" : "s"));
  }
}

std::optional<Simulation::NodeRef> Simulation::find_node(std::string_view name) {
  for (Controller& c : controllers_) {
    if (c.name == name) {
      return NodeRef{c.bus, c.node->node(), &c.node->controller(), c.node.get()};
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.name == name || e.name + ":0" == name) {
      return NodeRef{e.bus, e.node->node(), &e.node->controller(), e.node};
    }
  }
  return std::nullopt;
}

void Simulation::fault_log(const std::string& text) {
  log::info(log::At{"fault", scheduler_.now()}, "{}", text);
}

tl::expected<void, std::vector<std::string>> Simulation::apply_scenario(const Scenario& s,
                                                                        SimTime start) {
  // Resolve everything first: all or nothing.
  struct Resolved {
    const FaultSpec* spec;
    std::size_t bus = 0;
    std::optional<NodeRef> node;  // node effects; frame effects with match.from
  };
  std::vector<Resolved> plan;
  std::vector<std::string> errors;
  for (const FaultSpec& f : s.faults) {
    Resolved r{&f, 0, std::nullopt};
    const auto where = [&](std::string_view what) {
      errors.push_back(fmt::format("{}:{}: {}: {}", s.source, f.line, to_string(f.effect), what));
    };
    if (!f.bus.empty()) {
      if (auto b = bus_index(f.bus)) {
        r.bus = *b;
        if (config_.buses[*b].kind == BusKind::lin) {
          where(fmt::format("bus {} is a LIN bus; CAN faults need a CAN bus", f.bus));
          continue;
        }
      } else {
        where(fmt::format("no bus named \"{}\"", f.bus));
        continue;
      }
    }
    const std::string& node_name = !f.node.empty() ? f.node : f.match.from;
    if (!node_name.empty()) {
      r.node = find_node(node_name);
      if (!r.node) {
        where(fmt::format("no node named \"{}\" (configured nodes are DEVICE:N)", node_name));
        continue;
      }
      if (!f.bus.empty() && r.node->bus != r.bus) {
        where(fmt::format("node {} is not on bus {}", node_name, f.bus));
        continue;
      }
      r.bus = r.node->bus;
      if (f.effect == FaultEffect::line_error && !config_.buses[r.bus].low_speed) {
        where(
            fmt::format("node {} is on {}, a high-speed bus; wire faults are emulated on "
                        "low-speed buses (transceiver = \"low-speed\")",
                        node_name, config_.buses[r.bus].name));
        continue;
      }
    }
    plan.push_back(r);
  }
  if (!errors.empty()) {
    return tl::unexpected(errors);
  }
  const uint64_t seed = s.seed.value_or(config_.simulation.seed);
  fault_log(fmt::format("scenario \"{}\" ({}) applied: {} fault{}, seed {}", s.name, s.source,
                        s.faults.size(), s.faults.size() == 1 ? "" : "s", seed));
  LoadedScenario loaded{s.name, {}, false};
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const FaultSpec& f = *plan[k].spec;
    const std::size_t bus = plan[k].bus;
    auto state = std::make_shared<FaultSwitch>();
    // A fault due now takes effect at once (before any frame that starts now); later ones when
    // due, unless cleared by then.
    const auto when = [this, state](SimTime at, std::function<void()> fire) {
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
    };
    AppliedFault applied{f,
                         bus,
                         !f.node.empty() ? f.node : config_.buses[bus].name,
                         start,
                         std::nullopt,
                         state,
                         plan[k].node ? plan[k].node->hosted : nullptr};
    CanBus& b = *buses_[bus].bus;
    const SimTime at = start + SimDuration(f.at_ns);
    const std::string what = fault_label(s.name, f);
    switch (f.effect) {
      case FaultEffect::bit_error:
      case FaultEffect::stuff_error:
      case FaultEffect::form_error:
      case FaultEffect::crc_error:
      case FaultEffect::ack_error:
      case FaultEffect::random_errors: {
        FaultRule rule;
        if (plan[k].node) {
          rule.match.transmitter = plan[k].node->node;
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
        rule.from = at;
        if (f.until_ns) {
          rule.until = start + SimDuration(*f.until_ns);
        }
        rule.probability = f.probability;
        rule.seed = seed * 0x9E3779B97F4A7C15ull + k + 1;  // each fault its own draws
        applied.rule = buses_[bus].faults->add(rule);
        if (rule.until) {  // the end of its window, with what it did
          const std::size_t index = *applied.rule;
          when(*rule.until, [this, bus, index, what] {
            const uint64_t hits = buses_[bus].faults->rule(index).hits;
            const auto& count = buses_[bus].faults->rule(index).count;
            if (!count || hits < *count) {
              fault_log(fmt::format("{}: window over, {} hit{}", what, hits, hits == 1 ? "" : "s"));
            }
          });
        }
        break;
      }
      case FaultEffect::ack_suppress: {
        const SimTime until = at + SimDuration(f.duration_ns);
        when(at, [this, &b, until, what] {
          b.suppress_acks_until(until);
          fault_log(what);
        });
        break;
      }
      case FaultEffect::stuck_dominant: {
        const SimDuration d(f.duration_ns);
        when(at, [this, &b, d, what] {
          b.hold_dominant(scheduler_.now(), d);
          fault_log(what);
        });
        break;
      }
      case FaultEffect::node_off:
      case FaultEffect::node_on: {
        const NodeId node = plan[k].node->node;
        const bool on = f.effect == FaultEffect::node_on;
        when(at, [this, &b, node, on, what] {
          b.set_connected(node, on);
          fault_log(what);
        });
        if (!on && f.until_ns) {
          when(start + SimDuration(*f.until_ns), [this, &b, node, what] {
            b.set_connected(node, true);
            fault_log(what + " ends");
          });
        }
        break;
      }
      case FaultEffect::bus_off:
      case FaultEffect::error_counters: {
        const NodeRef n = *plan[k].node;
        const bool off = f.effect == FaultEffect::bus_off;
        const uint16_t tec = f.tec;
        const uint16_t rec = f.rec;
        when(at, [this, &b, n, off, tec, rec, what] {
          FaultConfinement& fc = n.controller->confinement();
          fc.set_counters(off ? kBusOffLimit : tec, off ? fc.rec() : rec);
          b.counters_changed(n.node);
          fault_log(what);
        });
        break;
      }
      case FaultEffect::babble: {
        HostedNode* hosted = plan[k].node->hosted;
        const Frame frame = *Frame::classic(f.id, f.data, f.ext);  // checked by the parser
        const SimDuration d(f.duration_ns);
        when(at, [this, hosted, frame, d, what, state] {
          if (hosted->babble(frame, scheduler_.now() + d)) {
            fault_log(what);
          } else {
            --state->fired;  // it did nothing
            fault_log(what +
                      ": the node is not on the bus (its line is not started); nothing "
                      "babbles");
          }
        });
        break;
      }
      case FaultEffect::line_error: {
        // The fault-tolerant transceiver sees the wire fault and says so (BUSCERR on a VCI
        // adapter). With one wire it goes on in single-wire mode; with both it is cut off.
        const NodeId node = plan[k].node->node;
        auto line = vci_line_of(plan[k].node->hosted);
        const bool both = f.both_wires;
        when(at, [this, &b, node, line, both, what] {
          if (line) {
            line->set_bus_coupling_error(true);
          }
          if (both) {
            b.set_connected(node, false);
          }
          fault_log(what);
        });
        if (f.until_ns) {
          when(start + SimDuration(*f.until_ns), [this, &b, node, line, both, what] {
            if (line) {
              line->set_bus_coupling_error(false);
            }
            if (both) {
              b.set_connected(node, true);
            }
            fault_log(what + " ends");
          });
        }
        break;
      }
      case FaultEffect::oscillator: {
        const NodeId node = plan[k].node->node;
        const int32_t ppm = f.ppm;
        when(at, [this, &b, node, ppm, what] {
          b.set_oscillator_ppm(node, ppm);
          fault_log(what);
        });
        if (f.until_ns) {
          when(start + SimDuration(*f.until_ns), [this, &b, node, what] {
            b.set_oscillator_ppm(node, 0);
            fault_log(what + " ends");
          });
        }
        break;
      }
    }
    loaded.faults.push_back(std::move(applied));
  }
  scenarios_.push_back(std::move(loaded));
  return {};
}

std::optional<std::string> Simulation::add_device(const DeviceConfig& d) {
  // Every controller's timing first, so that a device is added whole or not at all.
  struct Plan {
    std::size_t bus;
    HostedNodeSettings timing;
  };
  std::vector<Plan> plans;
  for (const std::string& bus_name : d.controllers) {
    Plan p{};
    p.bus = *bus_index(bus_name);
    const BusConfig& bc = config_.buses[p.bus];
    // Checked against the bus as it runs (a reload leaves changed buses as they were).
    if (bc.kind == BusKind::lin) {
      return fmt::format("{}:{}: device {}: bus {} is a LIN bus; a CAN controller cannot sit on it",
                         config_.source, d.line, d.name, bc.name);
    }
    const bool fd = d.model != DeviceModel::ixxat_usb_to_can;
    const auto timing = controller_timing(
        fd, bc.bitrate, bc.data_bitrate != 0 ? bc.data_bitrate : bc.bitrate, bc.sample_point);
    if (!timing) {
      return fmt::format("{}:{}: device {}: {} cannot run bus {} at {} bit/s", config_.source,
                         d.line, d.name, fd ? "the CAN FD controller" : "an SJA1000 at 16 MHz",
                         bc.name, bc.bitrate);
    }
    p.timing = *timing;
    plans.push_back(p);
  }
  for (std::size_t i = 0; i < plans.size(); ++i) {
    const Plan& p = plans[i];
    Controller c;
    c.name = fmt::format("{}:{}", d.name, i);
    c.bus = p.bus;
    // The controller stays in reset (off the bus) until an application initializes and starts
    // it through the VCI, as on a real adapter.
    CanBus& bus = *buses_[p.bus].bus;
    if (d.model == DeviceModel::ixxat_usb_to_can) {
      c.node = std::make_unique<Sja1000Node>(scheduler_, bus);
    } else {
      c.node = std::make_unique<CanFdNode>(scheduler_, bus);
    }
    c.line =
        std::make_shared<ixxat::CanLine>(scheduler_, *c.node, ixxat::Clocks{}, scheduler_.now());
    c.line->set_low_speed(config_.buses[p.bus].low_speed);
    controllers_.push_back(std::move(c));
  }
  vci_ids_[d.name] = next_vci_id_++;
  return std::nullopt;
}

std::shared_ptr<ixxat::CanLine> Simulation::vci_line_of(const HostedNode* node) const {
  for (const Controller& c : controllers_) {
    if (c.node.get() == node) {
      return c.line;
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.node == node) {
      return e.line;
    }
  }
  return nullptr;
}

std::shared_ptr<ixxat::CanLine> Simulation::vci_line(std::string_view device, uint32_t controller) {
  const std::string name = fmt::format("{}:{}", device, controller);
  for (Controller& c : controllers_) {
    if (c.name == name) {
      return c.line;
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.line && e.name == device && controller == 0) {
      return e.line;
    }
  }
  return nullptr;
}

std::string hardware_id(std::string_view device_name) {
  uint32_t h = 2166136261U;  // FNV-1a
  for (char ch : device_name) {
    h = (h ^ static_cast<uint8_t>(ch)) * 16777619U;
  }
  return fmt::format("HW{:06}", h % 1'000'000);
}

namespace {

bool same(const BusConfig& a, const BusConfig& b) {
  return a.name == b.name && a.kind == b.kind && a.bitrate == b.bitrate &&
         a.sample_point == b.sample_point && a.data_bitrate == b.data_bitrate;
}

bool same(const DeviceConfig& a, const DeviceConfig& b) {
  return a.name == b.name && a.model == b.model && a.controllers == b.controllers;
}

template <class T>
const T* find_named(const std::vector<T>& items, const std::string& name) {
  for (const T& item : items) {
    if (item.name == name) {
      return &item;
    }
  }
  return nullptr;
}

}  // namespace

ReloadReport Simulation::reload(const Config& fresh) {
  ReloadReport r;
  // What cannot change while the simulation runs.
  if (fresh.simulation.time.mode != config_.simulation.time.mode ||
      fresh.simulation.time.scale != config_.simulation.time.scale) {
    r.refused.push_back(fmt::format("simulation.time: stays {} (a restart changes it)",
                                    to_string(config_.simulation.time)));
  }
  if (fresh.simulation.seed != config_.simulation.seed) {
    r.refused.push_back(
        fmt::format("simulation.seed: stays {} (a restart changes it)", config_.simulation.seed));
  }
  for (const BusConfig& old : config_.buses) {
    const BusConfig* now = find_named(fresh.buses, old.name);
    if (now == nullptr) {
      r.refused.push_back(
          fmt::format("bus {}: still there (buses are removed by a restart)", old.name));
    } else if (!same(old, *now)) {
      r.refused.push_back(
          fmt::format("bus {}: keeps its settings ({} at {} bit/s; a restart changes them)",
                      old.name, to_string(old.kind), old.bitrate));
    }
  }
  for (const DeviceConfig& old : config_.devices) {
    const DeviceConfig* now = find_named(fresh.devices, old.name);
    if (now == nullptr) {
      r.refused.push_back(
          fmt::format("device {}: still there (devices are removed by a restart)", old.name));
    } else if (!same(old, *now)) {
      r.refused.push_back(
          fmt::format("device {}: keeps its settings (a restart changes them)", old.name));
    }
  }
  // What can: new buses and devices, the security lists, the wake-up tuning.
  for (const BusConfig& b : fresh.buses) {
    if (find_named(config_.buses, b.name) == nullptr) {
      config_.buses.push_back(b);
      add_bus(b);
      r.applied.push_back(
          fmt::format("bus {}: added ({} at {} bit/s)", b.name, to_string(b.kind), b.bitrate));
    }
  }
  for (const DeviceConfig& d : fresh.devices) {
    if (find_named(config_.devices, d.name) != nullptr) {
      continue;
    }
    if (device_exists(d.name)) {
      r.refused.push_back(fmt::format("device {}: an ephemeral device has that name", d.name));
    } else if (auto error = add_device(d)) {
      r.refused.push_back(*error);
    } else {
      config_.devices.push_back(d);
      ++generation_;
      if (on_device_change) {
        on_device_change(ipc::NotificationKind::device_added, d.name);
      }
      r.applied.push_back(fmt::format("device {}: added", d.name));
    }
  }
  if (fresh.security.allowed_users != config_.security.allowed_users ||
      fresh.security.allowed_groups != config_.security.allowed_groups) {
    config_.security = fresh.security;
    r.applied.push_back("security: allowed users and groups replaced");
  }
  if (fresh.simulation.batch_us != config_.simulation.batch_us ||
      fresh.simulation.spin_us != config_.simulation.spin_us) {
    config_.simulation.batch_us = fresh.simulation.batch_us;
    config_.simulation.spin_us = fresh.simulation.spin_us;
    r.applied.push_back(fmt::format("simulation: batch_us {}, spin_us {}",
                                    config_.simulation.batch_us, config_.simulation.spin_us));
  }
  return r;
}

std::vector<Simulation::FaultStatus> Simulation::fault_status() const {
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
      if (f.until_ns) {
        st.until_ns = (a.start + SimDuration(*f.until_ns)).ns();
      } else if (f.duration_ns > 0) {
        st.until_ns = st.at_ns + f.duration_ns;
      }
      bool over = st.until_ns && now.ns() >= *st.until_ns;
      if (a.rule) {
        const FaultRule& rule = buses_[a.bus].faults->rule(*a.rule);
        st.seen = rule.seen;
        st.hits = rule.hits;
        over = over || (rule.count && rule.hits >= *rule.count);
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

std::size_t Simulation::clear_scenarios(std::string_view name) {
  std::size_t cleared = 0;
  for (LoadedScenario& sc : scenarios_) {
    if (sc.cleared || (!name.empty() && sc.name != name)) {
      continue;
    }
    sc.cleared = true;
    ++cleared;
    for (AppliedFault& a : sc.faults) {
      a.state->cleared = true;
      if (a.rule) {
        buses_[a.bus].faults->disable(*a.rule);
      }
    }
    fault_log(fmt::format("scenario \"{}\" cleared", sc.name));
  }
  return cleared;
}

void Simulation::fill_status(ipc::StatusReply& r) {
  const SimTime now = scheduler_.now();
  r.sim_time_ns = now.ns();
  r.bus_count = static_cast<uint16_t>(std::min(buses_.size(), ipc::kMaxStatusBuses));
  for (std::size_t i = 0; i < r.bus_count; ++i) {
    const Bus& b = buses_[i];
    ipc::StatusBus& s = r.buses[i];
    ipc::copy_name(s.name, config_.buses[i].name);
    s.kind = static_cast<uint8_t>(config_.buses[i].kind);
    s.low_speed = config_.buses[i].low_speed ? 1 : 0;
    s.bitrate = config_.buses[i].bitrate;
    s.data_bitrate = config_.buses[i].data_bitrate;
    s.load_permille = static_cast<uint32_t>(b.bus->bus_load_percent(now) * 10 + 0.5);
    s.frames = b.bus->frames_on_bus();
    s.error_frames = b.bus->error_frames_on_bus();
  }
  std::size_t n = 0;
  auto add_node = [&](const std::string& name, std::size_t bus, CanController& controller,
                      NodeId node) {
    if (n == ipc::kMaxStatusNodes) {
      return;
    }
    ipc::StatusNode& s = r.nodes[n++];
    ipc::copy_name(s.name, name);
    s.bus = static_cast<uint16_t>(bus);
    FaultConfinement& fc = controller.confinement();
    s.state = static_cast<uint8_t>(fc.state());
    s.tec = fc.tec();
    s.rec = fc.rec();
    const NodeStats& st = buses_[bus].bus->stats(node);
    s.frames_sent = st.frames_sent;
    s.frames_received = st.frames_received;
    s.errors = st.errors_as_transmitter.total() + st.errors_as_receiver.total();
  };
  for (Controller& c : controllers_) {
    add_node(c.name, c.bus, c.node->controller(), c.node->node());
  }
  for (const Ephemeral& e : ephemeral_) {
    add_node(e.name + ":0", e.bus, e.node->controller(), e.node->node());
  }
  r.node_count = static_cast<uint16_t>(n);
}

void Simulation::fill_devices(ipc::DeviceListReply& r) const {
  r.generation = generation_;
  r.total = static_cast<uint16_t>(config_.devices.size() + ephemeral_.size());
  std::size_t n = 0;
  for (const DeviceConfig& d : config_.devices) {
    if (n == ipc::kMaxDevices) {
      break;
    }
    ipc::DeviceEntry& e = r.devices[n++];
    ipc::copy_name(e.name, d.name);
    e.model = static_cast<uint8_t>(d.model == DeviceModel::ixxat_usb_to_can
                                       ? ipc::WireDeviceModel::ixxat_usb_to_can
                                       : ipc::WireDeviceModel::ixxat_usb_to_can_fd);
    e.controller_count = static_cast<uint8_t>(d.controllers.size());
    for (std::size_t k = 0; k < d.controllers.size() && k < ipc::kMaxDeviceControllers; ++k) {
      ipc::copy_name(e.buses[k], d.controllers[k]);
      e.controller_fd[k] = d.model == DeviceModel::ixxat_usb_to_can ? 0 : 1;
    }
    if (auto id = vci_ids_.find(d.name); id != vci_ids_.end()) {
      e.vci_id = id->second;
    }
    const std::string first = d.name + ":0";
    for (const Controller& c : controllers_) {
      if (c.name == first && c.line) {
        e.epoch_ns = c.line->epoch().ns();
      }
    }
    ipc::copy_name(e.hardware_id, hardware_id(d.name));
  }
  for (const Ephemeral& x : ephemeral_) {
    if (n == ipc::kMaxDevices) {
      break;
    }
    ipc::DeviceEntry& e = r.devices[n++];
    ipc::copy_name(e.name, x.name);
    e.model = static_cast<uint8_t>(ipc::WireDeviceModel::ephemeral);
    e.controller_count = 1;
    e.ephemeral = 1;
    e.owner_pid = x.owner_pid;
    ipc::copy_name(e.buses[0], config_.buses[x.bus].name);
    if (x.line) {  // a VCI adapter
      const bool fd = x.line->fd_controller();
      e.model = static_cast<uint8_t>(fd ? ipc::WireDeviceModel::ixxat_usb_to_can_fd
                                        : ipc::WireDeviceModel::ixxat_usb_to_can);
      e.controller_fd[0] = fd ? 1 : 0;
      e.vci_id = x.vci_id;
      e.epoch_ns = x.line->epoch().ns();
      ipc::copy_name(e.hardware_id, hardware_id(x.name));
    }
  }
  r.count = static_cast<uint16_t>(n);
}

std::optional<std::size_t> Simulation::bus_index(std::string_view name) const {
  for (std::size_t i = 0; i < config_.buses.size(); ++i) {
    if (config_.buses[i].name == name) {
      return i;
    }
  }
  return std::nullopt;
}

HostedNode& Simulation::spare_node(std::size_t bus) {
  for (auto& node : pools_[bus]) {
    if (node->reusable()) {
      return *node;
    }
  }
  if (config_.buses[bus].kind == BusKind::can_fd) {
    pools_[bus].push_back(std::make_unique<CanFdNode>(scheduler_, *buses_[bus].bus));
  } else {
    pools_[bus].push_back(std::make_unique<Sja1000Node>(scheduler_, *buses_[bus].bus));
  }
  return *pools_[bus].back();
}

bool Simulation::device_exists(std::string_view name) const {
  for (const DeviceConfig& d : config_.devices) {
    if (d.name == name) {
      return true;
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.name == name) {
      return true;
    }
  }
  return false;
}

std::string Simulation::unique_device_name(std::string_view prefix) const {
  for (uint64_t k = 1;; ++k) {
    std::string name = fmt::format("{}{}", prefix, k);
    if (!device_exists(name)) {
      return name;
    }
  }
}

Simulation::DeviceLease Simulation::add_vci_device(std::string name, std::size_t bus,
                                                   uint32_t owner_pid) {
  HostedNode& node = spare_node(bus);
  // Powered on at the last whole microsecond: the time stamps of every adapter then tick
  // together (1 us), and the same frame carries the same time stamp on all of them.
  const int64_t now_ns = scheduler_.now().ns();
  const SimTime power_on = SimTime::from_ns(now_ns - now_ns % 1000);
  auto line = std::make_shared<ixxat::CanLine>(scheduler_, node, ixxat::Clocks{}, power_on);
  line->set_low_speed(config_.buses[bus].low_speed);
  DeviceLease lease = add_ephemeral(name, bus, node, owner_pid);
  ephemeral_.back().line = std::move(line);
  ephemeral_.back().vci_id = next_vci_id_++;
  return lease;
}

uint64_t Simulation::vci_id_of(std::string_view device) const {
  if (auto it = vci_ids_.find(device); it != vci_ids_.end()) {
    return it->second;
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.line && e.name == device) {
      return e.vci_id;
    }
  }
  return 0;
}

Simulation::DeviceLease Simulation::add_ephemeral(std::string name, std::size_t bus,
                                                  HostedNode& node, uint32_t owner_pid) {
  ephemeral_.push_back(Ephemeral{name, bus, &node, owner_pid, nullptr, 0});
  ++generation_;
  if (on_device_change) {
    on_device_change(ipc::NotificationKind::device_added, name);
  }
  return DeviceLease(this, std::move(name));
}

void Simulation::remove_ephemeral(const std::string& name) {
  for (const Ephemeral& e : ephemeral_) {
    if (e.name == name) {
      end_node_faults(e);
    }
  }
  std::erase_if(ephemeral_, [&](const Ephemeral& e) { return e.name == name; });
  ++generation_;
  if (on_device_change) {
    on_device_change(ipc::NotificationKind::device_removed, name);
  }
}

void Simulation::end_node_faults(const Ephemeral& e) {
  // Faults that name the device end with it; its node, kept for a later device, comes back
  // plugged in and on its nominal clock.
  for (LoadedScenario& sc : scenarios_) {
    for (AppliedFault& a : sc.faults) {
      if (a.node != e.node || a.state->cleared) {
        continue;
      }
      a.state->cleared = true;
      if (a.rule) {
        buses_[a.bus].faults->disable(*a.rule);
      }
      fault_log(fmt::format("{}: ends, device {} is gone", fault_label(sc.name, a.spec), e.name));
    }
  }
  CanBus& bus = *buses_[e.bus].bus;
  bus.set_connected(e.node->node(), true);
  bus.set_oscillator_ppm(e.node->node(), 0);
}

Simulation::DeviceLease::~DeviceLease() {
  if (sim_ != nullptr) {
    sim_->remove_ephemeral(name_);
  }
}

}  // namespace canemu::daemon
