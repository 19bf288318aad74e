#include "canemu/daemon/loop/server.hpp"

#include <algorithm>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <utility>

#include <fcntl.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <fmt/format.h>
#include <systemd/sd-daemon.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/ipc/clock.hpp"

namespace canemu::daemon {

namespace {

using ipc::monotonic_ns;

ipc::IpcError sys(const std::string& what) {
  const int e = errno;
  return ipc::IpcError{e, what + ": " + std::strerror(e)};
}

bool add(int epoll, int fd) {
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.fd = fd;
  return ::epoll_ctl(epoll, EPOLL_CTL_ADD, fd, &ev) == 0;
}

}  // namespace

Server::Server(Simulation& sim, ServerOptions options)
    : sim_(sim), options_(std::move(options)), dispatcher_(sim, options_.time, *this) {
  pacing_.set_max_spin(int64_t{sim_.config().simulation.spin_us} * 1000);
  sim_.devices().on_change = [this](ipc::NotificationKind kind, const std::string& name) {
    // Sent after the current batch of events: a device can go while its client is dropped.
    auto n = ipc::make_message<ipc::Notification>(0);
    n.kind = static_cast<uint32_t>(kind);
    n.generation = sim_.devices().generation();
    ipc::copy_name(n.device, name);
    pending_notifications_.push_back(n);
  };
}

Server::~Server() {
  for (auto& [fd, c] : clients_) {
    c.session.channels.clear();
  }
  sim_.devices().on_change = nullptr;
  if (listen_.valid() && !socket_from_systemd_) {
    ::unlink(options_.socket_path.c_str());
  }
}

// The control socket: the one systemd passes (canemud.socket), or a new one at the configured
// path with the configured mode and group.
ipc::IpcResult<void> Server::open_listener() {
  const int passed = sd_listen_fds(1);
  if (passed > 1) {
    return tl::unexpected(ipc::IpcError{
        EINVAL, fmt::format("systemd passed {} sockets; canemud takes exactly one", passed)});
  }
  if (passed == 1) {
    const int fd = SD_LISTEN_FDS_START;
    if (sd_is_socket_unix(fd, SOCK_SEQPACKET, 1, nullptr, 0) <= 0) {
      return tl::unexpected(ipc::IpcError{
          EINVAL,
          "systemd passed a socket that is not a listening AF_UNIX SOCK_SEQPACKET one "
          "(canemud.socket needs ListenSequentialPacket=)"});
    }
    sockaddr_un a{};
    socklen_t len = sizeof a;
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0 ||
        ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK) != 0 ||
        ::fcntl(fd, F_SETFD, FD_CLOEXEC) != 0) {
      return tl::unexpected(sys("socket from systemd"));
    }
    listen_.reset(fd);
    socket_from_systemd_ = true;
    options_.socket_path.assign(a.sun_path, strnlen(a.sun_path, sizeof a.sun_path));
    return {};
  }
  auto l = ipc::listen_seqpacket(options_.socket_path, SOMAXCONN);
  if (!l) {
    return tl::unexpected(l.error());
  }
  listen_ = std::move(*l);
  auto bound = AccessPolicy::socket_file(options_.socket_path);
  if (!bound) {
    return tl::unexpected(ipc::IpcError{EPERM, bound.error()});
  }
  socket_file_ = *bound;
  if (std::string e = AccessPolicy::apply_socket_permissions(options_.socket_path, socket_file_,
                                                             sim_.config().security);
      !e.empty()) {
    return tl::unexpected(ipc::IpcError{EPERM, e});
  }
  return {};
}

ipc::IpcResult<void> Server::open() {
  if (auto l = open_listener(); !l) {
    return l;
  }
  epoll_.reset(::epoll_create1(EPOLL_CLOEXEC));
  if (!epoll_.valid()) {
    return tl::unexpected(sys("epoll_create1"));
  }
  timer_.reset(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  if (!timer_.valid()) {
    return tl::unexpected(sys("timerfd_create"));
  }
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGINT);
  sigaddset(&mask, SIGTERM);
  sigaddset(&mask, SIGHUP);
  // Test hook for the watchdog test (tests/guest/systemd-tests.sh): with
  // CANEMU_TEST_HOOKS=stall-on-sigusr2 in the environment, SIGUSR2 stalls the loop for good.
  if (const char* hooks = std::getenv("CANEMU_TEST_HOOKS");
      hooks != nullptr && std::string_view(hooks) == "stall-on-sigusr2") {
    sigaddset(&mask, SIGUSR2);
    stall_hook_ = true;
    log::warning("test hook: SIGUSR2 stalls the event loop (CANEMU_TEST_HOOKS)");
  }
  if (::sigprocmask(SIG_BLOCK, &mask, nullptr) != 0) {
    return tl::unexpected(sys("sigprocmask"));
  }
  signals_.reset(::signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC));
  if (!signals_.valid()) {
    return tl::unexpected(sys("signalfd"));
  }
  if (!add(epoll_.get(), listen_.get()) || !add(epoll_.get(), timer_.get()) ||
      !add(epoll_.get(), signals_.get())) {
    return tl::unexpected(sys("epoll_ctl"));
  }
  access_.resolve(sim_.config().security);
  dispatcher_.set_ring_quota(std::size_t{sim_.config().security.ring_mib_per_user} << 20);
  for (const auto& b : sim_.bridges()) {  // configured bridges: their sockets wake the loop
    watch(*b);
  }
  if (Distributed* d = Distributed::of(sim_)) {  // other daemons' messages, the heartbeat
    watch(*d);
    watch(d->heartbeat());
    d->set_step_loop(this);
  }
  // Under systemd with WatchdogSec=: a ping every half period, from the loop itself, so a
  // stalled loop gets the daemon restarted.
  uint64_t watchdog_us = 0;
  if (sd_watchdog_enabled(0, &watchdog_us) > 0 && watchdog_us > 0) {
    watchdog_.reset(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
    itimerspec its{};
    const uint64_t half_ns = watchdog_us * 500;
    its.it_interval.tv_sec = static_cast<time_t>(half_ns / 1'000'000'000);
    its.it_interval.tv_nsec = static_cast<long>(half_ns % 1'000'000'000);
    its.it_value = its.it_interval;
    if (!watchdog_.valid() || ::timerfd_settime(watchdog_.get(), 0, &its, nullptr) != 0 ||
        !add(epoll_.get(), watchdog_.get())) {
      return tl::unexpected(sys("watchdog timer"));
    }
  }
  ::signal(SIGPIPE, SIG_IGN);  // a closed stderr or peer must not kill the daemon
  // Timer deadlines are met to the microsecond, not within Linux's default 50 us slack.
  ::prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  start_mono_ns_ = monotonic_ns();
  // Under systemd (Type=notify): ready once the socket listens. A no-op elsewhere.
  sd_notifyf(0, "READY=1\nSTATUS=listening on %s\nMAINPID=%d", options_.socket_path.c_str(),
             static_cast<int>(::getpid()));
  return {};
}

void Server::reload() {
  sd_notify(0, "RELOADING=1");
  const std::string& file = options_.config_file;
  auto fresh = file.empty() ? load_default_config() : load_config_file(file);
  if (!fresh) {
    for (const std::string& e : fresh.error()) {
      log::error("reload: {}", e);
    }
    log::warning("reload: configuration rejected; nothing changed");
  } else {
    if (options_.time_override) {
      fresh->simulation.time = *options_.time_override;
    }
    const ReloadReport r = sim_.reload(*fresh);
    if (pacing_.max_spin_ns() != int64_t{sim_.config().simulation.spin_us} * 1000) {
      pacing_.set_max_spin(int64_t{sim_.config().simulation.spin_us} * 1000);
    }
    access_.resolve(sim_.config().security);
    dispatcher_.set_ring_quota(std::size_t{sim_.config().security.ring_mib_per_user} << 20);
    if (!socket_from_systemd_) {
      if (std::string e = AccessPolicy::apply_socket_permissions(options_.socket_path, socket_file_,
                                                                 sim_.config().security);
          !e.empty()) {
        log::warning("reload: {}", e);
      }
    }
    drop_revoked_clients();
    for (const std::string& line : r.applied) {
      log::info("reload: {}", line);
    }
    for (const std::string& line : r.refused) {
      log::warning("reload: not applied: {}", line);
    }
    log::info("reload of {} done: {} change{} applied, {} not", fresh->source, r.applied.size(),
              r.applied.size() == 1 ? "" : "s", r.refused.size());
  }
  sd_notify(0, "READY=1");
}

model::SimTime Server::wall_to_sim() const {
  const double elapsed = static_cast<double>(monotonic_ns() - start_mono_ns_);
  const double scale = options_.time.mode == TimeMode::scaled ? options_.time.scale : 1.0;
  // Saturates instead of overflowing (scaled:1000000 reaches 2^63 ns after 2.5 hours).
  return model::SimTime::from_ns(static_cast<int64_t>(std::min(elapsed * scale, 9.0e18)));
}

void Server::advance_to_now() {
  if (options_.time.mode == TimeMode::stepped) {
    return;
  }
  const model::SimTime target = wall_to_sim();
  model::SimScheduler& s = sim_.scheduler();
  const double per_sim_ns =
      options_.time.mode == TimeMode::scaled ? 1.0 / options_.time.scale : 1.0;
  int64_t wall = monotonic_ns();
  const int64_t until = wall + kMaxPassWorkNs;
  // Each event's lateness against the clock read before its chunk of kEventsPerClock.
  const auto late = [&](model::SimTime at) {
    const double instant = static_cast<double>(at.ns()) * per_sim_ns;
    pacing_.event_late(wall - start_mono_ns_ - static_cast<int64_t>(std::min(instant, 9.0e18)));
  };
  while (s.run_until(target, kEventsPerClock, late) == kEventsPerClock) {
    wall = monotonic_ns();
    if (wall >= until) {
      break;  // the rest waits for the next pass (the timer is due at once)
    }
  }
  note_pace(monotonic_ns(), target);
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
    if (auto next = sim_.scheduler().next_event_time()) {
      // Absolute CLOCK_MONOTONIC deadline of the next simulated event, rounded up so the
      // timer never fires before the event is due; no sooner than one batch after the last
      // wake-up.
      const double scale = options_.time.mode == TimeMode::scaled ? options_.time.scale : 1.0;
      const double offset = std::ceil(static_cast<double>(next->ns()) / scale);
      const int64_t due = start_mono_ns_ + static_cast<int64_t>(std::min(offset, 9.0e18));
      const SimulationConfig& sc = sim_.config().simulation;
      deadline_ns_ = std::max(due, last_wake_ns_ + int64_t{sc.batch_us} * 1000);
      // Woken a little early (as early as the timer has lately been late, at most spin_us),
      // the loop spins to the deadline.
      const int64_t wall = std::max<int64_t>(1, deadline_ns_ - pacing_.spin_ns());
      armed_ns_ = wall;
      armed_ahead_ = wall > monotonic_ns();
      its.it_value.tv_sec = wall / 1'000'000'000;
      its.it_value.tv_nsec = wall % 1'000'000'000;
    }
  }
  if (::timerfd_settime(timer_.get(), TFD_TIMER_ABSTIME, &its, nullptr) != 0) {
    log::error("timerfd_settime: {}", std::strerror(errno));
  }
}

int Server::run() {
  while (running_) {
    if (!run_once(-1)) {
      return 1;
    }
  }
  return 0;
}

bool Server::run_once(int timeout_ms) {
  constexpr int kMaxEvents = 32;
  epoll_event events[kMaxEvents];
  arm_timer();
  const int due_ms = housekeeping();
  if (due_ms >= 0 && (timeout_ms < 0 || due_ms < timeout_ms)) {
    timeout_ms = due_ms;
  }
  // While a step runs, the loop only looks at what came and runs the step's next slice.
  const int n = ::epoll_wait(epoll_.get(), events, kMaxEvents, stepping() ? 0 : timeout_ms);
  if (n < 0) {
    if (errno == EINTR) {
      return true;
    }
    log::error("epoll_wait: {}", std::strerror(errno));
    return false;
  }
  bool timer_woke = false;
  for (int i = 0; i < n; ++i) {
    if (events[i].data.fd == timer_.get() && deadline_ns_ != 0) {
      timer_woke = true;
      const int64_t fired = monotonic_ns();
      if (armed_ahead_) {  // a timer armed for the past says nothing about the timer
        pacing_.timer_late(fired - armed_ns_);
      }
      // The last few microseconds to the deadline, never longer than the spin.
      const int64_t until = std::min(deadline_ns_, fired + pacing_.spin_ns());
      while (monotonic_ns() < until) {
      }
    }
  }
  last_wake_ns_ = monotonic_ns();
  if (timer_woke) {
    pacing_.wakeup_late(last_wake_ns_ - deadline_ns_);
  }
  advance_to_now();  // events are handled at the simulated instant they are seen
  for (int i = 0; i < n; ++i) {
    const int fd = events[i].data.fd;
    if (fd == timer_.get()) {
      uint64_t expirations = 0;
      [[maybe_unused]] const ssize_t r = ::read(timer_.get(), &expirations, sizeof expirations);
    } else if (fd == listen_.get()) {
      accept_clients();
    } else if (watchdog_.valid() && fd == watchdog_.get()) {
      uint64_t expirations = 0;
      [[maybe_unused]] const ssize_t r = ::read(fd, &expirations, sizeof expirations);
      sd_notify(0, "WATCHDOG=1");
    } else if (fd == signals_.get()) {
      signalfd_siginfo si{};
      while (::read(signals_.get(), &si, sizeof si) == static_cast<ssize_t>(sizeof si)) {
        if (si.ssi_signo == SIGHUP) {
          if (stepping()) {
            reload_waiting_ = true;  // a reload changes the world: after the step
          } else {
            reload();
          }
        } else if (si.ssi_signo == SIGUSR2 && stall_hook_) {
          log::warning("test hook: the event loop stalls now");
          for (;;) {
            ::pause();  // until the watchdog's SIGABRT (or SIGKILL) ends the process
          }
        } else {
          log::info("signal {}, stopping", si.ssi_signo);
          sd_notify(0, "STOPPING=1");
          running_ = false;
        }
      }
    } else if (auto bell = doorbells_.find(fd); bell != doorbells_.end()) {
      if (!stepping()) {
        bell->second->kick();
      } else if (std::find(bells_rung_.begin(), bells_rung_.end(), fd) == bells_rung_.end()) {
        bells_rung_.push_back(fd);  // what it brings belongs after the step
      }
    } else {
      serve(fd);
    }
  }
  if (stepping()) {
    run_step_slice();
  }
  if (!stepping() && waits_for_steps_) {
    after_step_runs();
  }
  check_channels();
  flush_recorders();
  send_outboxes();
  drop_closing();
  send_notifications();
  return true;
}

void Server::flush_recorders() {
  for (const std::string& line : sim_.flush_recorders()) {
    log::error("{}", line);
  }
}

void Server::kick_all_channels() {
  for (auto& [fd, c] : clients_) {
    ControlDispatcher::for_each_ring(c.session, [](Doorbell& d) { d.kick(); });
  }
  // What arrived on the bridges is sent in the step too, whichever the loop saw first.
  for (const auto& b : sim_.bridges()) {
    b->kick();
  }
}

// A client whose ring positions make no sense is dropped; the others go on.
void Server::check_channels() {
  for (auto& entry : clients_) {
    Client& c = entry.second;
    ControlDispatcher::for_each_ring(c.session, [&c](Doorbell& d) {
      if (!c.closing && d.broken()) {
        log::warning("client {} ({}): a ring was corrupted; disconnecting", c.session.pid,
                     c.session.name);
        c.closing = true;
      }
    });
  }
}

// Sent in the order they were made; a client that does not read them is dropped.
void Server::send_outboxes() {
  for (auto& [fd, c] : clients_) {
    for (auto* out : {&c.session.xcan.outbox, &c.session.slcan.outbox}) {
      while (!out->empty() && !c.closing) {
        if (!ipc::send_packet(fd, out->front().data(), out->front().size())) {
          c.closing = true;
        }
        out->pop_front();
      }
      out->clear();
    }
  }
}

void Server::send_notifications() {
  // Sending can drop a client (full socket), which can remove devices and add notifications.
  while (!pending_notifications_.empty()) {
    std::vector<ipc::Notification> batch;
    batch.swap(pending_notifications_);
    for (const ipc::Notification& n : batch) {
      for (auto& [fd, c] : clients_) {
        if (!c.closing && (c.session.events & ipc::kEventDevices) && !ipc::send_message(fd, n)) {
          c.closing = true;  // a subscriber that does not read its notifications
        }
      }
    }
    drop_closing();
  }
}

void Server::fill_clients(ipc::ClientListReply& r) {
  // The page from r.first on; total counts them all.
  r.total = 0;
  std::size_t n = 0;
  for (auto& [fd, c] : clients_) {
    if (c.closing || !c.refused.empty()) {
      continue;
    }
    if (r.total++ >= r.first && n < ipc::kClientPage) {
      ipc::ClientEntry& e = r.clients[n++];
      ipc::copy_name(e.name, c.session.name);
      e.pid = c.session.pid;
      e.uid = c.session.uid;
      // Channels of ephemeral devices and VCI channels alike.
      const auto vci_channels =
          std::count_if(c.session.vci.handles.begin(), c.session.vci.handles.end(),
                        [](const auto& h) { return h.second->kind() == VciHandle::Kind::channel; });
      e.channels =
          static_cast<uint32_t>(c.session.channels.size()) + static_cast<uint32_t>(vci_channels);
    }
  }
  r.count = static_cast<uint16_t>(n);
}

void Server::accept_clients() {
  while (true) {
    const int fd = ::accept4(listen_.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE) {
        // Out of descriptors: stop accepting until a client leaves, instead of spinning on a
        // listening socket that stays readable.
        ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, listen_.get(), nullptr);
        accepting_ = false;
        log::warning("out of file descriptors; not accepting for now");
      }
      return;  // EAGAIN: no more; other errors: the client is gone already
    }
    Client c;
    c.fd.reset(fd);
    c.accepted_ns = monotonic_ns();
    ucred cred{};
    socklen_t len = sizeof cred;
    if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0) {
      continue;  // unknown peer: refused (closed when c goes out of scope)
    }
    c.session.uid = cred.uid;
    c.session.gid = cred.gid;
    c.session.pid = static_cast<uint32_t>(cred.pid);
    c.session.vci.pid = c.session.pid;
    c.session.vci.uid = c.session.uid;
    c.session.admin = access_.admin(fd, c.session.uid, c.session.gid);
    // Slots: the connections being served (not refused, not on their way out).
    const auto served = [this] {
      return static_cast<std::size_t>(std::count_if(
          clients_.begin(), clients_.end(),
          [](const auto& e) { return e.second.refused.empty() && !e.second.closing; }));
    };
    const auto waiting = static_cast<std::size_t>(std::count_if(
        clients_.begin(), clients_.end(), [](const auto& e) { return !e.second.refused.empty(); }));
    const std::size_t limit = c.session.admin ? kMaxClients : kMaxClients - kAdminSlots;
    if (served() >= limit) {
      evict_silent(c.accepted_ns - kSilentEvictNs);  // frees a slot, if one was silent long
    }
    if (served() >= limit) {
      const std::string why =
          c.session.admin ? fmt::format("canemud serves at most {} clients", kMaxClients)
                          : fmt::format(
                                "canemud serves at most {} clients (the last {} of {} are kept for "
                                "administrators)",
                                limit, kAdminSlots, kMaxClients);
      reply_error(c, 0, ipc::ErrorCode::no_resources, why);
      log_refusal(fmt::format("refused uid {} (pid {}): {}", c.session.uid, c.session.pid, why));
      continue;
    }
    if (!access_.allowed(fd, c.session.uid, c.session.gid)) {
      c.refused =
          fmt::format("uid {} is not allowed by the [security] configuration", c.session.uid);
      log_refusal(fmt::format("refused uid {} (pid {}): not allowed by [security]", c.session.uid,
                              c.session.pid));
    } else if (const std::size_t held = connections_of(c.session.uid);
               c.session.uid != 0 && held >= sim_.config().security.max_clients_per_user) {
      c.refused = fmt::format(
          "uid {} has {} connections to canemud; [security] max_clients_per_user allows {}",
          c.session.uid, held, sim_.config().security.max_clients_per_user);
      c.refused_code = ipc::ErrorCode::no_resources;
      log_refusal(fmt::format("refused uid {} (pid {}): {} connections, the most one user may have",
                              c.session.uid, c.session.pid, held));
    }
    if (!c.refused.empty() && waiting >= kMaxRefusedWaiting) {
      reply_error(c, 0, c.refused_code, c.refused);
      continue;  // closed when c goes out of scope
    }
    if (!add(epoll_.get(), fd)) {
      continue;
    }
    c.serial = ++client_serials_;
    clients_.emplace(fd, std::move(c));
  }
}

void Server::log_refusal(const std::string& line) {
  const int64_t now = monotonic_ns();
  end_refusal_window(now);
  if (refusals_logged_ == 0 && refusals_unlogged_ == 0) {
    refusal_window_ns_ = now;
  }
  if (refusals_logged_ < kRefusalLines) {
    ++refusals_logged_;
    log::warning("{}", line);
  } else {
    ++refusals_unlogged_;
  }
}

void Server::end_refusal_window(int64_t now_ns) {
  if ((refusals_logged_ == 0 && refusals_unlogged_ == 0) ||
      now_ns - refusal_window_ns_ < kRefusalWindowNs) {
    return;
  }
  if (refusals_unlogged_ > 0) {
    log::warning("{} more connection{} refused in {} s (the first {} were logged)",
                 refusals_unlogged_, refusals_unlogged_ == 1 ? "" : "s",
                 kRefusalWindowNs / 1'000'000'000, kRefusalLines);
  }
  refusals_logged_ = 0;
  refusals_unlogged_ = 0;
}

bool Server::evict_silent(int64_t before_ns) {
  Client* oldest = nullptr;
  for (auto& [fd, c] : clients_) {
    if (!c.closing && !c.session.greeted && c.refused.empty() && c.accepted_ns < before_ns &&
        (oldest == nullptr || c.accepted_ns < oldest->accepted_ns)) {
      oldest = &c;
    }
  }
  if (oldest == nullptr) {
    return false;
  }
  reply_error(*oldest, 0, ipc::ErrorCode::no_resources,
              fmt::format("canemud is full and this connection had not said hello for {} s",
                          kSilentEvictNs / 1'000'000'000));
  log_refusal(
      fmt::format("closed a connection of uid {} (pid {}): no hello, and its slot was "
                  "wanted",
                  oldest->session.uid, oldest->session.pid));
  oldest->closing = true;
  return true;
}

int Server::housekeeping() {
  const int64_t now = monotonic_ns();
  end_refusal_window(now);
  int64_t next = refusals_unlogged_ > 0 ? refusal_window_ns_ + kRefusalWindowNs : INT64_MAX;
  for (auto& [fd, c] : clients_) {
    if (c.closing || c.session.greeted) {
      continue;
    }
    const int64_t deadline = c.accepted_ns + kHelloDeadlineNs;
    if (now < deadline) {
      next = std::min(next, deadline);
      continue;
    }
    // Silent since it connected: told why (a refused one its refusal) and closed.
    if (c.refused.empty()) {
      reply_error(
          c, 0, ipc::ErrorCode::not_hello,
          fmt::format("no hello within {} s of connecting", kHelloDeadlineNs / 1'000'000'000));
      log_refusal(fmt::format("closed a connection of uid {} (pid {}): no hello within {} s",
                              c.session.uid, c.session.pid, kHelloDeadlineNs / 1'000'000'000));
    } else {
      reply_error(c, 0, c.refused_code, c.refused);
    }
    c.closing = true;
  }
  drop_closing();
  if (next == INT64_MAX) {
    return -1;
  }
  return static_cast<int>(std::min<int64_t>((next - now) / 1'000'000 + 1, INT32_MAX));
}

// Connections of `uid` being served (refused and closing ones not counted).
std::size_t Server::connections_of(uint32_t uid) const {
  return static_cast<std::size_t>(
      std::count_if(clients_.begin(), clients_.end(), [&](const auto& e) {
        return e.second.session.uid == uid && e.second.refused.empty() && !e.second.closing;
      }));
}

// After a reload: a client the new [security] no longer allows is told why and dropped.
void Server::drop_revoked_clients() {
  for (auto& [fd, c] : clients_) {
    c.session.admin = access_.admin(fd, c.session.uid, c.session.gid);
    if (!c.closing && c.refused.empty() && !access_.allowed(fd, c.session.uid, c.session.gid)) {
      log::warning("reload: uid {} (pid {}, \"{}\") is no longer allowed; connection closed",
                   c.session.uid, c.session.pid, c.session.name);
      reply_error(c, 0, ipc::ErrorCode::permission_denied,
                  fmt::format("uid {} is no longer allowed by the [security] configuration",
                              c.session.uid));
      c.closing = true;  // dropped after this batch, with everything it opened
    }
  }
}

// Counts clients whose socket is still open; the ones that went away are dropped after the
// current batch of events (never while one of their requests is being answered).
uint16_t Server::live_clients() {
  uint16_t live = 0;
  for (auto& [fd, c] : clients_) {
    pollfd p{fd, POLLRDHUP, 0};
    if (::poll(&p, 1, 0) == 1 && (p.revents & (POLLRDHUP | POLLHUP | POLLERR))) {
      c.closing = true;
    } else if (c.refused.empty()) {
      ++live;
    }
  }
  return live;
}

void Server::drop_closing() {
  if (stepping()) {
    return;  // a client's channels and devices leave the world after the step
  }
  std::vector<int> gone;
  for (const auto& [fd, c] : clients_) {
    if (c.closing) {
      gone.push_back(fd);
    }
  }
  for (int fd : gone) {
    drop(fd);
  }
}

void Server::drop(int fd) {
  ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, fd, nullptr);
  auto it = clients_.find(fd);
  if (it == clients_.end()) {
    return;
  }
  // Its channels stop their nodes and their devices go (notified after this batch); what it
  // opened through the VCI is closed.
  dispatcher_.end_session(it->second.session);
  clients_.erase(it);
  if (!accepting_ && add(epoll_.get(), listen_.get())) {
    accepting_ = true;  // a descriptor is free again
  }
}

void Server::serve(int fd) {
  auto it = clients_.find(fd);
  if (it == clients_.end()) {
    return;
  }
  if (it->second.closing || !it->second.held.empty()) {
    return;  // a held request first (its later ones wait in the socket)
  }
  auto n = ipc::receive_packet(fd, buffer_, 0);
  if (!n && n.error().error_number == ETIMEDOUT) {
    return;  // nothing to read: a stale event for a descriptor number reused in this batch
  }
  if (!n || *n == 0) {
    it->second.closing = true;  // closed, oversized or broken: dropped after this batch
    return;
  }
  if (!it->second.refused.empty()) {
    ipc::MsgHeader h{};
    std::memcpy(&h, buffer_.data(), std::min(sizeof h, buffer_.size()));
    reply_error(it->second, h.request_id, it->second.refused_code, it->second.refused);
    it->second.closing = true;
    return;
  }
  if (stepping() && !reads_only(buffer_)) {
    it->second.held = buffer_;
    waits_for_steps_ = true;
    return;
  }
  handle(it->second, buffer_);
}

bool Server::reads_only(const std::vector<uint8_t>& packet) {
  ipc::MsgHeader h{};
  if (packet.size() < sizeof h) {
    return true;  // answered with an error at once
  }
  std::memcpy(&h, packet.data(), sizeof h);
  switch (static_cast<ipc::MsgType>(h.type)) {
    case ipc::MsgType::hello:
    case ipc::MsgType::status_request:
    case ipc::MsgType::channel_status_request:
    case ipc::MsgType::device_list_request:
    case ipc::MsgType::client_list_request:
    case ipc::MsgType::subscribe_request:
    case ipc::MsgType::fault_list_request:
    case ipc::MsgType::recorder_list_request:
    case ipc::MsgType::bridge_list_request:
    case ipc::MsgType::peer_list_request:
    case ipc::MsgType::timeline_request:
      return true;
    default:
      return false;
  }
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

void Server::reply_error(Client& c, uint32_t request_id, ipc::ErrorCode code,
                         const std::string& text) {
  auto e = ipc::make_message<ipc::ErrorReply>(request_id);
  e.code = static_cast<uint32_t>(code);
  ipc::copy_name(e.message, text);
  (void)ipc::send_message(c.fd.get(), e);
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

void Server::handle(Client& c, const std::vector<uint8_t>& packet) {
  current_ = &c;
  dispatcher_.handle(c.session, packet.data(), packet.size(),
                     [&c](const void* data, std::size_t size, std::span<const int> fds) {
                       // A client that does not read its replies is dropped, not waited for.
                       if (!ipc::send_packet(c.fd.get(), data, size, fds)) {
                         c.closing = true;
                       }
                     });
}

// ---- what the dispatcher and the link between daemons ask of the loop ----

void Server::before_status() {
  advance_to_now();
  flush_recorders();
}

uint16_t Server::client_count() {
  return live_clients();
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
  if (auto problem = d->step(step_ns, token)) {
    pending_steps_.erase(token);
    reply_error(*current_, request_id, ipc::ErrorCode::not_stepped, *problem);
  }
  return true;
}

void Server::watch(Doorbell& bell) {
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.fd = bell.doorbell_fd();
  if (::epoll_ctl(epoll_.get(), EPOLL_CTL_ADD, bell.doorbell_fd(), &ev) == 0) {
    doorbells_[bell.doorbell_fd()] = &bell;
  }
}

void Server::unwatch(Doorbell& bell) {
  ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, bell.doorbell_fd(), nullptr);
  doorbells_.erase(bell.doorbell_fd());
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
