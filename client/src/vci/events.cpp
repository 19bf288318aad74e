#include "events.hpp"

#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "canemu_events.h"

namespace canemu::client::vci {

namespace {

void drain(int fd) {
  uint64_t count = 0;
  while (::read(fd, &count, sizeof count) == static_cast<ssize_t>(sizeof count)) {
  }
}

// One thread for the process: polls the ring events of every FIFO with an assigned event.
class Pump {
 public:
  static Pump& get() {
    static Pump* p = new Pump;  // never destroyed: the thread runs until the process ends
    return *p;
  }
  void watch(const void* key, const ipc::RingEvent& ring, void* event) {
    std::lock_guard lock(mutex_);
    ring.flag->store(0);  // what was signalled before the event was assigned is not its
    ring.arm();  // the other side's next signal writes the eventfd (the pump arms it again)
    watches_[key] = Watch{&ring, event};
    if (ring.flag->exchange(0) != 0) {  // signalled while it was being armed
      if (EventObj* e = event_of(event)) {
        e->set();
      }
    }
    wake();
  }
  void unwatch(const void* key) {
    std::lock_guard lock(mutex_);
    watches_.erase(key);
    wake();
  }

 private:
  struct Watch {
    const ipc::RingEvent* ring;
    void* event;
  };
  Pump() : wake_fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
    std::thread([this] { run(); }).detach();
  }
  void wake() const {
    const uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof one);
  }
  void run() {
    std::vector<pollfd> fds;
    std::vector<const void*> keys;
    while (true) {
      fds.assign(1, pollfd{wake_fd_, POLLIN, 0});
      keys.assign(1, nullptr);
      {
        std::lock_guard lock(mutex_);
        for (const auto& [key, w] : watches_) {
          fds.push_back(pollfd{w.ring->eventfd, POLLIN, 0});
          keys.push_back(key);
        }
      }
      if (::poll(fds.data(), fds.size(), -1) <= 0) {
        continue;
      }
      drain(wake_fd_);
      std::lock_guard lock(mutex_);
      for (std::size_t i = 1; i < fds.size(); ++i) {
        if ((fds[i].revents & POLLIN) == 0) {
          continue;
        }
        auto it = watches_.find(keys[i]);
        if (it == watches_.end()) {
          continue;  // unwatched meanwhile
        }
        drain(it->second.ring->eventfd);
        // A signal writes the eventfd once per arming: armed again before the flag is taken,
        // so a signal after this look wakes the pump and one before it is in the flag.
        it->second.ring->arm();
        if (it->second.ring->flag->exchange(0) != 0) {
          if (EventObj* e = event_of(it->second.event)) {
            e->set();
          }
        }
      }
    }
  }
  std::mutex mutex_;
  std::map<const void*, Watch> watches_;
  int wake_fd_;
};

}  // namespace

void watch_ring_event(const void* key, const ipc::RingEvent& ring_event, void* event) {
  if (event == nullptr) {
    unwatch_ring_event(key);
  } else {
    Pump::get().watch(key, ring_event, event);
  }
}

void unwatch_ring_event(const void* key) {
  Pump::get().unwatch(key);
}

}  // namespace canemu::client::vci

using namespace canemu::client::vci;

extern "C" {

HANDLE VCIAPI CreateEvent(PVOID, BOOL bManualReset, BOOL bInitialState, const char*) {
  return create_event(bManualReset != 0, bInitialState != 0);
}

BOOL VCIAPI SetEvent(HANDLE hEvent) {
  EventObj* e = event_of(hEvent);
  if (e == nullptr) {
    return FALSE;
  }
  e->set();
  return TRUE;
}

BOOL VCIAPI ResetEvent(HANDLE hEvent) {
  EventObj* e = event_of(hEvent);
  if (e == nullptr) {
    return FALSE;
  }
  e->reset();
  return TRUE;
}

UINT32 VCIAPI WaitForMultipleObjects(UINT32 nCount, const HANDLE* pHandles, BOOL bWaitAll,
                                     UINT32 dwMilliseconds) {
  if (nCount == 0 || pHandles == nullptr) {
    return WAIT_FAILED;
  }
  std::vector<EventObj*> events;
  for (UINT32 i = 0; i < nCount; ++i) {
    EventObj* e = event_of(pHandles[i]);
    if (e == nullptr) {
      return WAIT_FAILED;
    }
    events.push_back(e);
  }
  const int i = wait_events(events, bWaitAll != 0, dwMilliseconds);
  return i < 0 ? WAIT_TIMEOUT : WAIT_OBJECT_0 + static_cast<UINT32>(i);
}

UINT32 VCIAPI WaitForSingleObject(HANDLE hEvent, UINT32 dwMilliseconds) {
  return WaitForMultipleObjects(1, &hEvent, FALSE, dwMilliseconds);
}

BOOL VCIAPI CloseHandle(HANDLE hObject) {
  return unregister_object(hObject, Object::Kind::event) ? TRUE : FALSE;
}

int VCIAPI canemuEventFd(HANDLE hEvent) {
  EventObj* e = event_of(hEvent);
  return e == nullptr ? -1 : e->fd;
}

}  // extern "C"
