// A pipe between a test and a child process it forks, closed with it.
#pragma once

#include <unistd.h>

namespace canemu::testing {

// p[0] to read, p[1] to write; close(end) closes one end early (each process closes the end it
// does not use, and a writer that closes gives its reader end of file).
class Pipe {
 public:
  Pipe() {
    if (::pipe(fd_) != 0) {
      fd_[0] = fd_[1] = -1;
    }
  }
  ~Pipe() {
    close(0);
    close(1);
  }
  Pipe(const Pipe&) = delete;
  Pipe& operator=(const Pipe&) = delete;
  bool ok() const { return fd_[0] >= 0; }
  int operator[](int end) const { return fd_[end]; }
  void close(int end) {
    if (fd_[end] >= 0) {
      ::close(fd_[end]);
      fd_[end] = -1;
    }
  }

 private:
  int fd_[2] = {-1, -1};
};

}  // namespace canemu::testing
