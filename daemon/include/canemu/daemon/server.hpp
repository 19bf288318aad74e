// canemud's event loop: one thread, epoll over the control socket, the clients, a timer for the
// next simulated event and the signals. Time follows the configured mode:
//   realtime  simulated time = CLOCK_MONOTONIC since start;
//   scaled:F  simulated time = F x CLOCK_MONOTONIC since start;
//   stepped   simulated time moves only on a client's time-step request.
#pragma once

#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "canemu/daemon/access_policy.hpp"
#include "canemu/daemon/config.hpp"
#include "canemu/daemon/control_dispatcher.hpp"
#include "canemu/daemon/pacing.hpp"
#include "canemu/daemon/simulation.hpp"
#include "canemu/ipc/seqpacket.hpp"

namespace canemu::daemon {

struct ServerOptions {
  std::string socket_path;
  TimeSetting time;
  std::string config_file;                   // read again on SIGHUP; empty: the embedded one
  std::optional<TimeSetting> time_override;  // --time, which a reload keeps
};

class Server {
 public:
  Server(Simulation& sim, ServerOptions options);
  ~Server();

  // Opens the socket and the loop's descriptors; an error names the failing call.
  ipc::IpcResult<void> open();
  // Runs until SIGTERM or SIGINT (or stop()). Returns the exit code.
  int run();
  // One turn of the loop: waits up to `timeout_ms` (-1: until something happens) and serves
  // what came. False on a failure of epoll itself (logged). For run() and the fuzz target.
  bool run_once(int timeout_ms);
  bool running() const { return running_; }
  void stop() { running_ = false; }
  const std::string& socket_path() const { return options_.socket_path; }

 private:
  struct Client {
    ipc::UniqueFd fd;
    Session session;
    bool closing = false;  // gone or misbehaving: dropped after the current batch of events
    // Why canemud will not serve it: its first request is answered with this, then it is
    // dropped (closing at once could discard the answer with the request still unread).
    std::string refused;
    ipc::ErrorCode refused_code = ipc::ErrorCode::permission_denied;
    uint64_t serial = 0;  // tells a later client on the same descriptor apart
  };
  // A step request answered when the step has run across hosts (Distributed::step).
  struct PendingStep {
    int fd = -1;
    uint64_t serial = 0;
    uint32_t request_id = 0;
  };
  std::map<uint64_t, PendingStep> pending_steps_;
  uint64_t step_tokens_ = 0;
  uint64_t client_serials_ = 0;
  Client* current_ = nullptr;  // the client whose request is being handled
  void step_done(uint64_t token, uint64_t events_run, int64_t sim_ns);
  static constexpr std::size_t kMaxClients = 256;
  // Refused peers kept until their first request (to answer it with the reason): at most this
  // many at once, so that refused peers never take the slots of allowed ones; beyond it a refused
  // peer is told at once and closed.
  static constexpr std::size_t kMaxRefusedWaiting = 16;

  model::SimTime wall_to_sim() const;
  void advance_to_now();
  void arm_timer();
  void accept_clients();
  void serve(int fd);
  void drop(int fd);
  uint16_t live_clients();
  void drop_closing();
  void handle(Client& c, const std::vector<uint8_t>& packet);
  void reply_error(Client& c, uint32_t request_id, ipc::ErrorCode code, const std::string& text);
  void reload();
  void kick_all_channels();
  // Writes what recorders hold (each pass of the loop, before status, after a time step); logs
  // recorders that began to lose frames.
  void flush_recorders();
  void check_channels();
  void send_notifications();
  void send_outboxes();
  void fill_clients(ipc::ClientListReply& r);
  ipc::IpcResult<void> open_listener();
  void drop_revoked_clients();
  std::size_t connections_of(uint32_t uid) const;
  // Keeps the samples for the achieved scale, logs a lag now and then.
  void note_pace(int64_t mono_ns, model::SimTime target);
  double achieved_scale() const;

  Simulation& sim_;
  ServerOptions options_;
  ControlDispatcher dispatcher_;
  ipc::UniqueFd listen_;
  ipc::UniqueFd epoll_;
  ipc::UniqueFd timer_;
  ipc::UniqueFd signals_;
  ipc::UniqueFd watchdog_;  // only under systemd's watchdog
  std::map<int, Client> clients_;
  int64_t start_mono_ns_ = 0;
  int64_t last_wake_ns_ = 0;  // CLOCK_MONOTONIC of the loop's last wake-up
  int64_t deadline_ns_ = 0;   // of the armed timer (0: none)
  bool accepting_ = true;
  bool socket_from_systemd_ = false;  // socket activation: systemd owns the file
  AccessPolicy access_;
  bool running_ = true;
  bool stall_hook_ = false;  // CANEMU_TEST_HOOKS=stall-on-sigusr2
  std::vector<uint8_t> buffer_;
  std::map<int, Doorbell*> doorbells_;  // doorbell fd -> its channel
  std::vector<ipc::Notification> pending_notifications_;

  // Real and scaled time: one pass of the loop runs the simulation for at most kMaxPassWorkNs
  // of wall time (checked every kEventsPerClock events), so requests, doorbells and signals are
  // served at least that often whatever the load. When the scale cannot be kept, simulated time
  // lags behind the configured mapping instead (docs/daemon.md, "Time").
  static constexpr int64_t kMaxPassWorkNs = 2'000'000;
  // The clock is read every kEventsPerClock events: an event's lateness is measured against
  // the last reading (at most the time that many events take, a few microseconds, early).
  static constexpr std::size_t kEventsPerClock = 8;
  Pacing pacing_;
  int64_t armed_ns_ = 0;      // CLOCK_MONOTONIC the timer is armed for (the deadline less the spin)
  bool armed_ahead_ = false;  // ... and that instant was still ahead when armed
  int64_t lag_ns_ = 0;        // simulated ns behind
  std::deque<std::pair<int64_t, int64_t>> pace_;  // (CLOCK_MONOTONIC, simulated) ns
  int64_t lag_logged_ns_ = 0;                     // CLOCK_MONOTONIC of the last lag warning
};

}  // namespace canemu::daemon
