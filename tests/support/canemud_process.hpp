// canemud as a child process on a private socket in a fresh temporary directory, for system
// tests and benchmarks. Ready once it says it listens; killed when the object goes.
#pragma once

#include <csignal>
#include <string>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

namespace canemu::testing {

// Waits until `fd` is readable or `timeout_ms` passes.
inline bool readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) == 1;
}

class CanemudProcess {
 public:
  // Starts `canemud` with `args` and --socket in its own directory; waits up to 10 s until it
  // listens.
  CanemudProcess(const std::string& canemud, std::vector<std::string> args) {
    char dir[] = "/tmp/canemu-test-XXXXXX";
    dir_ = ::mkdtemp(dir);
    socket_ = dir_ + "/canemud.sock";
    int err[2];
    if (::pipe2(err, O_CLOEXEC) != 0) {
      return;
    }
    args.insert(args.begin(), canemud);
    args.push_back("--socket=" + socket_);
    std::vector<char*> argv;
    for (std::string& a : args) {
      argv.push_back(a.data());
    }
    argv.push_back(nullptr);
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ == 0) {
      // Dies with the test process, even when that one crashes, so that nothing keeps the test
      // runner's output pipe open.
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (::getppid() != parent) {
        ::_exit(127);
      }
      ::dup2(err[1], 2);
      ::execv(canemud.c_str(), argv.data());
      ::_exit(127);
    }
    ::close(err[1]);
    stderr_ = err[0];
    read_log_until("listening on " + socket_, 10'000);
    ready_ = log_.find("listening on " + socket_) != std::string::npos;
  }
  CanemudProcess(const CanemudProcess&) = delete;
  CanemudProcess& operator=(const CanemudProcess&) = delete;
  ~CanemudProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::close(stderr_);
    ::unlink(socket_.c_str());
    ::rmdir(dir_.c_str());
  }

  bool ready() const { return ready_; }
  // What it wrote to stderr so far.
  const std::string& log() const { return log_; }
  // Reads stderr until `text` shows up or `timeout_ms` passes without output.
  bool read_log_until(const std::string& text, int timeout_ms) {
    char buf[512];
    while (log_.find(text) == std::string::npos && readable(stderr_, timeout_ms)) {
      const ssize_t n = ::read(stderr_, buf, sizeof buf);
      if (n <= 0) {
        break;
      }
      log_.append(buf, static_cast<std::size_t>(n));
    }
    return log_.find(text) != std::string::npos;
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
  void signal(int sig) const { ::kill(pid_, sig); }
  pid_t pid() const { return pid_; }
  const std::string& socket() const { return socket_; }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::string socket_;
  pid_t pid_ = -1;
  int stderr_ = -1;
  std::string log_;
  bool ready_ = false;
};

}  // namespace canemu::testing
