// The event objects every VCI library hands out (events.hpp): an eventfd per event, a
// non-zero counter meaning signalled.
#include <algorithm>
#include <memory>

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "canemu/ipc/clock.hpp"
#include "events.hpp"

namespace canemu::client::vci {

namespace {

void drain(int fd) {
  uint64_t count = 0;
  while (::read(fd, &count, sizeof count) == static_cast<ssize_t>(sizeof count)) {
  }
}

}  // namespace

EventObj::~EventObj() {
  ::close(fd);
}

void EventObj::set() const {
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(fd, &one, sizeof one);
}

void EventObj::reset() const {
  drain(fd);
}

void* create_event(bool manual_reset, bool initial) {
  const int fd = ::eventfd(initial ? 1 : 0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (fd < 0) {
    return nullptr;
  }
  return register_object(std::make_unique<EventObj>(fd, manual_reset));
}

EventObj* event_of(void* handle) {
  return static_cast<EventObj*>(lookup(handle, Object::Kind::event));
}

int wait_events(const std::vector<EventObj*>& events, bool all, uint32_t timeout_ms) {
  const int64_t deadline =
      timeout_ms == 0xFFFFFFFFU ? -1 : ipc::monotonic_ns() / 1'000'000 + timeout_ms;
  auto left = [deadline] {
    return deadline < 0
               ? -1
               : static_cast<int>(std::max<int64_t>(0, deadline - ipc::monotonic_ns() / 1'000'000));
  };
  // An auto-reset event is taken by the wait that sees it; false if another waiter was faster.
  auto take = [](const EventObj* e) {
    uint64_t count = 0;
    return e->manual || ::read(e->fd, &count, sizeof count) == static_cast<ssize_t>(sizeof count);
  };
  if (all) {
    for (const EventObj* e : events) {
      pollfd p{e->fd, POLLIN, 0};
      while (::poll(&p, 1, left()) <= 0) {
        if (left() == 0) {
          return -1;
        }
      }
    }
    for (const EventObj* e : events) {
      take(e);
    }
    return 0;
  }
  std::vector<pollfd> fds(events.size());
  while (true) {
    for (std::size_t i = 0; i < events.size(); ++i) {
      fds[i] = pollfd{events[i]->fd, POLLIN, 0};
    }
    const int wait = left();
    if (::poll(fds.data(), fds.size(), wait) > 0) {
      for (std::size_t i = 0; i < events.size(); ++i) {
        if ((fds[i].revents & POLLIN) != 0 && take(events[i])) {
          return static_cast<int>(i);
        }
      }
    }
    if (wait == 0) {
      return -1;
    }
  }
}

}  // namespace canemu::client::vci
