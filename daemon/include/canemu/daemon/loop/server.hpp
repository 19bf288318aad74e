// canemud's event loop: one thread, epoll over the control socket, the clients, a timer for the
// next simulated event and the signals. Time follows the configured mode:
//   realtime  simulated time = CLOCK_MONOTONIC since start;
//   scaled:F  simulated time = F x CLOCK_MONOTONIC since start;
//   stepped   simulated time moves only on a client's time-step request.
#pragma once

#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/control/control_dispatcher.hpp"
#include "canemu/daemon/distributed/distributed.hpp"
#include "canemu/daemon/loop/access_policy.hpp"
#include "canemu/daemon/loop/batch_window.hpp"
#include "canemu/daemon/loop/cpu_latency.hpp"
#include "canemu/daemon/loop/pacing.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/ipc/seqpacket.hpp"

struct epoll_event;

namespace canemu::daemon {

struct ServerOptions {
  std::string socket_path;
  TimeSetting time;
  std::string config_file;                   // read again on SIGHUP; empty: the embedded one
  std::optional<TimeSetting> time_override;  // --time, which a reload keeps
};

// The loop is what the dispatcher and the link between daemons ask things of (LoopServices,
// StepLoop): it watches doorbells, runs steps in slices and answers them.
class Server final : private LoopServices, private StepLoop {
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
    uint64_t serial = 0;      // tells a later client on the same descriptor apart
    int64_t accepted_ns = 0;  // CLOCK_MONOTONIC: it must say hello within kHelloDeadlineNs
    // A request that changes the world, read while a step ran: handled when the steps are done
    // (the client's later requests stay in its socket until then).
    std::vector<uint8_t> held;
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
  void step_done(uint64_t token, uint64_t events_run, int64_t sim_ns,
                 const std::string& note) override;
  void answer_step(const PendingStep& p, uint64_t events_run, int64_t sim_ns,
                   const std::string& note = {});

  // Stepped time: a step runs in slices of at most kMaxPassWorkNs of wall time, between which
  // the loop serves new clients, requests that only read, the watchdog and signals. Requests
  // that change the world, doorbells and reloads wait until the steps have run, so a step
  // takes everything queued before it and nothing that came while it ran (docs/daemon.md,
  // "Long steps"). Steps asked for while one runs run after it, in order.
  struct StepRun {
    std::function<model::SimTime()> start;  // called when the run begins: returns its end
    std::function<void(uint64_t events)> done;
    model::SimTime until;
    bool started = false;
    uint64_t events = 0;
  };
  std::deque<StepRun> step_runs_;
  std::vector<int> bells_rung_;   // doorbells that rang during a step: kicked once it has run
  bool reload_waiting_ = false;   // a SIGHUP during a step
  bool waits_for_steps_ = false;  // something above, or a held request, waits for the steps
  bool stepping() const { return !step_runs_.empty(); }
  void queue_local_step(int64_t step_ns, uint32_t request_id);
  void queue_step_run(std::function<model::SimTime()> start,
                      std::function<void(uint64_t events)> done);
  // Runs what is queued to its end now (a message from another daemon must come after it).
  void finish_step_runs();
  // Runs the current step for one slice; when the last one has ended, what waited is served.
  void run_step_slice();
  void after_step_runs();
  // Requests a client may make while a step runs: they read the world and change nothing.
  static bool reads_only(const std::vector<uint8_t>& packet);
  static constexpr std::size_t kMaxClients = 256;
  // Refused peers kept until their first request (to answer it with the reason): at most this
  // many at once, so that refused peers never take the slots of allowed ones; beyond it a refused
  // peer is told at once and closed.
  static constexpr std::size_t kMaxRefusedWaiting = 16;
  // The last kAdminSlots of the kMaxClients are kept for administrators (root, the daemon's
  // user, [security] admin_groups), so `canemu status` works however many clients there are.
  static constexpr std::size_t kAdminSlots = 4;
  // A connection says hello at once: one that has not within kHelloDeadlineNs is told so and
  // closed; when every slot is taken, a new connection takes the slot of the oldest one that has
  // been silent for kSilentEvictNs (docs/security.md).
  static constexpr int64_t kHelloDeadlineNs = 5'000'000'000;
  static constexpr int64_t kSilentEvictNs = 1'000'000'000;
  // Closes the oldest connection that has not said hello since before `before_ns`; false if
  // there is none.
  bool evict_silent(int64_t before_ns);
  // Refusals are logged, at most kRefusalLines in kRefusalWindowNs; then one line says how many
  // more there were.
  static constexpr int kRefusalLines = 5;
  static constexpr int64_t kRefusalWindowNs = 10'000'000'000;
  int64_t refusal_window_ns_ = 0;  // CLOCK_MONOTONIC the current window began
  int refusals_logged_ = 0;
  uint64_t refusals_unlogged_ = 0;
  void log_refusal(const std::string& line);
  void end_refusal_window(int64_t now_ns);
  // Drops connections past their hello deadline; returns the ms until the next deadline of
  // this housekeeping (-1: none).
  int housekeeping();

  // Simulated time at CLOCK_MONOTONIC `mono_ns` (real and scaled time).
  model::SimTime wall_to_sim(int64_t mono_ns) const;
  model::SimTime wall_to_sim() const;
  void advance_to_now();
  // Runs the events due up to `target` (at most kMaxPassWorkNs of wall time from `wall`).
  void run_events_until(model::SimTime target, int64_t wall);
  // The doorbells among this wake-up's `events` whose client said when it rang (within
  // kMaxRungAgeNs): each kicked at that instant of simulated time, earliest first, the events due
  // before it run first; their entries in `events` are set to fd -1.
  void kick_rung_doorbells(epoll_event* events, int n);
  static constexpr int64_t kMaxRungAgeNs = 10'000'000;
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
  // LoopServices and StepLoop.
  void before_status() override;
  uint16_t client_count() override;
  void fill_pace(ipc::StatusReply& r) override;
  void fill_clients(ipc::ClientListReply& r) override;
  bool defer_step(int64_t step_ns, uint32_t request_id) override;
  void watch(Doorbell& bell) override;
  void unwatch(Doorbell& bell) override;
  void before_step() override;
  void after_step() override;
  void run_to(model::SimTime until, std::function<void(uint64_t events)> done) override;
  void finish_runs() override;
  void steps_failed(const std::string& why) override;
  int64_t monotonic_at(model::SimTime t) const override;
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
  BatchWindow batch_;         // how long events gather before the loop wakes for them
  uint64_t turn_events_ = 0;  // events run since the last wake-up
  bool accepting_ = true;
  bool socket_from_systemd_ = false;      // socket activation: systemd owns the file
  AccessPolicy::SocketFile socket_file_;  // the file bound (its mode and group follow reloads)
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
  // A step's slice reads the clock every kEventsPerStepClock events (nobody waits on an
  // event's instant there).
  static constexpr std::size_t kEventsPerStepClock = 64;
  Pacing pacing_;
  // simulation.cpu_latency_us, held in real and scaled time; the log says what changed.
  CpuLatencyRequest cpu_latency_;
  void hold_cpu_latency();
  int64_t armed_ns_ = 0;      // CLOCK_MONOTONIC the timer is armed for (the deadline less the spin)
  bool armed_ahead_ = false;  // ... and that instant was still ahead when armed
  bool timer_armed_ = true;   // the timer may be armed (false: disarmed by arm_timer)
  int64_t lag_ns_ = 0;        // simulated ns behind
  std::deque<std::pair<int64_t, int64_t>> pace_;  // (CLOCK_MONOTONIC, simulated) ns
  int64_t lag_logged_ns_ = 0;                     // CLOCK_MONOTONIC of the last lag warning
};

}  // namespace canemu::daemon
