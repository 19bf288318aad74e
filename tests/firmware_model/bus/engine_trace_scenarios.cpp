// The scenario half of the engine trace (engine_trace.hpp): random buses, random traffic and a
// random plan of everything a caller may do to the bus while it runs, played through CanBus with
// every callback, statistic and counter written out.
//
// The plan (engine_trace_plan.hpp) is a function of the scenario's seed alone, so the actions a
// scenario takes do not depend on what the engine does; only the controllers' own reactions (a
// host restarting its controller after bus-off, a reply to a remote frame) do, as they would in
// a firmware model. Actions run between events: the scheduler first runs every event due at or
// before the action's instant.
#include <algorithm>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "engine_trace.hpp"
#include "engine_trace_plan.hpp"

namespace canemu::model::testing::engine_trace {
namespace {

using C = ScenarioCountNames::Id;

const char* state_text(ErrorState s) {
  switch (s) {
    case ErrorState::active:
      return "A";
    case ErrorState::warning:
      return "W";
    case ErrorState::passive:
      return "P";
    case ErrorState::bus_off:
      return "OFF";
  }
  return "?";
}

// --- the run ---

class Scenario;

// A controller that sends what it is given, in order, and writes down everything the bus tells
// it; its host restarts it after bus-off if its setup says so.
class TraceController final : public CanController {
 public:
  TraceController(Scenario& s, const NodeSetup& setup)
      : scenario_(s), setup_(setup), fc(setup.rec_limit) {
    fc.set_warning_limit(setup.warning_limit);
  }

  NodeTiming timing() const override { return timing_; }
  bool participating() const override { return running; }
  bool listen_only() const override { return listen; }
  bool self_test() const override { return self_test_mode; }
  bool fd_capable() const override { return fd; }
  BusOffRecovery bus_off_recovery() const override { return setup_.recovery; }
  const TxFrame* pending_tx() override { return current ? &*current : nullptr; }
  FaultConfinement& confinement() override { return fc; }

  void on_frame(SimTime at, const Frame& f, bool own) override;
  void on_tx_done(SimTime at) override;
  void on_tx_dropped(SimTime at) override;
  void on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed_bit) override;
  void on_error(const BusErrorEvent& e) override;
  void on_state_change(SimTime at, ErrorState state) override;

  void send(const TxFrame& f);
  // The next frame of the backlog becomes the pending one.
  void next();

  NodeId id = 0;
  NodeTiming timing_;
  bool running = true;
  bool listen = false;
  bool self_test_mode = false;
  bool fd = false;
  std::optional<TxFrame> current;
  std::deque<TxFrame> backlog;

 private:
  Scenario& scenario_;
  const NodeSetup setup_;
  bool was_bus_off_ = false;

 public:
  FaultConfinement fc;
};

class Scenario final : public FaultInjector {
 public:
  Scenario(std::size_t k, std::string& out, ScenarioCounts& counts)
      : out_(out), counts_(counts), seed_(item_seed(kScenarioSeed, k)) {
    Rng rng(seed_);
    plan_ = make_plan(rng);
    appendf(out_, "scenario %zu seed 0x%016llx %s nominal %s", k,
            static_cast<unsigned long long>(seed_), plan_.fd_bus ? "fd" : "classic",
            timing_text(plan_.fd_bus ? kFdNominal[plan_.rate] : kClassic[plan_.rate]).c_str());
    if (plan_.fd_bus) {
      appendf(out_, " data %s", timing_text(kFdData[plan_.data_rate]).c_str());
    }
    appendf(out_, " bit %lld ns, %lld ns, %zu nodes (%zu at the start)\n",
            static_cast<long long>(plan_.bit_ns), static_cast<long long>(plan_.duration_ns),
            plan_.nodes.size(), plan_.initial);
    bus_.set_injector(this);
    plan_faults_.on_hit = [this](std::size_t rule, const FrameContext& ctx, const FrameFault& f) {
      counts_[C::fault_rule_hits]++;
      appendf(out_, "%lld hit rule %zu n%u ", static_cast<long long>(ctx.sof.ns()), rule,
              ctx.transmitter);
      append_frame(out_, ctx.frame);
      appendf(out_, " %s bit %d%s\n", f.error ? std::string(to_string(*f.error)).c_str() : "-",
              f.bit ? static_cast<int>(*f.bit) : -1, f.suppress_ack ? " no-ack" : "");
    };
    bus_.on_bus_event = [this](const BusEvent& e) { bus_event(e); };
    for (std::size_t i = 0; i < plan_.nodes.size(); ++i) {
      const NodeSetup& s = plan_.nodes[i];
      appendf(out_, "node %zu %s%s%s ppm %d recovery %s restart %lld rec-limit %u warning %u%s\n",
              i, timing_text(s.timing.nominal).c_str(),
              s.timing.has_data_phase ? (" data " + timing_text(s.timing.data)).c_str() : "",
              s.fd_capable ? " fd" : "", s.timing.oscillator_ppm,
              s.recovery == BusOffRecovery::automatic ? "automatic" : "on-restart",
              static_cast<long long>(s.restart_delay_ns), s.rec_limit, s.warning_limit,
              s.responder ? " responder" : "");
    }
    for (std::size_t i = 0; i < plan_.initial; ++i) {
      attach(i);
    }
  }

  void run() {
    for (const Action& a : plan_.actions) {
      sched_.run_until(SimTime::from_ns(a.at));
      apply(a);
      checkpoint();
    }
    const SimTime end = SimTime::from_ns(plan_.duration_ns);
    sched_.run_until(end);
    finish(end);
  }

  // --- told by the controllers and the bus ---

  std::string& out() { return out_; }
  ScenarioCounts& counts() { return counts_; }
  CanBus& bus() { return bus_; }
  SimScheduler& scheduler() { return sched_; }
  const NodeSetup& setup(NodeId id) const { return plan_.nodes[id]; }

  void before_arbitration(SimTime now, CanBus& bus) override {
    while (!at_arbitration_.empty() && at_arbitration_.front().at <= now.ns()) {
      const Action a = at_arbitration_.front();
      at_arbitration_.pop_front();
      counts_[C::faults_at_arbitration]++;
      appendf(out_, "%lld at arbitration n%u ", static_cast<long long>(now.ns()), a.node);
      if (a.variant == 0) {
        bus.set_connected(a.node, a.on);
        appendf(out_, "connected %d\n", a.on);
      } else if (a.variant == 1) {
        bus.set_oscillator_ppm(a.node, static_cast<int32_t>(a.a));
        appendf(out_, "ppm %lld\n", static_cast<long long>(a.a));
      } else {
        nodes_[a.node]->fc.set_counters(static_cast<uint16_t>(a.a), static_cast<uint16_t>(a.b));
        appendf(out_, "counters %lld %lld\n", static_cast<long long>(a.a),
                static_cast<long long>(a.b));
      }
    }
  }
  FrameFault on_frame(const FrameContext& ctx) override { return plan_faults_.on_frame(ctx); }

 private:
  void attach(std::size_t i) {
    const NodeSetup& s = plan_.nodes[i];
    auto c = std::make_unique<TraceController>(*this, s);
    c->timing_ = s.timing;
    c->timing_.oscillator_ppm = 0;  // as an injected offset instead, below
    c->fd = s.fd_capable;
    c->id = bus_.attach(*c);
    if (s.timing.oscillator_ppm != 0) {
      bus_.set_oscillator_ppm(c->id, s.timing.oscillator_ppm);
    }
    nodes_.push_back(std::move(c));
  }

  void bus_event(const BusEvent& e) {
    static constexpr std::array<const char*, 3> kKinds{"frame", "error-frame", "held"};
    appendf(out_, "%lld bus %s %lld n%u", static_cast<long long>(e.start.ns()),
            kKinds[static_cast<std::size_t>(e.kind)], static_cast<long long>(e.end.ns()),
            e.transmitter);
    if (e.frame) {
      out_ += ' ';
      append_frame(out_, *e.frame);
    }
    appendf(out_, " bit %u\n", e.error_bit);
    switch (e.kind) {
      case BusEvent::Kind::frame:
        counts_[C::frames]++;
        counts_[C::fd_frames] += e.frame->fd();
        counts_[C::brs_frames] += e.frame->brs();
        counts_[C::extended_frames] += e.frame->extended();
        counts_[C::remote_frames] += e.frame->remote();
        break;
      case BusEvent::Kind::error_frame:
        counts_[C::error_frames]++;
        break;
      case BusEvent::Kind::bus_held:
        counts_[C::dominant_holds]++;
        break;
    }
  }

  TraceController* attached(uint32_t node) {
    return node < nodes_.size() ? nodes_[node].get() : nullptr;
  }

  void apply(const Action& a) {
    appendf(out_, "%lld @", static_cast<long long>(a.at));
    if (a.op == Op::send) {
      for (std::size_t i = 0; i < a.nodes.size(); ++i) {
        TraceController* c = attached(a.nodes[i]);
        const std::size_t first = a.nodes.size() == 1 ? 0 : i;
        const std::size_t last = a.nodes.size() == 1 ? a.frames.size() : i + 1;
        for (std::size_t k = first; k < last; ++k) {
          appendf(out_, " n%u send ", a.nodes[i]);
          append_frame(out_, a.frames[k].frame);
          appendf(out_, "%s%s%s", a.frames[k].single_shot ? " single-shot" : "",
                  a.frames[k].self_reception ? " self" : "", c == nullptr ? " (not attached)" : "");
          if (c != nullptr) {
            c->send(a.frames[k]);
          }
        }
      }
      out_ += '\n';
      return;
    }
    if (a.op == Op::attach) {
      appendf(out_, " attach n%u\n", a.node);
      counts_[C::late_attaches]++;
      attach(a.node);
      return;
    }
    if (a.op == Op::add_rule) {
      const FaultRule& r = *a.rule;
      appendf(out_,
              " rule %lld: %s bit %d no-ack %d ber %g tx %d id %x/%x ext %d rtr %d skip %llu "
              "count %lld p %g from %lld until %lld\n",
              static_cast<long long>(a.a),
              r.fault.error ? std::string(to_string(*r.fault.error)).c_str() : "-",
              r.fault.bit ? static_cast<int>(*r.fault.bit) : -1, r.fault.suppress_ack,
              r.bit_error_rate, r.match.transmitter ? static_cast<int>(*r.match.transmitter) : -1,
              r.match.id, r.match.mask, r.match.extended ? static_cast<int>(*r.match.extended) : -1,
              r.match.remote ? static_cast<int>(*r.match.remote) : -1,
              static_cast<unsigned long long>(r.skip),
              r.count ? static_cast<long long>(*r.count) : -1LL, r.probability,
              static_cast<long long>(r.from.ns()),
              r.until ? static_cast<long long>(r.until->ns()) : -1LL);
      plan_faults_.add(r);
      return;
    }
    if (a.op == Op::disable_rule || a.op == Op::remove_rule) {
      const auto id = static_cast<std::size_t>(a.a);
      const bool there = plan_faults_.contains(id);
      appendf(out_, " %s rule %zu%s\n", a.op == Op::disable_rule ? "disable" : "remove", id,
              there ? "" : " (not there)");
      if (there) {
        a.op == Op::disable_rule ? plan_faults_.disable(id) : plan_faults_.remove(id);
      }
      return;
    }
    if (a.op == Op::hold) {
      appendf(out_, " hold from %lld for %lld\n", static_cast<long long>(a.a),
              static_cast<long long>(a.b));
      bus_.hold_dominant(SimTime::from_ns(a.a), SimDuration(a.b));
      return;
    }
    if (a.op == Op::suppress_acks) {
      appendf(out_, " no acks for %lld\n", static_cast<long long>(a.b));
      bus_.suppress_acks_until(SimTime::from_ns(a.at + a.b));
      return;
    }
    TraceController* c = attached(a.node);
    if (c == nullptr) {
      appendf(out_, " n%u not attached\n", a.node);
      return;
    }
    appendf(out_, " n%u ", a.node);
    switch (a.op) {
      case Op::connect:
        appendf(out_, "connected %d\n", a.on);
        bus_.set_connected(c->id, a.on);
        break;
      case Op::oscillator:
        appendf(out_, "ppm %lld\n", static_cast<long long>(a.a));
        bus_.set_oscillator_ppm(c->id, static_cast<int32_t>(a.a));
        break;
      case Op::run:
        appendf(out_, "running %d\n", a.on);
        c->running = a.on;
        bus_.controller_changed(c->id);
        break;
      case Op::listen:
        appendf(out_, "listen-only %d\n", a.on);
        c->listen = a.on;
        bus_.controller_changed(c->id);
        break;
      case Op::self_test:
        appendf(out_, "self-test %d\n", a.on);
        c->self_test_mode = a.on;
        bus_.controller_changed(c->id);
        break;
      case Op::fd:
        appendf(out_, "fd %d\n", a.on);
        c->fd = a.on;
        bus_.controller_changed(c->id);
        break;
      case Op::retime:
        if (a.a < 0) {
          c->timing_.nominal = plan_.nodes[a.node].timing.nominal;
          c->timing_.has_data_phase = plan_.nodes[a.node].timing.has_data_phase;
        } else {
          c->timing_.nominal = kClassic[static_cast<std::size_t>(a.a)];
          c->timing_.has_data_phase = false;
        }
        appendf(out_, "timing %s data %d\n", timing_text(c->timing_.nominal).c_str(),
                c->timing_.has_data_phase);
        bus_.controller_changed(c->id);
        break;
      case Op::counters:
        appendf(out_, "counters %lld %lld%s\n", static_cast<long long>(a.a),
                static_cast<long long>(a.b), a.on ? " told" : "");
        c->fc.set_counters(static_cast<uint16_t>(a.a), static_cast<uint16_t>(a.b));
        if (a.on) {
          bus_.counters_changed(c->id);
        }
        break;
      case Op::restart:
        appendf(out_, "restart\n");
        bus_.restart(c->id);
        break;
      case Op::withdraw: {
        const bool had = c->current.has_value();
        const bool gone = withdraw_tx(&bus_, c->id, c->current);
        appendf(out_, "withdraw %s", gone ? "gone" : had ? "on the wire" : "nothing");
        counts_[C::withdrawn_before_start] += gone;
        counts_[C::withdrawn_on_the_wire] += had && !gone;
        if (gone) {
          if (a.on) {
            out_ += ", instead ";
            append_frame(out_, a.frames[0].frame);
            c->backlog.push_front(a.frames[0]);
          }
          c->next();
        }
        out_ += '\n';
        break;
      }
      case Op::at_arbitration:
        appendf(out_, "at next arbitration: variant %u %d %lld %lld\n", a.variant, a.on,
                static_cast<long long>(a.a), static_cast<long long>(a.b));
        at_arbitration_.push_back(a);
        break;
      default:
        out_ += '\n';
        break;
    }
  }

  // Counters, states and frames on the wire after an action.
  void checkpoint() {
    appendf(out_, "  ck load %.17g", bus_.bus_load_percent(sched_.now()));
    for (const auto& c : nodes_) {
      const FaultConfinement& fc = c->fc;
      appendf(out_, " n%u %u/%u/%s%s%s", c->id, fc.tec(), fc.rec(), state_text(fc.state()),
              fc.recovering() ? "/r" : "", bus_.in_flight(c->id) ? "*" : "");
    }
    out_ += '\n';
  }

  void finish(SimTime end) {
    appendf(out_, "end %lld frames %llu error-frames %llu", static_cast<long long>(end.ns()),
            static_cast<unsigned long long>(bus_.frames_on_bus()),
            static_cast<unsigned long long>(bus_.error_frames_on_bus()));
    for (const int64_t later : {int64_t{0}, int64_t{50'000'000}, int64_t{1'000'000'000}}) {
      appendf(out_, " load+%lld %.17g", static_cast<long long>(later),
              bus_.bus_load_percent(end + SimDuration(later)));
    }
    out_ += "\n history";
    for (const BusLoad::Bin& b : bus_.bus_load_history(end + seconds(1))) {
      appendf(out_, " %lld:%lld", static_cast<long long>(b.start.ns()),
              static_cast<long long>(b.busy.ns()));
    }
    out_ += '\n';
    for (const auto& c : nodes_) {
      const NodeStats& s = bus_.stats(c->id);
      const FaultConfinement& fc = c->fc;
      appendf(
          out_,
          "n%u sent %llu received %llu lost %llu dropped %llu tx-errors %llu/%llu/%llu/%llu/%llu "
          "rx-errors %llu/%llu/%llu/%llu/%llu tec %u rec %u %s%s left %u pending %d backlog %zu\n",
          c->id, static_cast<unsigned long long>(s.frames_sent),
          static_cast<unsigned long long>(s.frames_received),
          static_cast<unsigned long long>(s.arbitration_lost),
          static_cast<unsigned long long>(s.tx_dropped),
          static_cast<unsigned long long>(s.errors_as_transmitter.bit),
          static_cast<unsigned long long>(s.errors_as_transmitter.stuff),
          static_cast<unsigned long long>(s.errors_as_transmitter.form),
          static_cast<unsigned long long>(s.errors_as_transmitter.crc),
          static_cast<unsigned long long>(s.errors_as_transmitter.ack),
          static_cast<unsigned long long>(s.errors_as_receiver.bit),
          static_cast<unsigned long long>(s.errors_as_receiver.stuff),
          static_cast<unsigned long long>(s.errors_as_receiver.form),
          static_cast<unsigned long long>(s.errors_as_receiver.crc),
          static_cast<unsigned long long>(s.errors_as_receiver.ack), fc.tec(), fc.rec(),
          state_text(fc.state()), fc.recovering() ? " recovering" : "",
          fc.recovery_sequences_left(), c->current.has_value(), c->backlog.size());
      out_ += " states";
      for (const StateChange& sc : s.state_changes) {
        appendf(out_, " %lld:%s", static_cast<long long>(sc.at.ns()), state_text(sc.state));
      }
      appendf(out_, "\n timeline forgotten %llu",
              static_cast<unsigned long long>(s.timeline.forgotten()));
      for (const CounterSample& t : s.timeline.samples()) {
        appendf(out_, " %lld:%u/%u/%s/%s", static_cast<long long>(t.at.ns()), t.tec, t.rec,
                state_text(t.state), std::string(to_string(t.cause)).c_str());
        if (t.cause == CounterCause::error || t.cause == CounterCause::severe) {
          appendf(out_, "/%s/%s", std::string(to_string(t.error)).c_str(),
                  t.role == ErrorRole::transmitter ? "tx" : "rx");
        }
        counts_[C::severe_counts] += t.cause == CounterCause::severe;
        counts_[C::counters_written] += t.cause == CounterCause::written;
      }
      out_ += '\n';
    }
  }

  std::string& out_;
  ScenarioCounts& counts_;
  uint64_t seed_;
  Plan plan_;
  SimScheduler sched_;
  CanBus bus_{sched_, "trace"};
  FaultPlan plan_faults_;
  std::vector<std::unique_ptr<TraceController>> nodes_;
  std::deque<Action> at_arbitration_;
};

void TraceController::send(const TxFrame& f) {
  if (current) {
    backlog.push_back(f);
    return;
  }
  current = f;
  scenario_.bus().tx_changed(id);
}

void TraceController::next() {
  current.reset();
  if (!backlog.empty()) {
    current = backlog.front();
    backlog.pop_front();
    scenario_.bus().tx_changed(id);
  }
}

void TraceController::on_frame(SimTime at, const Frame& f, bool own) {
  std::string& out = scenario_.out();
  appendf(out, "%lld n%u rx ", static_cast<long long>(at.ns()), id);
  append_frame(out, f);
  out += own ? " own\n" : "\n";
  scenario_.counts()[C::self_receptions] += own;
  if (setup_.responder && f.remote() && !own && f.id() % 3 == id % 3) {
    // The reply: the data the remote frame asks for, made from its identifier.
    std::array<uint8_t, 8> data{};
    for (std::size_t i = 0; i < data.size(); ++i) {
      data[i] = static_cast<uint8_t>(f.id() >> (i % 4 * 8)) ^ static_cast<uint8_t>(i);
    }
    const std::size_t length = dlc_to_length(f.dlc(), false);
    FrameSpec spec;
    spec.id = f.id();
    spec.extended = f.extended();
    spec.dlc = f.dlc();
    spec.data = std::span<const uint8_t>(data.data(), length);
    scenario_.counts()[C::remote_replies]++;
    appendf(out, "%lld n%u replies\n", static_cast<long long>(at.ns()), id);
    send(TxFrame{*Frame::create(spec), false, false});
  }
}

void TraceController::on_tx_done(SimTime at) {
  appendf(scenario_.out(), "%lld n%u done\n", static_cast<long long>(at.ns()), id);
  next();
}

void TraceController::on_tx_dropped(SimTime at) {
  appendf(scenario_.out(), "%lld n%u dropped\n", static_cast<long long>(at.ns()), id);
  scenario_.counts()[C::single_shots_dropped]++;
  next();
}

void TraceController::on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed_bit) {
  appendf(scenario_.out(), "%lld n%u lost %u/%u\n", static_cast<long long>(at.ns()), id, bit,
          destuffed_bit);
  scenario_.counts()[C::arbitration_losses]++;
}

void TraceController::on_error(const BusErrorEvent& e) {
  appendf(scenario_.out(), "%lld n%u error %s %s bit %u/%u %s%s%s%s tec %u rec %u\n",
          static_cast<long long>(e.at.ns()), id, std::string(to_string(e.type)).c_str(),
          e.role == ErrorRole::transmitter ? "tx" : "rx", e.bit, e.destuffed_bit,
          std::string(to_string(e.field)).c_str(), e.extended_frame ? " ext" : "",
          e.in_frame ? "" : " idle", e.data_phase ? " data-phase" : "", e.tec, e.rec);
  ScenarioCounts& n = scenario_.counts();
  static constexpr std::array<C, 5> kTypes{C::bit_errors, C::stuff_errors, C::form_errors,
                                           C::crc_errors, C::ack_errors};
  n[kTypes[static_cast<std::size_t>(e.type)]]++;
  n[C::data_phase_errors] += e.data_phase;
  n[C::errors_outside_frames] += !e.in_frame;
}

void TraceController::on_state_change(SimTime at, ErrorState state) {
  appendf(scenario_.out(), "%lld n%u state %s\n", static_cast<long long>(at.ns()), id,
          state_text(state));
  ScenarioCounts& n = scenario_.counts();
  n[C::warning_entries] += state == ErrorState::warning;
  n[C::error_passive_entries] += state == ErrorState::passive;
  n[C::bus_off_entries] += state == ErrorState::bus_off;
  n[C::recoveries] += was_bus_off_ && state != ErrorState::bus_off;
  was_bus_off_ = state == ErrorState::bus_off;
  if (state == ErrorState::bus_off && setup_.recovery == BusOffRecovery::on_restart &&
      setup_.restart_delay_ns >= 0) {
    scenario_.scheduler().schedule_at(at + SimDuration(setup_.restart_delay_ns), [this](
                                                                                     SimTime now) {
      appendf(scenario_.out(), "%lld n%u host restarts\n", static_cast<long long>(now.ns()), id);
      scenario_.counts()[C::host_restarts]++;
      scenario_.bus().restart(id);
    });
  }
}

}  // namespace

void run_scenario(std::size_t k, std::string& text, ScenarioCounts& counts) {
  Scenario s(k, text, counts);
  s.run();
}

}  // namespace canemu::model::testing::engine_trace
