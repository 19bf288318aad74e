// Windows-style events over eventfds (canemu_events.h), and the thread that turns a FIFO's
// ring event into the event a program assigned to it (IFifoReader/Writer::AssignEvent).
#pragma once

#include <cstdint>

#include "canemu/ipc/shm_ring.hpp"
#include "vci_core.hpp"

namespace canemu::client::vci {

struct EventObj : Object {
  EventObj(int event_fd, bool manual_reset)
      : Object(Kind::event), fd(event_fd), manual(manual_reset) {}
  ~EventObj() override;
  int fd;
  bool manual;
  void set() const;
};

// Signals `event` (a HANDLE from CreateEvent) whenever `ring_event` is signalled, until
// unwatched; `key` names the watch (the FIFO object). A null event only unwatches.
void watch_ring_event(const void* key, const ipc::RingEvent& ring_event, void* event);
void unwatch_ring_event(const void* key);

}  // namespace canemu::client::vci
