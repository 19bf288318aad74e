// canemu run as a process against a test's canemud, with its output through pipes; and a
// partner node that acknowledges.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "canemu/client/channel.hpp"
#include "daemon_process.hpp"

extern char** environ;

namespace canemu {

// canemu with `args` on the daemon's socket; stdout (and stderr) through pipes.
struct Cli {
  pid_t pid = -1;
  int out = -1;
  int err = -1;
  Cli(const testing::Daemon& d, std::vector<std::string> args) {
    args.insert(args.begin(), {"--socket", d.socket()});
    start(CANEMU_PATH, std::move(args));
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
  void start(const std::string& program, std::vector<std::string> args) {
    int o[2];
    int e[2];
    EXPECT_EQ(::pipe2(o, O_CLOEXEC), 0);
    EXPECT_EQ(::pipe2(e, O_CLOEXEC), 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, o[1], 1);
    posix_spawn_file_actions_adddup2(&actions, e[1], 2);
    args.insert(args.begin(), program);
    std::vector<char*> argv;
    for (std::string& a : args) {
      argv.push_back(a.data());
    }
    argv.push_back(nullptr);
    EXPECT_EQ(::posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
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
  int wait() {
    int status = 0;
    ::waitpid(pid, &status, 0);
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
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
