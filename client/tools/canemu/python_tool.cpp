#include "python_tool.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>

namespace canemu::cli {

namespace {

constexpr std::string_view kSourceKey = "CMAKE_HOME_DIRECTORY:INTERNAL=";

// The repository's .venv/bin/python when this canemu runs from a build tree: the folder of the
// executable or one of its two parents holds a CMakeCache.txt whose source folder has a .venv
// (`make deps`). Empty for an installed canemu.
std::string build_tree_python() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) {
    return {};
  }
  fs::path dir = exe.parent_path();
  for (int up = 0; up < 3 && !dir.empty(); ++up, dir = dir.parent_path()) {
    std::ifstream cache(dir / "CMakeCache.txt");
    if (!cache) {
      continue;
    }
    for (std::string line; std::getline(cache, line);) {
      if (line.starts_with(kSourceKey)) {
        const fs::path python = fs::path(line.substr(kSourceKey.size())) / ".venv/bin/python";
        return ::access(python.c_str(), X_OK) == 0 ? python.string() : std::string();
      }
    }
    return {};
  }
  return {};
}

}  // namespace

std::string python_interpreter() {
  const char* env = std::getenv("CANEMU_PYTHON");
  if (env != nullptr && *env != '\0') {
    return env;
  }
  std::string venv = build_tree_python();
  return venv.empty() ? "python3" : venv;
}

PythonRun run_python_module(const std::string& module, const std::vector<std::string>& args,
                            const std::string& input, bool capture_output) {
  PythonRun run;
  run.interpreter = python_interpreter();
  std::vector<std::string> words{run.interpreter, "-m", module};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) {
    argv.push_back(w.data());
  }
  argv.push_back(nullptr);
  int in[2];
  int out[2] = {-1, -1};
  if (::pipe2(in, O_CLOEXEC) != 0 || (capture_output && ::pipe2(out, O_CLOEXEC) != 0)) {
    run.error = std::strerror(errno);
    return run;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
  if (capture_output) {
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  }
  pid_t pid = 0;
  const int spawned =
      ::posix_spawnp(&pid, run.interpreter.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(in[0]);
  if (capture_output) {
    ::close(out[1]);
  }
  if (spawned != 0) {
    ::close(in[1]);
    if (capture_output) {
      ::close(out[0]);
    }
    run.error = std::strerror(spawned);
    return run;
  }
  ::signal(SIGPIPE, SIG_IGN);  // a module that ends early is reported by its exit status
  for (std::size_t done = 0; done < input.size();) {
    const ssize_t n = ::write(in[1], input.data() + done, input.size() - done);
    if (n <= 0) {
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  ::close(in[1]);
  if (capture_output) {
    char buf[4096];
    ssize_t n;
    while ((n = ::read(out[0], buf, sizeof buf)) > 0) {
      run.output.append(buf, static_cast<std::size_t>(n));
    }
    ::close(out[0]);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

PythonFilter start_python_filter(const std::string& module, const std::vector<std::string>& args) {
  PythonFilter f;
  f.interpreter = python_interpreter();
  std::vector<std::string> words{f.interpreter, "-m", module};
  words.insert(words.end(), args.begin(), args.end());
  words.insert(words.end(), {"--ready-fd", "3"});
  std::vector<char*> argv;
  for (std::string& w : words) {
    argv.push_back(w.data());
  }
  argv.push_back(nullptr);
  int in[2];
  int ready[2];
  if (::pipe2(in, O_CLOEXEC) != 0) {
    f.error = std::strerror(errno);
    return f;
  }
  if (::pipe2(ready, O_CLOEXEC) != 0) {
    f.error = std::strerror(errno);
    ::close(in[0]);
    ::close(in[1]);
    return f;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, ready[1], 3);
  pid_t pid = 0;
  const int spawned =
      ::posix_spawnp(&pid, f.interpreter.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(in[0]);
  ::close(ready[1]);
  if (spawned != 0) {
    ::close(in[1]);
    ::close(ready[0]);
    f.error = std::strerror(spawned);
    return f;
  }
  char c = 0;
  ssize_t n;
  while ((n = ::read(ready[0], &c, 1)) < 0 && errno == EINTR) {
  }
  ::close(ready[0]);
  if (n != 1) {
    ::close(in[1]);
    int status = 0;
    ::waitpid(pid, &status, 0);
    f.status = WIFEXITED(status) && WEXITSTATUS(status) != 0 ? WEXITSTATUS(status) : -1;
    if (f.status == -1) {
      f.error = "it ended without reading the file";
    }
    return f;
  }
  std::fflush(stdout);
  ::dup2(in[1], STDOUT_FILENO);
  ::close(in[1]);
  f.pid = pid;
  f.status = 0;
  return f;
}

int finish_python_filter(const PythonFilter& filter) {
  std::fflush(stdout);
  ::close(STDOUT_FILENO);
  int status = 0;
  while (::waitpid(filter.pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

std::string exec_python_module(const std::string& module, const std::vector<std::string>& args) {
  const std::string interpreter = python_interpreter();
  std::vector<std::string> words{interpreter, "-m", module};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) {
    argv.push_back(w.data());
  }
  argv.push_back(nullptr);
  ::execvp(interpreter.c_str(), argv.data());
  return interpreter + ": " + std::strerror(errno);
}

}  // namespace canemu::cli
