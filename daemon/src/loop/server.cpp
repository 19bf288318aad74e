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
#include "loop/epoll.hpp"

namespace canemu::daemon {

namespace {

using ipc::monotonic_ns;

ipc::IpcError sys(const std::string& what) {
  const int e = errno;
  return ipc::IpcError{e, what + ": " + std::strerror(e)};
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
    return tl::unexpected(ipc::IpcError{EPERM, bound.error().what()});
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
  if (!epoll_add(epoll_.get(), listen_.get()) || !epoll_add(epoll_.get(), timer_.get()) ||
      !epoll_add(epoll_.get(), signals_.get())) {
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
        !epoll_add(epoll_.get(), watchdog_.get())) {
      return tl::unexpected(sys("watchdog timer"));
    }
  }
  ::signal(SIGPIPE, SIG_IGN);  // a closed stderr or peer must not kill the daemon
  // Timer deadlines are met to the microsecond, not within Linux's default 50 us slack.
  ::prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  start_mono_ns_ = monotonic_ns();
  hold_cpu_latency();
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
    hold_cpu_latency();
    log::info("reload of {} done: {} change{} applied, {} not", fresh->source, r.applied.size(),
              r.applied.size() == 1 ? "" : "s", r.refused.size());
  }
  sd_notify(0, "READY=1");
}

void Server::hold_cpu_latency() {
  // Stepped time waits for no wake-up: no request there.
  const std::optional<uint32_t> bound = options_.time.mode == TimeMode::stepped
                                            ? std::nullopt
                                            : sim_.config().simulation.cpu_latency_us;
  const std::optional<uint32_t> before = cpu_latency_.held();
  if (bound == before) {
    return;
  }
  if (std::string e = cpu_latency_.hold(bound); !e.empty()) {
    log::warning("simulation.cpu_latency_us {}: no request made: {}{}", *bound, e,
                 before ? fmt::format("; the request of {} us stays", *before) : "");
  } else if (bound) {
    log::info("CPUs asked to wake within {} us while canemud runs ({})", *bound,
              CpuLatencyRequest::file());
  } else {
    log::info("CPU wake-up latency request of {} us ended", *before);
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
  if (options_.time.mode != TimeMode::stepped) {
    kick_rung_doorbells(events, n);  // frames queued while the loop slept, at their instants
  }
  advance_to_now();  // events are handled at the simulated instant they are seen
  if (options_.time.mode != TimeMode::stepped) {
    batch_.woke(turn_events_, last_wake_ns_);  // the events since the wake-up before
    turn_events_ = 0;
  }
  for (int i = 0; i < n; ++i) {
    const int fd = events[i].data.fd;
    if (fd < 0) {
      continue;  // a doorbell kicked already (kick_rung_doorbells)
    }
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
  if (Distributed* d = Distributed::of(sim_)) {
    d->flush();  // what this turn did to other daemons' nodes: a sample for each daemon
  }
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
      if (out->empty()) {
        continue;  // nearly always: a pass costs no deque call per client
      }
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

// ---- what the dispatcher asks of the loop (the rest in server_clients.cpp, server_time.cpp) ----

void Server::before_status() {
  advance_to_now();
  flush_recorders();
}

void Server::watch(Doorbell& bell) {
  bell.set_arming(options_.time.mode != TimeMode::stepped);
  if (epoll_add(epoll_.get(), bell.doorbell_fd())) {
    doorbells_[bell.doorbell_fd()] = &bell;
  } else {
    // Its transmit ring is then looked at only when the loop kicks every channel.
    log::error("cannot watch a doorbell (descriptor {}): {}", bell.doorbell_fd(),
               std::strerror(errno));
  }
}

void Server::unwatch(Doorbell& bell) {
  ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, bell.doorbell_fd(), nullptr);
  doorbells_.erase(bell.doorbell_fd());
}

}  // namespace canemu::daemon
