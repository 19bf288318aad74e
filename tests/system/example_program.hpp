// A program of client/examples run as a user runs it against a test's canemud: CANEMU_SOCKET
// names the daemon's socket (its whole environment), its standard output comes through a pipe,
// and the test moves stepped time while it runs.
#pragma once

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "canemu_vci.h"

namespace canemu::testing {

struct ExampleProgram {
  pid_t pid = -1;
  int out = -1;
  int status = -1;
  ExampleProgram() = default;
  // Starts it: `args` are the program's path, then its arguments (ASSERT_NO_FATAL_FAILURE
  // around the call stops the test when it cannot start).
  void start(std::vector<std::string> args, const std::string& socket) {
    int pipe[2];
    ASSERT_EQ(::pipe(pipe), 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipe[1], 1);
    posix_spawn_file_actions_addclose(&actions, pipe[0]);
    std::vector<char*> argv;
    for (std::string& a : args) {
      argv.push_back(a.data());
    }
    argv.push_back(nullptr);
    std::vector<std::string> env_text = {"CANEMU_SOCKET=" + socket};
    std::vector<char*> env = {env_text[0].data(), nullptr};
    const int spawned =
        ::posix_spawn(&pid, args[0].c_str(), &actions, nullptr, argv.data(), env.data());
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe[1]);
    out = pipe[0];
    ASSERT_EQ(spawned, 0);
  }
  ~ExampleProgram() {
    if (out >= 0) {
      ::close(out);
    }
  }
  ExampleProgram(const ExampleProgram&) = delete;
  ExampleProgram& operator=(const ExampleProgram&) = delete;

  // Steps simulated time 1 ms at a time, calling `each_step` after each, until the program
  // ends (for at most 30 s of wall time); `status` is then its wait status.
  template <class EachStep>
  void step_until_exit(EachStep each_step) {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (::waitpid(pid, &status, WNOHANG) == 0 && std::chrono::steady_clock::now() < give_up) {
      UINT64 now = 0;
      ASSERT_EQ(canemuStepTime(1'000'000, &now), VCI_OK);
      each_step();
    }
  }
  void step_until_exit() {
    step_until_exit([] {});
  }
  // What it wrote, to the end.
  std::string output() const {
    std::string text;
    char buffer[512];
    ssize_t n = 0;
    while ((n = ::read(out, buffer, sizeof buffer)) > 0) {
      text.append(buffer, static_cast<std::size_t>(n));
    }
    return text;
  }
};

}  // namespace canemu::testing
