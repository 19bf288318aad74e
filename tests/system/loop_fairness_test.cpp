// One client never stalls or locks out the others: a long step runs in slices between which
// canemud serves everyone and pings the watchdog, requests that change the world wait for the
// step's end, connections that never say hello are closed, and the last slots are kept for an
// administrator (docs/security.md).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <grp.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../support/temp_dir.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/ipc/seqpacket.hpp"
#include "daemon_process.hpp"
#include "pipe_support.hpp"

namespace canemu {
namespace {

using testing::Daemon;

// `buses` 1 Mbit/s buses can0.. in stepped time, each with a babbling node (an ephemeral
// channel's node that a babble fault makes send back to back) and a second node that
// acknowledges; the channels belong to `owner`.
struct BusyBuses {
  std::vector<client::Channel> channels;
  std::string open(client::Connection& owner, int buses) {
    std::string scenario = "[scenario]\nname = \"babble\"\n";
    for (int i = 0; i < buses; ++i) {
      for (const char* role : {"tx", "rx"}) {
        client::ChannelOptions o;
        o.bus = "can" + std::to_string(i);
        o.device = role + std::to_string(i);
        o.rx_capacity = 16;
        o.tx_capacity = 16;
        auto ch = client::Channel::open(owner, o);
        if (!ch) {
          return ch.error().message;
        }
        channels.push_back(std::move(*ch));
      }
      scenario += "[[fault]]\nat = \"0s\"\nnode = \"tx" + std::to_string(i) +
                  ":0\"\neffect = \"babble\"\nid = 0\ndata = [1, 2, 3, 4, 5, 6, 7, 8]\n"
                  "duration = \"3600s\"\n";
    }
    auto load = std::make_unique<ipc::FaultLoadRequest>(ipc::make_message<ipc::FaultLoadRequest>());
    ipc::copy_name(load->source, "busy");
    load->length = static_cast<uint32_t>(scenario.size());
    std::memcpy(load->text, scenario.data(), scenario.size());
    auto loaded = owner.call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(*load);
    if (!loaded) {
      return loaded.error().message;
    }
    return loaded->applied == 1 ? std::string() : std::string(loaded->errors);
  }
};

std::string busy_config(const testing::TempDir& dir, int buses) {
  const std::string path = (dir.path / "busy.toml").string();
  std::ofstream f(path);
  f << "[simulation]\ntime = \"stepped\"\n";
  for (int i = 0; i < buses; ++i) {
    f << "[[bus]]\nname = \"can" << i << "\"\nbitrate = 1000000\n";
  }
  return path;
}

// A datagram socket standing in for systemd's notification socket: counts WATCHDOG=1.
struct NotifySocket {
  ipc::UniqueFd fd;
  std::string path;
  explicit NotifySocket(const testing::TempDir& dir) : path((dir.path / "notify").string()) {
    fd.reset(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path.c_str(), sizeof a.sun_path - 1);
    EXPECT_EQ(::bind(fd.get(), reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  }
  // The watchdog pings that came since the last call.
  int pings() const {
    int n = 0;
    char buf[512];
    ssize_t got = 0;
    while ((got = ::recv(fd.get(), buf, sizeof buf - 1, 0)) > 0) {
      buf[got] = '\0';
      n += std::strstr(buf, "WATCHDOG=1") != nullptr ? 1 : 0;
    }
    return n;
  }
};

// A 20 s step of two busy buses takes a while (in a sanitizer build too, seconds); meanwhile
// another client is answered, sees the step's progress, and the watchdog is pinged. A scenario
// loaded during the step starts at its end: requests that change the world wait for the step.
TEST(LoopFairness, ALongStepLeavesOthersServedAndTheWatchdogPinged) {
  testing::TempDir dir;
  NotifySocket notify(dir);
  ::setenv("NOTIFY_SOCKET", notify.path.c_str(), 1);
  ::setenv("WATCHDOG_USEC", "20000", 1);  // a ping every 10 ms
  Daemon d("stepped", {"--config=" + busy_config(dir, 2)});
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");
  auto owner = testing::connect(d, "owner");
  BusyBuses busy;
  ASSERT_EQ(busy.open(owner, 2), "");
  auto stepper = testing::connect(d, "stepper");
  auto other = testing::connect(d, "other");
  auto loader = testing::connect(d, "loader");
  constexpr int64_t kStep = int64_t{20} * 1'000'000'000;
  std::atomic<bool> stepped{false};
  int64_t step_end = -1;
  std::thread step([&] {
    auto req = ipc::make_message<ipc::TimeStepRequest>();
    req.step_ns = kStep;
    auto r = stepper.call<ipc::TimeStepRequest, ipc::TimeStepReply>(req, -1);
    step_end = r ? r->sim_time_ns : -2;
    stepped = true;
  });
  notify.pings();  // those before the step
  int answered_during = 0;
  int pings_during = 0;
  int64_t seen_mid_step = -1;
  std::thread load;  // the scenario's "at 0s" is the instant canemud takes the request
  std::atomic<uint32_t> applied{2};
  while (!stepped) {
    auto s =
        other.call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
    ASSERT_TRUE(s) << s.error().message;
    pings_during += notify.pings();
    if (stepped) {
      break;
    }
    ++answered_during;
    if (s->sim_time_ns > 0 && s->sim_time_ns < kStep) {
      seen_mid_step = s->sim_time_ns;
      if (!load.joinable()) {
        load = std::thread([&] {
          const std::string text =
              "[scenario]\nname = \"late\"\n[[fault]]\nat = \"0s\"\nbus = \"can0\"\n"
              "effect = \"ack_suppress\"\nduration = \"1ms\"\n";
          auto m =
              std::make_unique<ipc::FaultLoadRequest>(ipc::make_message<ipc::FaultLoadRequest>());
          m->length = static_cast<uint32_t>(text.size());
          std::memcpy(m->text, text.data(), text.size());
          auto r = loader.call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(*m, -1);
          applied = r ? r->applied : 3;
        });
      }
    }
  }
  step.join();
  ASSERT_TRUE(load.joinable());
  load.join();
  EXPECT_EQ(applied, 1u);
  EXPECT_EQ(step_end, kStep);
  EXPECT_GT(answered_during, 0);
  EXPECT_GT(seen_mid_step, 0) << "no status answer showed the step in progress";
  // A ping every 10 ms; a loop held by the step pings once, after it.
  EXPECT_GE(pings_during, 2) << "the watchdog was not pinged while the step ran";
  auto faults = other.call<ipc::FaultListRequest, ipc::FaultListReply>(
      ipc::make_message<ipc::FaultListRequest>());
  ASSERT_TRUE(faults) << faults.error().message;
  bool found = false;
  for (uint16_t i = 0; i < faults->count; ++i) {
    if (ipc::name_of(faults->faults[i].scenario) == "late") {
      found = true;
      EXPECT_EQ(faults->faults[i].at_ns, kStep) << "a request that changes the world ran mid-step";
    }
  }
  EXPECT_TRUE(found);
}

// Two steps asked for at once run one after the other, each its whole length.
TEST(LoopFairness, StepsAskedForWhileOneRunsRunAfterIt) {
  testing::TempDir dir;
  Daemon d("stepped", {"--config=" + busy_config(dir, 1)});
  auto owner = testing::connect(d, "owner");
  BusyBuses busy;
  ASSERT_EQ(busy.open(owner, 1), "");
  auto a = testing::connect(d, "a");
  auto b = testing::connect(d, "b");
  int64_t end_a = 0;
  int64_t end_b = 0;
  std::thread ta([&] {
    auto req = ipc::make_message<ipc::TimeStepRequest>();
    req.step_ns = 2'000'000'000;
    auto r = a.call<ipc::TimeStepRequest, ipc::TimeStepReply>(req, -1);
    end_a = r ? r->sim_time_ns : -1;
  });
  std::thread tb([&] {
    auto req = ipc::make_message<ipc::TimeStepRequest>();
    req.step_ns = 3'000'000'000;
    auto r = b.call<ipc::TimeStepRequest, ipc::TimeStepReply>(req, -1);
    end_b = r ? r->sim_time_ns : -1;
  });
  ta.join();
  tb.join();
  // Whichever came first ended at its length; the other 5 s in.
  EXPECT_TRUE((end_a == 2'000'000'000 && end_b == 5'000'000'000) ||
              (end_b == 3'000'000'000 && end_a == 5'000'000'000))
      << end_a << " " << end_b;
  EXPECT_EQ(testing::status(owner).sim_time_ns, 5'000'000'000);
}

// A raw connection that says nothing.
ipc::UniqueFd silent(const Daemon& d) {
  auto fd = ipc::connect_seqpacket(d.socket());
  EXPECT_TRUE(fd) << fd.error().message;
  return fd ? std::move(*fd) : ipc::UniqueFd();
}

// The error canemud sent on `fd` within `timeout_ms`, or "".
std::string error_on(const ipc::UniqueFd& fd, int timeout_ms) {
  std::vector<uint8_t> buffer;
  auto n = ipc::receive_packet(fd.get(), buffer, timeout_ms);
  if (!n || *n < sizeof(ipc::ErrorReply)) {
    return "";
  }
  ipc::ErrorReply e{};
  std::memcpy(&e, buffer.data(), sizeof e);
  return ipc::name_of(e.message);
}

// Connections that never say hello hold no slot for long: when all 256 are taken, a new client
// takes the slot of the oldest connection silent for a second (which is told why), and each silent
// one is closed with the reason 5 s after it connected. Refusals and such closings are logged at
// most five times in ten seconds.
TEST(LoopFairness, ConnectionsThatNeverSayHelloGiveWay) {
  Daemon d("stepped");
  std::vector<ipc::UniqueFd> quiet;
  for (int i = 0; i < 256; ++i) {
    quiet.push_back(silent(d));
  }
  // Refused while the silent ones are younger than a second; then served.
  std::optional<client::Connection> served;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!served && std::chrono::steady_clock::now() < deadline) {
    if (auto c = client::Connection::open(d.socket(), "served")) {
      served.emplace(std::move(*c));
    }
  }
  ASSERT_TRUE(served) << d.log();
  EXPECT_EQ(testing::status(*served).bus_count, 3);
  int gave_way = 0;
  int timed_out = 0;
  for (const ipc::UniqueFd& fd : quiet) {
    const std::string why = error_on(fd, 10'000);
    gave_way += why == "canemud is full and this connection had not said hello for 1 s" ? 1 : 0;
    timed_out += why == "no hello within 5 s of connecting" ? 1 : 0;
    std::vector<uint8_t> buffer;
    auto end = ipc::receive_packet(fd.get(), buffer, 5000);
    EXPECT_TRUE(end && *end == 0) << "the connection stayed open";
  }
  EXPECT_EQ(gave_way, 1);
  EXPECT_EQ(timed_out, 255);
  EXPECT_EQ(testing::status(*served).client_count, 1);
  d.terminate(5000);
  d.read_log_until("no such text", 200);
  std::size_t lines = 0;
  for (const char* what : {"refused uid", "closed a connection"}) {
    for (std::size_t at = d.log().find(what); at != std::string::npos;
         at = d.log().find(what, at + 1)) {
      ++lines;
    }
  }
  EXPECT_EQ(lines, 5u) << d.log();
}

// The last slots are an administrator's: a user who filled the rest is told so, and root's
// status still works.
TEST(LoopFairness, TheLastSlotsAreKeptForAnAdministrator) {
  if (::geteuid() != 0) {
    GTEST_SKIP() << "needs root to run clients as another user";
  }
  testing::TempDir dir;
  const std::string config = (dir.path / "c.toml").string();
  {
    std::ofstream f(config);
    f << "[[bus]]\nname = \"can0\"\n[security]\nallowed_users = [\"nobody\"]\n"
         "socket_mode = 0o666\nsocket_group = \"\"\nmax_clients_per_user = 256\n";
  }
  Daemon d("stepped", {"--config=" + config});
  std::string socket = d.socket();
  ::chmod(socket.substr(0, socket.rfind('/')).c_str(), 0755);
  testing::Pipe done;
  testing::Pipe go_on;
  ASSERT_TRUE(done.ok() && go_on.ok());
  const pid_t child = ::fork();
  if (child == 0) {
    if (::setgroups(0, nullptr) != 0 || ::setgid(65534) != 0 || ::setuid(65534) != 0) {
      ::_exit(3);
    }
    std::vector<client::Connection> held;
    std::string last;
    for (int i = 0; i < 260; ++i) {
      auto c = client::Connection::open(socket, "many");
      if (!c) {
        last = c.error().message;
        break;
      }
      held.push_back(std::move(*c));
    }
    const std::string report = std::to_string(held.size()) + "|" + last;
    [[maybe_unused]] ssize_t w = ::write(done[1], report.data(), report.size());
    done.close(1);
    char byte = 0;
    [[maybe_unused]] ssize_t r = ::read(go_on[0], &byte, 1);
    ::_exit(0);
  }
  done.close(1);
  std::string report;
  char buf[1024];
  for (ssize_t n = 0; (n = ::read(done[0], buf, sizeof buf)) > 0;) {
    report.append(buf, static_cast<std::size_t>(n));
  }
  EXPECT_EQ(report.substr(0, report.find('|')), "252");
  EXPECT_NE(report.find("canemud serves at most 252 clients (the last 4 of 256 are kept for "
                        "administrators)"),
            std::string::npos)
      << report;
  auto admin = testing::connect(d, "admin");
  EXPECT_EQ(testing::status(admin).bus_count, 1);
  ASSERT_EQ(::write(go_on[1], "x", 1), 1);
  ::waitpid(child, nullptr, 0);
}

}  // namespace
}  // namespace canemu
