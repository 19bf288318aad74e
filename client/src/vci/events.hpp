// Event objects over eventfds: the Windows-style events of libvciapi (canemu_events.h) and
// the vciEvent* functions of the C libraries, one implementation; and the thread that turns a
// FIFO's ring event into the event a program assigned to it (IFifoReader/Writer::AssignEvent,
// libvciapi only).
#pragma once

#include <cstdint>
#include <vector>

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
  void reset() const;
};

// A new event's handle (signalled if `initial`; a manual-reset one stays signalled until
// reset, an auto-reset one is reset by the wait it ends); nullptr when no descriptor is left.
void* create_event(bool manual_reset, bool initial);
// The event behind `handle`, nullptr if it is not a live event.
EventObj* event_of(void* handle);

// Waits up to `timeout_ms` (0xFFFFFFFF: no limit) until one of `events` is signalled (`all`:
// until all are) and takes it (auto-reset events are reset). The index of the event that ended
// the wait (0 with `all`), or -1 when the time ran out.
int wait_events(const std::vector<EventObj*>& events, bool all, uint32_t timeout_ms);

// Signals `event` (a HANDLE from CreateEvent) whenever `ring_event` is signalled, until
// unwatched; `key` names the watch (the FIFO object). A null event only unwatches.
void watch_ring_event(const void* key, const ipc::RingEvent& ring_event, void* event);
void unwatch_ring_event(const void* key);

}  // namespace canemu::client::vci
