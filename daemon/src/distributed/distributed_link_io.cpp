// The same-host link's messages (docs/distributed.md, "Daemons on one host"): a request or the
// events for a daemon written straight from the caller's memory (queued only while the socket is
// full), what comes read and checked, and the instant a waiting request was made at, for the loop
// to apply it there. The connections themselves: distributed_link.cpp.
#ifdef CANEMU_HAVE_DDS

#include <sys/socket.h>
#include <sys/uio.h>

#include <cerrno>
#include <cstring>

#include "distributed_link_wire.hpp"
#include "remote_node.hpp"

namespace canemu::daemon {

using namespace link_wire;  // the link's own messages

void Distributed::Impl::link_send(LocalLink& l, uint8_t type, const std::string& to, uint64_t seq,
                                  const void* items, uint32_t count, std::size_t item_size) {
  if (l.fd < 0) {
    return;
  }
  Head h{};
  h.type = type;
  h.count = count;
  h.written = legs.on() ? dds_time() : 0;
  put(h.to, to);
  h.seq = seq;
  const std::size_t body = count * item_size;
  if (l.backlog.empty()) {
    // Nothing waits (nearly always): written straight from the caller's memory.
    iovec iov[2] = {{&h, sizeof h}, {const_cast<void*>(items), body}};
    msghdr msg{};
    msg.msg_iov = iov;
    msg.msg_iovlen = body > 0 ? 2 : 1;
    if (::sendmsg(l.fd, &msg, MSG_DONTWAIT | MSG_NOSIGNAL) >= 0) {
      return;
    }
    if (errno != EAGAIN && errno != EWOULDBLOCK) {
      link_write_failed(l);
      return;
    }
  }
  std::vector<char> m(sizeof h + body);
  std::memcpy(m.data(), &h, sizeof h);
  if (body > 0) {
    std::memcpy(m.data() + sizeof h, items, body);
  }
  if (l.backlog.size() >= kBacklog) {
    link_close(l, fmt::format("daemon {} did not read {} messages", l.peer, kBacklog));
    return;
  }
  l.backlog.push_back(std::move(m));
  if (l.backlog.size() == 1) {
    link_flush(l);  // the socket was full a moment ago: most likely it waits for room now
  }
}

void Distributed::Impl::link_write_failed(LocalLink& l) {
  link_close(l, errno == EPIPE || errno == ECONNRESET
                    ? std::string(kClosedWithoutBye)
                    : fmt::format("writing to it: {}", std::strerror(errno)));
}

void Distributed::Impl::link_request(LocalLink& l, const canemu_net_Request& r) {
  const int64_t made = loop != nullptr ? loop->monotonic_at(sim.scheduler().now()) : 0;
  link_send(l, kRequest, "", static_cast<uint64_t>(std::max<int64_t>(made, 0)), &r, 1, sizeof r);
}

int64_t Distributed::Impl::links_rung_ns() {
  int64_t earliest = 0;
  for (const auto& l : links) {
    if (l->fd < 0 || l->to_owner || !l->identified) {
      continue;
    }
    Head h{};
    const ssize_t n = ::recv(l->fd, &h, sizeof h, MSG_PEEK | MSG_DONTWAIT);
    if (n != static_cast<ssize_t>(sizeof h) || h.type != kRequest) {
      continue;
    }
    const auto at = static_cast<int64_t>(h.seq);
    if (at > 0 && (earliest == 0 || at < earliest)) {
      earliest = at;
    }
  }
  return earliest;
}

void Distributed::Impl::link_read_requests(LocalLink& l) {
  static thread_local std::vector<char> buf(kMaxMessage + 1);
  for (uint32_t k = 0; k < kMaxTakesPerKick && l.fd >= 0; ++k) {
    Head h{};
    const ssize_t peeked = ::recv(l.fd, &h, sizeof h, MSG_PEEK | MSG_DONTWAIT);
    if (peeked != static_cast<ssize_t>(sizeof h) || h.type != kRequest) {
      return;  // nothing, or not a request: link_read() at "now"
    }
    const ssize_t n = ::recv(l.fd, buf.data(), buf.size(), MSG_DONTWAIT | MSG_TRUNC);
    if (n <= 0) {
      return;  // link_read() at "now" says what happened
    }
    if (static_cast<std::size_t>(n) > kMaxMessage) {
      link_close(l, fmt::format("a message of {} bytes, more than any ({})", n, kMaxMessage), true);
      return;
    }
    link_message(l, buf.data(), static_cast<std::size_t>(n));
  }
}

void Distributed::Impl::link_events(LocalLink& l, const std::string& to, uint64_t seq,
                                    const std::vector<canemu_net_Event>& events) {
  link_send(l, kEvents, to, seq, events.data(), static_cast<uint32_t>(events.size()),
            sizeof(canemu_net_Event));
}

void Distributed::Impl::link_flush(LocalLink& l) {
  while (!l.backlog.empty() && l.fd >= 0) {
    const std::vector<char>& m = l.backlog.front();
    const ssize_t n = ::send(l.fd, m.data(), m.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      // Written when the socket has room again (EPOLLOUT).
      if (!l.waits_out) {
        l.waits_out = epoll_watch(ep, EPOLL_CTL_MOD, l.fd, EPOLLIN | EPOLLOUT, &l);
      }
      return;
    }
    if (n < 0) {
      link_write_failed(l);
      return;
    }
    l.backlog.pop_front();
  }
  if (l.fd >= 0 && l.waits_out) {
    l.waits_out = !epoll_watch(ep, EPOLL_CTL_MOD, l.fd, EPOLLIN, &l);
  }
}

void Distributed::Impl::link_read(LocalLink& l) {
  static thread_local std::vector<char> buf(kMaxMessage + 1);
  for (uint32_t k = 0; k < kMaxTakesPerKick && l.fd >= 0; ++k) {
    const ssize_t n = ::recv(l.fd, buf.data(), buf.size(), MSG_DONTWAIT | MSG_TRUNC);
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK) {
        // A daemon that ends with messages of ours unread leaves ECONNRESET, not an end of file.
        link_close(l, errno == ECONNRESET
                          ? std::string(kClosedWithoutBye)
                          : fmt::format("reading from it: {}", std::strerror(errno)));
      }
      return;
    }
    if (n == 0) {
      link_close(l, kClosedWithoutBye);
      return;
    }
    if (static_cast<std::size_t>(n) > kMaxMessage) {
      link_close(l, fmt::format("a message of {} bytes, more than any ({})", n, kMaxMessage), true);
      return;
    }
    link_message(l, buf.data(), static_cast<std::size_t>(n));
  }
}

void Distributed::Impl::link_message(LocalLink& l, const char* data, std::size_t size) {
  Head h{};
  if (size < sizeof h) {
    link_close(l, fmt::format("a message of {} bytes", size), true);
    return;
  }
  std::memcpy(&h, data, sizeof h);
  data += sizeof h;
  size -= sizeof h;
  l.heard = true;
  if (!l.identified) {
    if (h.type == kHello && h.count == 1) {
      link_hello(l, data, size);
    } else {
      link_close(l, "no hello first", true);
    }
    return;
  }
  if (legs.on() && h.written != 0 && (h.type == kRequest || h.type == kEvents)) {
    legs.add(h.type == kEvents ? Leg::event_delivery : Leg::request_delivery,
             dds_time() - h.written);
  }
  switch (h.type) {
    case kRequest: {
      canemu_net_Request r{};
      if (l.to_owner || h.count != 1 || size != sizeof r) {
        link_close(l, "a request that is none", true);
        return;
      }
      std::memcpy(&r, data, sizeof r);
      sanitize(r);
      // Who sent it is the link's, whatever the sample says.
      put(r.from, l.peer);
      r.from_boot = l.peer_boot;
      on_request(r);
      return;
    }
    case kEvents: {
      if (!l.to_owner || h.count == 0 || h.count > kEventsPerSample ||
          size != h.count * sizeof(canemu_net_Event)) {
        link_close(l, "events that are none", true);
        return;
      }
      std::vector<canemu_net_Event> list(h.count);
      std::memcpy(list.data(), data, size);
      for (canemu_net_Event& e : list) {
        sanitize(e);
      }
      canemu_net_Events b{};
      put(b.from, l.peer);
      b.from_boot = l.peer_boot;
      h.to[sizeof h.to - 1] = '\0';
      put(b.to, get(h.to));
      b.seq = h.seq;
      b.list._buffer = list.data();
      b.list._length = h.count;
      b.list._maximum = h.count;
      b.list._release = false;
      on_events(b);
      return;
    }
    case kBye:
      l.bye = true;
      return;
    default:
      link_close(l, fmt::format("a message of unknown type {}", h.type), true);
      return;
  }
}

}  // namespace canemu::daemon

#endif  // CANEMU_HAVE_DDS
