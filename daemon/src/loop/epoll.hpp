// The loop's one way to watch a descriptor: readable, level-triggered, its fd as the key.
#pragma once

#include <sys/epoll.h>

namespace canemu::daemon {

inline bool epoll_add(int epoll, int fd) {
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.fd = fd;
  return ::epoll_ctl(epoll, EPOLL_CTL_ADD, fd, &ev) == 0;
}

}  // namespace canemu::daemon
