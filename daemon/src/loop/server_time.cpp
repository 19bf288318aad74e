// Time in canemud's loop: simulated time mapped to the wall clock (real and scaled time), the
// timer for the next event, the pace kept, and the steps of stepped time run in slices.
#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <utility>

#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/loop/server.hpp"
#include "canemu/ipc/clock.hpp"
#include "loop/epoll.hpp"

namespace canemu::daemon {

using ipc::monotonic_ns;

model::SimTime Server::wall_to_sim() const {
  return wall_to_sim(monotonic_ns());
}

model::SimTime Server::wall_to_sim(int64_t mono_ns) const {
  const double elapsed = static_cast<double>(mono_ns - start_mono_ns_);
  const double scale = options_.time.mode == TimeMode::scaled ? options_.time.scale : 1.0;
  // Saturates instead of overflowing (scaled:1000000 reaches 2^63 ns after 2.5 hours).
  return model::SimTime::from_ns(static_cast<int64_t>(std::min(elapsed * scale, 9.0e18)));
}

int64_t Server::monotonic_at(model::SimTime t) const {
  if (options_.time.mode == TimeMode::stepped) {
    return 0;
  }
  const double scale = options_.time.mode == TimeMode::scaled ? options_.time.scale : 1.0;
  return start_mono_ns_ + static_cast<int64_t>(static_cast<double>(t.ns()) / scale);
}

void Server::advance_to_now() {
  if (options_.time.mode == TimeMode::stepped) {
    return;
  }
  const int64_t wall = monotonic_ns();
  const model::SimTime target = wall_to_sim(wall);
  run_events_until(target, wall);
  note_pace(monotonic_ns(), target);
}

void Server::run_events_until(model::SimTime target, int64_t wall) {
  model::SimScheduler& s = sim_.scheduler();
  const double per_sim_ns =
      options_.time.mode == TimeMode::scaled ? 1.0 / options_.time.scale : 1.0;
  const int64_t until = wall + kMaxPassWorkNs;
  // Each event's lateness against the clock read before its chunk of kEventsPerClock.
  const auto late = [&](model::SimTime at) {
    const double instant = static_cast<double>(at.ns()) * per_sim_ns;
    pacing_.event_late(wall - start_mono_ns_ - static_cast<int64_t>(std::min(instant, 9.0e18)));
  };
  while (true) {
    const std::size_t ran = s.run_until(target, kEventsPerClock, late);
    turn_events_ += ran;
    if (ran != kEventsPerClock) {
      break;
    }
    wall = monotonic_ns();
    if (wall >= until) {
      break;  // the rest waits for the next pass (the timer is due at once)
    }
  }
}

void Server::kick_rung_doorbells(epoll_event* events, int n) {
  struct Rung {
    int64_t at;
    int index;
  };
  std::array<Rung, 32> rung;
  std::size_t count = 0;
  const int64_t wall = last_wake_ns_;
  for (int i = 0; i < n && count < rung.size(); ++i) {
    const auto bell = doorbells_.find(events[i].data.fd);
    if (bell == doorbells_.end()) {
      continue;
    }
    // The client's word, bounded: not in the future, not older than kMaxRungAgeNs (a clock of
    // another time namespace, a wake-up that came that late): otherwise kicked now, below.
    const int64_t at = bell->second->take_rung_ns();
    if (at <= 0 || at > wall || wall - at > kMaxRungAgeNs) {
      continue;
    }
    rung[count++] = Rung{at, i};
  }
  std::sort(rung.begin(), rung.begin() + static_cast<std::ptrdiff_t>(count),
            [](const Rung& a, const Rung& b) {
              return a.at < b.at || (a.at == b.at && a.index < b.index);
            });
  for (std::size_t k = 0; k < count; ++k) {
    // Never before what already ran (run_until does not go back): at the latest of the two.
    run_events_until(wall_to_sim(rung[k].at), wall);
    // Looked up again: what ran since may have removed it (as the loop below does for each).
    const auto bell = doorbells_.find(events[rung[k].index].data.fd);
    if (bell != doorbells_.end() && bell->second->kick_rung()) {
      events[rung[k].index].data.fd = -1;
    }
  }
}

void Server::note_pace(int64_t mono_ns, model::SimTime target) {
  pacing_.tick(mono_ns);
  const model::SimTime now = sim_.scheduler().now();
  lag_ns_ = std::max<int64_t>(0, (target - now).ns());
  if (pace_.empty() || mono_ns - pace_.back().first >= 100'000'000) {
    pace_.emplace_back(mono_ns, now.ns());
    while (pace_.size() > 2 && mono_ns - pace_[1].first >= 1'000'000'000) {
      pace_.pop_front();  // keep a window of at least one second
    }
  }
  const double scale = options_.time.mode == TimeMode::scaled ? options_.time.scale : 1.0;
  const double lag_wall_ns = static_cast<double>(lag_ns_) / scale;
  if (lag_wall_ns >= 100e6 && mono_ns - lag_logged_ns_ >= 10'000'000'000) {
    lag_logged_ns_ = mono_ns;
    log::warning(
        "simulated time lags {:.3f} s behind: the simulation cannot keep up with time {} "
        "(achieved {:.1f} x real time over the last second)",
        static_cast<double>(lag_ns_) / 1e9, to_string(options_.time), achieved_scale());
  }
}

double Server::achieved_scale() const {
  const double scale = options_.time.mode == TimeMode::scaled ? options_.time.scale : 1.0;
  if (pace_.size() < 2 || pace_.back().first - pace_.front().first < 500'000'000) {
    return lag_ns_ == 0 ? scale : 0.0;  // too early to tell
  }
  return static_cast<double>(pace_.back().second - pace_.front().second) /
         static_cast<double>(pace_.back().first - pace_.front().first);
}

void Server::arm_timer() {
  itimerspec its{};
  deadline_ns_ = 0;
  if (options_.time.mode != TimeMode::stepped) {
    const SimulationConfig& sc = sim_.config().simulation;
    batch_.configure(sc.batch_us, sc.batch_max_us);  // a reload may have changed them
    if (auto next = sim_.scheduler().next_event_time()) {
      // Absolute CLOCK_MONOTONIC deadline of the next simulated event, rounded up so the
      // timer never fires before the event is due; no sooner than one batch after the last
      // wake-up.
      const double scale = options_.time.mode == TimeMode::scaled ? options_.time.scale : 1.0;
      const double offset = std::ceil(static_cast<double>(next->ns()) / scale);
      const int64_t due = start_mono_ns_ + static_cast<int64_t>(std::min(offset, 9.0e18));
      deadline_ns_ = std::max(due, last_wake_ns_ + batch_.window_ns());
      // Woken a little early (as early as the timer has lately been late, at most spin_us),
      // the loop spins to the deadline; not when a widened window set it (events come densely
      // and wait for the window by design: a spin would buy no punctuality worth its cost).
      const bool widened = batch_.widened() && deadline_ns_ > due;
      const int64_t wall = std::max<int64_t>(1, deadline_ns_ - (widened ? 0 : pacing_.spin_ns()));
      armed_ns_ = wall;
      armed_ahead_ = wall > monotonic_ns();
      its.it_value.tv_sec = wall / 1'000'000'000;
      its.it_value.tv_nsec = wall % 1'000'000'000;
    }
  }
  const bool arm = its.it_value.tv_sec != 0 || its.it_value.tv_nsec != 0;
  if (!arm && !timer_armed_) {
    return;  // disarmed already (stepped time, nothing due): no call on every turn
  }
  if (::timerfd_settime(timer_.get(), TFD_TIMER_ABSTIME, &its, nullptr) != 0) {
    log::error("timerfd_settime: {}", std::strerror(errno));
    return;
  }
  timer_armed_ = arm;
}

void Server::queue_local_step(int64_t step_ns, uint32_t request_id) {
  const PendingStep p{current_->fd.get(), current_->serial, request_id};
  queue_step_run(
      [this, step_ns] {
        kick_all_channels();  // what the clients queued before the step
        return sim_.scheduler().now() + model::SimDuration(step_ns);
      },
      [this, p](uint64_t events) {
        send_outboxes();
        flush_recorders();
        answer_step(p, events, sim_.scheduler().now().ns());
      });
}

void Server::queue_step_run(std::function<model::SimTime()> start,
                            std::function<void(uint64_t events)> done) {
  StepRun run;
  run.start = std::move(start);
  run.done = std::move(done);
  step_runs_.push_back(std::move(run));
  waits_for_steps_ = true;
}

void Server::run_step_slice() {
  model::SimScheduler& s = sim_.scheduler();
  const int64_t slice_end = monotonic_ns() + kMaxPassWorkNs;
  while (!step_runs_.empty()) {
    StepRun& r = step_runs_.front();
    if (!r.started) {
      r.started = true;
      r.until = r.start();
    }
    std::size_t ran = 0;
    do {
      ran = s.run_until(r.until, kEventsPerStepClock);
      r.events += ran;
    } while (ran == kEventsPerStepClock && monotonic_ns() < slice_end);
    if (ran == kEventsPerStepClock && s.now() < r.until) {
      return;  // the slice is over: the rest on the next pass
    }
    StepRun ended = std::move(r);
    step_runs_.pop_front();
    ended.done(ended.events);  // may queue the next run (a step across hosts)
    if (monotonic_ns() >= slice_end) {
      return;
    }
  }
}

void Server::finish_step_runs() {
  model::SimScheduler& s = sim_.scheduler();
  while (!step_runs_.empty()) {
    StepRun ended = std::move(step_runs_.front());
    step_runs_.pop_front();
    if (!ended.started) {
      ended.until = ended.start();
    }
    ended.events += s.run_until(ended.until);
    ended.done(ended.events);
  }
}

// The steps have run: what waited for them, in the order the loop would have served it.
void Server::after_step_runs() {
  waits_for_steps_ = false;
  for (const int fd : std::exchange(bells_rung_, {})) {
    if (auto bell = doorbells_.find(fd); bell != doorbells_.end()) {
      bell->second->kick();
    }
  }
  if (std::exchange(reload_waiting_, false)) {
    reload();
  }
  for (auto& [fd, c] : clients_) {
    if (c.held.empty() || c.closing) {
      continue;
    }
    if (stepping() && !reads_only(c.held)) {
      waits_for_steps_ = true;  // a step asked for by a held request runs first
      continue;
    }
    const std::vector<uint8_t> packet = std::exchange(c.held, {});
    handle(c, packet);
  }
  if (stepping()) {
    waits_for_steps_ = true;
  }
}

void Server::step_done(uint64_t token, uint64_t events_run, int64_t sim_ns,
                       const std::string& note) {
  auto it = pending_steps_.find(token);
  if (it == pending_steps_.end()) {
    return;
  }
  const PendingStep p = it->second;
  pending_steps_.erase(it);
  answer_step(p, events_run, sim_ns, note);
}

void Server::answer_step(const PendingStep& p, uint64_t events_run, int64_t sim_ns,
                         const std::string& note) {
  auto c = clients_.find(p.fd);
  if (c == clients_.end() || c->second.serial != p.serial || c->second.closing) {
    return;  // the client left before its step ended
  }
  auto r = ipc::make_message<ipc::TimeStepReply>(p.request_id);
  r.events_run = events_run;
  r.sim_time_ns = sim_ns;
  ipc::copy_name(r.note, note);
  if (!ipc::send_message(p.fd, r)) {
    c->second.closing = true;
  }
}

void Server::fill_pace(ipc::StatusReply& r) {
  if (options_.time.mode != TimeMode::stepped) {
    r.lag_ns = lag_ns_;
    r.achieved_scale = achieved_scale();
    pacing_.fill(r.pacing);
  }
}

// A client's step runs in slices (queue_step_run); across hosts when another daemon takes part.
bool Server::defer_step(int64_t step_ns, uint32_t request_id) {
  Distributed* d = Distributed::of(sim_);
  if (d == nullptr || (!d->follows_owner() && !d->leads_steps())) {
    queue_local_step(step_ns, request_id);
    return true;
  }
  const uint64_t token = ++step_tokens_;
  pending_steps_[token] = PendingStep{current_->fd.get(), current_->serial, request_id};
  if (auto stepped = d->step(step_ns, token); !stepped) {
    pending_steps_.erase(token);
    reply_error(*current_, request_id, ipc::ErrorCode::not_stepped, stepped.error().what());
  }
  return true;
}

void Server::before_step() {
  kick_all_channels();
}

void Server::after_step() {
  send_outboxes();
  flush_recorders();
}

void Server::run_to(model::SimTime until, std::function<void(uint64_t events)> done) {
  queue_step_run([until] { return until; }, std::move(done));
}

void Server::finish_runs() {
  finish_step_runs();
}

void Server::steps_failed(const std::string& why) {
  for (const auto& [token, p] : std::exchange(pending_steps_, {})) {
    auto c = clients_.find(p.fd);
    if (c != clients_.end() && c->second.serial == p.serial && !c->second.closing) {
      reply_error(c->second, p.request_id, ipc::ErrorCode::not_stepped, why);
    }
  }
}

}  // namespace canemu::daemon
