#include "canemu/ipc/unique_fd.hpp"

#include <unistd.h>

namespace canemu::ipc {

void UniqueFd::reset(int fd) {
  if (fd_ >= 0) {
    ::close(fd_);
  }
  fd_ = fd;
}

}  // namespace canemu::ipc
