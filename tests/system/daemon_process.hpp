// canemud as a child process on a private socket, and helpers for its clients.
#pragma once

#include <gtest/gtest.h>

#include <csignal>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "canemu/client/connection.hpp"

extern char** environ;

namespace canemu::testing {

// Waits until `fd` is readable or `timeout_ms` passes.
inline bool readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) == 1;
}

class Daemon {
 public:
  explicit Daemon(const std::string& time = "stepped") {
    char dir[] = "/tmp/canemu-test-XXXXXX";
    dir_ = ::mkdtemp(dir);
    socket_ = dir_ + "/canemud.sock";
    int err[2];
    EXPECT_EQ(::pipe2(err, O_CLOEXEC), 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, err[1], 2);
    const std::string time_arg = "--time=" + time;
    const std::string socket_arg = "--socket=" + socket_;
    char* argv[] = {const_cast<char*>(CANEMUD_PATH), const_cast<char*>(time_arg.c_str()),
                    const_cast<char*>(socket_arg.c_str()), nullptr};
    EXPECT_EQ(::posix_spawn(&pid_, CANEMUD_PATH, &actions, nullptr, argv, environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    ::close(err[1]);
    stderr_ = err[0];
    // Ready when it says it listens (stderr), within 10 s.
    std::string log;
    char buf[512];
    while (log.find("listening on") == std::string::npos && readable(stderr_, 10'000)) {
      const ssize_t n = ::read(stderr_, buf, sizeof buf);
      if (n <= 0) {
        break;
      }
      log.append(buf, static_cast<std::size_t>(n));
    }
    EXPECT_NE(log.find("listening on " + socket_), std::string::npos) << log;
  }
  ~Daemon() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::close(stderr_);
    ::unlink(socket_.c_str());
    ::rmdir(dir_.c_str());
  }
  // SIGTERM, then the exit status within `timeout_ms` (-1 if it did not exit).
  int terminate(int timeout_ms) {
    const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, pid_, 0));
    ::kill(pid_, SIGTERM);
    int status = -1;
    if (pidfd >= 0 && readable(pidfd, timeout_ms)) {
      ::waitpid(pid_, &status, 0);
      pid_ = -1;
    }
    if (pidfd >= 0) {
      ::close(pidfd);
    }
    return status;
  }
  const std::string& socket() const { return socket_; }

 private:
  std::string dir_;
  std::string socket_;
  pid_t pid_ = -1;
  int stderr_ = -1;
};

inline client::Connection connect(const Daemon& d, const char* name = "test") {
  auto c = client::Connection::open(d.socket(), name);
  EXPECT_TRUE(c) << c.error().message;
  return std::move(*c);
}

inline ipc::StatusReply status(client::Connection& c) {
  auto r = c.call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  EXPECT_TRUE(r) << r.error().message;
  return r ? *r : ipc::StatusReply{};
}

}  // namespace canemu::testing
