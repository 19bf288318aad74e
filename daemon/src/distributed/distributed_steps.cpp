// Buses across hosts in stepped time (docs/distributed.md, "Time"): the owner's steps and their
// barrier, a follower's steps asked of its owner.
#ifdef CANEMU_HAVE_DDS

#include "distributed_impl.hpp"

namespace canemu::daemon {

void Distributed::Impl::enqueue_step(Step st) {
  steps.push_back(std::move(st));
  if (!barrier && !running) {
    start_next_step();
  }
}

void Distributed::Impl::run_to(SimTime until, std::function<void(uint64_t)> done) {
  if (loop == nullptr) {
    done(sim.scheduler().run_until(until));
    return;
  }
  ++runs_queued;
  loop->run_to(until, [this, done = std::move(done)](uint64_t events) {
    --runs_queued;
    done(events);
  });
}

void Distributed::Impl::start_next_step() {
  if (steps.empty() || barrier || running) {
    return;
  }
  ++step_no;
  waiting.clear();
  step_dropped.clear();
  for (const auto& [name, p] : peers) {
    if (p.follower && !p.gone) {
      waiting.insert(name);
    }
  }
  if (waiting.empty()) {
    run_step();
    return;
  }
  barrier = true;
  barrier_deadline_ms = monotonic_ms() + cfg.timeout_ms;
  canemu_net_Event e{};
  e.kind = canemu_net_EV_STEP_BEGIN;
  e.at_ns = sim.scheduler().now().ns();
  e.step = step_no;
  e.step_ns = steps.front().ns;
  send_event("", e);
}

void Distributed::Impl::run_step() {
  barrier = false;
  waiting.clear();
  if (steps.empty()) {
    return;
  }
  const Step st = steps.front();
  steps.pop_front();
  if (loop != nullptr) {
    loop->before_step();
  }
  running = true;
  run_to(sim.scheduler().now() + SimDuration(st.ns), [this, st](uint64_t events) {
    running = false;
    SimScheduler& s = sim.scheduler();
    if (loop != nullptr) {
      loop->after_step();
    }
    canemu_net_Event e{};
    e.kind = canemu_net_EV_STEP_DONE;
    e.at_ns = s.now().ns();
    e.step = step_no;
    e.step_ns = st.ns;
    e.token = st.token;
    put(e.asker, st.asker);
    const std::string note = step_note();
    put(e.text, note);
    send_event("", e);  // every follower runs to the step's end; the asker answers its client
    if (st.asker == cfg.name && loop != nullptr) {
      loop->step_done(st.token, events, s.now().ns(), note);
    }
    start_next_step();
  });
}

std::string Distributed::Impl::step_note() const {
  if (step_dropped.empty()) {
    return {};
  }
  std::string names;
  for (const std::string& d : step_dropped) {
    names += (names.empty() ? "" : "; ") + d;
  }
  return fmt::format("let go during the step: {}", names);
}

bool Distributed::follows_owner() const {
  return impl_->stepped() && !impl_->stepped_owner.empty();
}

bool Distributed::leads_steps() const {
  return impl_->leads();
}

Result<> Distributed::step(int64_t step_ns, uint64_t token) {
  Impl& d = *impl_;
  if (follows_owner()) {
    if (!d.attached(d.stepped_owner)) {
      return fail(Errc::unavailable,
                  fmt::format("steps are daemon {}'s, which is not attached ({})", d.stepped_owner,
                              remote_buses().empty() ? "" : remote_buses().front().reason));
    }
    canemu_net_Request r{};
    r.kind = canemu_net_REQ_STEP;
    r.step_ns = step_ns;
    r.step = token;
    if (!d.send_request(d.stepped_owner, r)) {
      return fail(Errc::io,
                  fmt::format("DDS did not take the step request for daemon {}", d.stepped_owner));
    }
    return {};
  }
  d.enqueue_step(Impl::Step{step_ns, d.cfg.name, token});
  return {};
}

}  // namespace canemu::daemon

#endif
