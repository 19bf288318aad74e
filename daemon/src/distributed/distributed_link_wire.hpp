// The same-host link's messages as both ends lay them out (docs/distributed.md, "Daemons on one
// host"): the head every message begins with, the user's hello, the limits, and what makes a
// message from another process safe to read. Private to distributed_link.cpp (connections) and
// distributed_link_io.cpp (messages).
#pragma once

#ifdef CANEMU_HAVE_DDS

#include <sys/epoll.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>

#include "distributed_impl.hpp"

namespace canemu::daemon::link_wire {

inline constexpr char kMagic[8] = {'c', 'a', 'n', 'e', 'm', 'u', 'L', '1'};
inline constexpr uint8_t kHello = 1;    // the user's first message: who it is, whom it wants
inline constexpr uint8_t kRequest = 2;  // one canemu_net_Request
inline constexpr uint8_t kEvents = 3;   // 1 to 64 canemu_net_Event, as an Events sample
inline constexpr uint8_t kBye = 4;      // the sender stops

// The user's first message, after its Head.
struct Hello {
  char magic[8];
  uint32_t request_size;  // the two daemons must lay the samples out alike
  uint32_t event_size;
  uint16_t protocol;  // canemu_net_PROTOCOL
  uint16_t reserved[3];
  char from[32];
  uint64_t from_boot;
  char to[32];
  uint64_t to_boot;
};

// Every message begins with this; `count` items of its type follow.
struct Head {
  uint8_t type;
  uint8_t reserved[3];
  uint32_t count;
  int64_t written;  // dds_time() as it was sent (CANEMU_NET_LEGS: the delivery leg)
  char to[32];      // kEvents: the sample's `to` ("": every follower)
  // kEvents: the sample's seq. kRequest: the sender's simulated instant it made the request at,
  // on CLOCK_MONOTONIC (ns; 0: not known, stepped time): the owner applies it there
  // (Distributed::take_rung_ns), as if both were one daemon.
  uint64_t seq;
};

inline constexpr std::size_t kMaxMessage =
    sizeof(Head) + kEventsPerSample * sizeof(canemu_net_Event);
inline constexpr std::size_t kBacklog = kWriterDepth;  // messages a link holds for a reader behind
inline constexpr std::ptrdiff_t kUnidentified = 16;  // connections at once that have not said hello
// An end of file, ECONNRESET or EPIPE: the other daemon ended (killed, it died), or it closed the
// link itself because this one did not read (kBacklog); which of them, its announcements tell.
inline constexpr const char* kClosedWithoutBye = "it closed without a bye";

// What came from another process is made safe to read: texts end within their arrays, and every
// bool is 0 or 1.
template <class T>
inline void fix_bools(T& s, std::initializer_list<std::size_t> offsets) {
  auto* bytes = reinterpret_cast<unsigned char*>(&s);
  for (const std::size_t off : offsets) {
    bytes[off] = bytes[off] != 0 ? 1 : 0;
  }
}

inline void sanitize(canemu_net_Request& r) {
  r.from[sizeof r.from - 1] = '\0';
  r.to[sizeof r.to - 1] = '\0';
  r.bus[sizeof r.bus - 1] = '\0';
  r.device[sizeof r.device - 1] = '\0';
  using R = canemu_net_Request;
  fix_bools(r, {offsetof(R, listen_only), offsetof(R, single_shot), offsetof(R, self_reception),
                offsetof(R, extended), offsetof(R, remote), offsetof(R, fd), offsetof(R, brs),
                offsetof(R, esi)});
}

inline void sanitize(canemu_net_Event& e) {
  e.text[sizeof e.text - 1] = '\0';
  e.asker[sizeof e.asker - 1] = '\0';
  using E = canemu_net_Event;
  fix_bools(e, {offsetof(E, own), offsetof(E, extended), offsetof(E, remote), offsetof(E, fd),
                offsetof(E, brs), offsetof(E, esi), offsetof(E, extended_frame),
                offsetof(E, in_frame), offsetof(E, data_phase)});
}

inline bool epoll_watch(int ep, int op, int fd, uint32_t events, void* ptr) {
  epoll_event ev{};
  ev.events = events;
  ev.data.ptr = ptr;
  return ::epoll_ctl(ep, op, fd, &ev) == 0;
}

}  // namespace canemu::daemon::link_wire

#endif  // CANEMU_HAVE_DDS
