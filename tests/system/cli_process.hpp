// canemu run as a process against a test's canemud, with its output through pipes; and a
// partner node that acknowledges.
#pragma once

#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "canemu/client/channel.hpp"
#include "daemon_process.hpp"

extern char** environ;

namespace canemu {

// Who a client process runs as (a test that runs as root starts clients as other users).
struct Credentials {
  uid_t uid = 0;
  gid_t gid = 0;
  std::vector<gid_t> groups;
};

// canemu with `args` on the daemon's socket (unless `args` start with another --socket); stdout
// (and stderr) through pipes. With `as`, it runs with those credentials (the test must run as
// root); with `cwd`, in that directory.
struct Cli {
  pid_t pid = -1;
  int out = -1;
  int err = -1;
  Cli(const testing::Daemon& d, std::vector<std::string> args, const Credentials* as = nullptr,
      const std::string& cwd = "") {
    if (args.empty() || args[0] != "--socket") {  // a test may name another socket
      args.insert(args.begin(), {"--socket", d.socket()});
    }
    start(CANEMU_PATH, std::move(args), as, cwd);
  }
  // `program` (canemu or canemud) with `args` alone, no daemon's socket.
  Cli(const std::string& program, std::vector<std::string> args) {
    start(program, std::move(args));
  }
  ~Cli() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
    ::close(out);
    ::close(err);
  }
  Cli(const Cli&) = delete;
  Cli& operator=(const Cli&) = delete;
  void start(const std::string& program, std::vector<std::string> args,
             const Credentials* as = nullptr, const std::string& cwd = "") {
    int o[2];
    int e[2];
    EXPECT_EQ(::pipe2(o, O_CLOEXEC), 0);
    EXPECT_EQ(::pipe2(e, O_CLOEXEC), 0);
    args.insert(args.begin(), program);
    std::vector<char*> argv;
    for (std::string& a : args) {
      argv.push_back(a.data());
    }
    argv.push_back(nullptr);
    if (as != nullptr) {
      pid = ::fork();
      if (pid == 0) {
        if (::dup2(o[1], 1) < 0 || ::dup2(e[1], 2) < 0 ||
            (!cwd.empty() && ::chdir(cwd.c_str()) != 0) ||
            ::setgroups(as->groups.size(), as->groups.data()) != 0 || ::setgid(as->gid) != 0 ||
            ::setuid(as->uid) != 0) {
          ::_exit(127);
        }
        ::execve(program.c_str(), argv.data(), environ);
        ::_exit(127);
      }
      EXPECT_GT(pid, 0);
    } else {
      posix_spawn_file_actions_t actions;
      posix_spawn_file_actions_init(&actions);
      posix_spawn_file_actions_adddup2(&actions, o[1], 1);
      posix_spawn_file_actions_adddup2(&actions, e[1], 2);
      if (!cwd.empty()) {
        posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
      }
      EXPECT_EQ(::posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ), 0);
      posix_spawn_file_actions_destroy(&actions);
    }
    ::close(o[1]);
    ::close(e[1]);
    out = o[0];
    err = e[0];
  }
  // Reads `fd` until it closes or `timeout_ms` passes without data.
  static std::string read_all(int fd, int timeout_ms = 10'000) {
    std::string text;
    char buf[512];
    while (testing::readable(fd, timeout_ms)) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n <= 0) {
        break;
      }
      text.append(buf, static_cast<std::size_t>(n));
    }
    return text;
  }
  // Reads `fd` until what came holds `text`, it closes, or `timeout_ms` passes without data.
  static std::string read_until(int fd, const std::string& text, int timeout_ms = 10'000) {
    std::string got;
    char buf[512];
    while (got.find(text) == std::string::npos && testing::readable(fd, timeout_ms)) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n <= 0) {
        break;
      }
      got.append(buf, static_cast<std::size_t>(n));
    }
    return got;
  }
  int wait() {
    int status = 0;
    ::waitpid(pid, &status, 0);
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  // The exit code once it ends within `timeout_ms`; -2 if it still runs then (-1: killed by a
  // signal).
  int wait_for(int timeout_ms) {
    const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
    const bool ended = pidfd >= 0 && testing::readable(pidfd, timeout_ms);
    if (pidfd >= 0) {
      ::close(pidfd);
    }
    return ended ? wait() : -2;
  }
};

// A node on `bus` that acknowledges (the dump only listens, and configured adapters stay off
// the bus until an application starts them).
inline client::Channel partner_on(client::Connection& c, const std::string& bus) {
  client::ChannelOptions o;
  o.bus = bus;
  auto ch = client::Channel::open(c, o);
  EXPECT_TRUE(ch) << ch.error().message;
  return std::move(*ch);
}

}  // namespace canemu
