// Daemons on one host (docs/distributed.md, "Daemons on one host"): a daemon that uses another's
// buses and hears it announce itself from this host reaches it over a Unix socket of its own
// instead of Cyclone DDS. The owner listens at an abstract address made of its name and boot;
// the user connects as it says hello, and from then on its requests and the owner's events for
// it go over that connection, in the order written, as DDS samples would. DDS still carries the
// announcements (who is there, and where), and everything for a daemon without a link.
#ifdef CANEMU_HAVE_DDS

#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/un.h>

#include <cerrno>
#include <cstddef>
#include <initializer_list>

#include "remote_node.hpp"

namespace canemu::daemon {

namespace {

constexpr char kMagic[8] = {'c', 'a', 'n', 'e', 'm', 'u', 'L', '1'};
constexpr uint8_t kHello = 1;    // the user's first message: who it is, whom it wants
constexpr uint8_t kRequest = 2;  // one canemu_net_Request
constexpr uint8_t kEvents = 3;   // 1 to 64 canemu_net_Event, as an Events sample
constexpr uint8_t kBye = 4;      // the sender stops

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

constexpr std::size_t kMaxMessage = sizeof(Head) + kEventsPerSample * sizeof(canemu_net_Event);
constexpr std::size_t kBacklog = kWriterDepth;  // messages a link holds for a reader behind
constexpr std::ptrdiff_t kUnidentified = 16;    // connections at once that have not said hello
// An end of file, ECONNRESET or EPIPE: the other daemon ended (killed, it died), or it closed the
// link itself because this one did not read (kBacklog); which of them, its announcements tell.
constexpr const char* kClosedWithoutBye = "it closed without a bye";

// What came from another process is made safe to read: texts end within their arrays, and every
// bool is 0 or 1.
template <class T>
void fix_bools(T& s, std::initializer_list<std::size_t> offsets) {
  auto* bytes = reinterpret_cast<unsigned char*>(&s);
  for (const std::size_t off : offsets) {
    bytes[off] = bytes[off] != 0 ? 1 : 0;
  }
}

void sanitize(canemu_net_Request& r) {
  r.from[sizeof r.from - 1] = '\0';
  r.to[sizeof r.to - 1] = '\0';
  r.bus[sizeof r.bus - 1] = '\0';
  r.device[sizeof r.device - 1] = '\0';
  using R = canemu_net_Request;
  fix_bools(r, {offsetof(R, listen_only), offsetof(R, single_shot), offsetof(R, self_reception),
                offsetof(R, extended), offsetof(R, remote), offsetof(R, fd), offsetof(R, brs),
                offsetof(R, esi)});
}

void sanitize(canemu_net_Event& e) {
  e.text[sizeof e.text - 1] = '\0';
  e.asker[sizeof e.asker - 1] = '\0';
  using E = canemu_net_Event;
  fix_bools(e, {offsetof(E, own), offsetof(E, extended), offsetof(E, remote), offsetof(E, fd),
                offsetof(E, brs), offsetof(E, esi), offsetof(E, extended_frame),
                offsetof(E, in_frame), offsetof(E, data_phase)});
}

sockaddr_un abstract_address(const std::string& name, socklen_t& len) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  // sun_path[0] = '\0': the abstract namespace (no file; gone with the socket).
  std::memcpy(a.sun_path + 1, name.data(), std::min(name.size(), sizeof a.sun_path - 2));
  len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 +
                               std::min(name.size(), sizeof a.sun_path - 2));
  return a;
}

// Whether the process at the other end of `fd` runs as this one's user (or as root): nobody else
// may speak for a daemon.
bool same_user(int fd, std::string& why) {
  ucred cred{};
  socklen_t len = sizeof cred;
  if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0) {
    why = fmt::format("its credentials: {}", std::strerror(errno));
    return false;
  }
  if (cred.uid != ::geteuid() && cred.uid != 0) {
    why = fmt::format("process {} runs as user {}, this daemon as {}", cred.pid, cred.uid,
                      ::geteuid());
    return false;
  }
  return true;
}

bool epoll_watch(int ep, int op, int fd, uint32_t events, void* ptr) {
  epoll_event ev{};
  ev.events = events;
  ev.data.ptr = ptr;
  return ::epoll_ctl(ep, op, fd, &ev) == 0;
}

// The epoll data of `wake` and of the listening socket (a link's is its LocalLink).
char kWakeTag;
char kListenTag;

}  // namespace

std::string Distributed::Impl::link_address(const std::string& name, uint64_t boot) {
  return fmt::format("canemu-net/{}/{:016x}", name, boot);
}

Result<> Distributed::Impl::open_links() {
  ep = ::epoll_create1(EPOLL_CLOEXEC);
  if (ep < 0 || !epoll_watch(ep, EPOLL_CTL_ADD, wake, EPOLLIN, &kWakeTag)) {
    return fail(Errc::io, fmt::format("epoll: {}", std::strerror(errno)));
  }
  if (!cfg.local_link) {
    return {};
  }
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  socklen_t len = 0;
  const sockaddr_un addr = abstract_address(link_address(cfg.name, boot), len);
  if (fd < 0 || ::bind(fd, reinterpret_cast<const sockaddr*>(&addr), len) != 0 ||
      ::listen(fd, 16) != 0 || !epoll_watch(ep, EPOLL_CTL_ADD, fd, EPOLLIN, &kListenTag)) {
    // Not fatal: every other daemon is reached over DDS, as without local_link.
    log::warning(
        "distributed: no same-host address ({}): other daemons on this host are "
        "reached over DDS",
        std::strerror(errno));
    if (fd >= 0) {
      ::close(fd);
    }
    return {};
  }
  link_listen = fd;
  return {};
}

void Distributed::Impl::serve() {
  epoll_event evs[32];
  const int n = ::epoll_wait(ep, evs, 32, 0);
  for (int i = 0; i < n; ++i) {
    void* tag = evs[i].data.ptr;
    if (tag == &kWakeTag) {
      receive();
    } else if (tag == &kListenTag) {
      link_accept();
    } else {
      auto* l = static_cast<LocalLink*>(tag);
      if (l->fd >= 0 && (evs[i].events & EPOLLOUT) != 0) {
        link_flush(*l);
      }
      if (l->fd >= 0 && (evs[i].events & (EPOLLIN | EPOLLHUP | EPOLLERR)) != 0) {
        link_read(*l);
      }
    }
  }
  flush_events();  // the answers to what came
  links_sweep();
}

void Distributed::Impl::link_accept() {
  for (int k = 0; k < 16; ++k) {
    const int fd = ::accept4(link_listen, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        // The connection stays queued: not looked at again before the next heartbeat
        // (links_resume), so that the loop does not spin on it. Logged once, not at every
        // heartbeat until there is room.
        if (!listen_starved) {
          log::warning(
              "distributed: a same-host connection not taken: {}; tried again at every "
              "heartbeat",
              std::strerror(errno));
          listen_starved = true;
        }
        listen_paused = ::epoll_ctl(ep, EPOLL_CTL_DEL, link_listen, nullptr) == 0;
      }
      return;  // EAGAIN: no more
    }
    if (listen_starved) {
      listen_starved = false;
      log::info("distributed: same-host connections are taken again");
    }
    std::string why;
    const auto unidentified = std::count_if(links.begin(), links.end(), [](const auto& l) {
      return l->fd >= 0 && !l->to_owner && !l->identified;
    });
    if (unidentified >= kUnidentified) {
      why = fmt::format("{} connections have not said hello yet", unidentified);
    }
    if (!why.empty() || !same_user(fd, why)) {
      drop(NetDrop::not_accepted, fmt::format("refused a same-host link: {}", why));
      ::close(fd);
      continue;
    }
    auto l = std::make_unique<LocalLink>();
    l->fd = fd;
    l->opened_ms = monotonic_ms();
    if (!epoll_watch(ep, EPOLL_CTL_ADD, fd, EPOLLIN, l.get())) {
      ::close(fd);
      continue;
    }
    links.push_back(std::move(l));
  }
}

void Distributed::Impl::try_link(const Peer& owner) {
  if (!cfg.local_link || owner.boot == 0 || link_to(owner.name) != nullptr) {
    return;
  }
  if (link_failed.count({owner.name, owner.boot}) != 0) {
    return;
  }
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  socklen_t len = 0;
  const sockaddr_un addr = abstract_address(link_address(owner.name, owner.boot), len);
  if (fd < 0 || ::connect(fd, reinterpret_cast<const sockaddr*>(&addr), len) != 0) {
    // Another host (or network namespace), an owner without the link: DDS, and no second try
    // with this boot. EAGAIN (its queue of connections full) is tried again at the next hello.
    if (errno != EAGAIN) {
      link_failed.insert({owner.name, owner.boot});
    }
    if (fd >= 0) {
      ::close(fd);
    }
    return;
  }
  std::string why;
  if (!same_user(fd, why)) {
    log::warning("distributed: daemon {}'s same-host address: {}; DDS it is", owner.name, why);
    link_failed.insert({owner.name, owner.boot});
    ::close(fd);
    return;
  }
  auto l = std::make_unique<LocalLink>();
  l->fd = fd;
  l->to_owner = true;
  l->identified = true;
  l->peer = owner.name;
  l->peer_boot = owner.boot;
  if (!epoll_watch(ep, EPOLL_CTL_ADD, fd, EPOLLIN, l.get())) {
    ::close(fd);
    return;
  }
  Hello h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.request_size = sizeof(canemu_net_Request);
  h.event_size = sizeof(canemu_net_Event);
  h.protocol = canemu_net_PROTOCOL;
  put(h.from, cfg.name);
  h.from_boot = boot;
  put(h.to, owner.name);
  h.to_boot = owner.boot;
  link_send(*l, kHello, "", 0, &h, 1, sizeof h);
  log::info("daemon {} is on this host: requests and events go over a same-host link", owner.name);
  links.push_back(std::move(l));
}

LocalLink* Distributed::Impl::find_link(const std::string& name, bool to_owner) const {
  auto p = peers.find(name);
  if (p == peers.end()) {
    return nullptr;
  }
  for (const auto& l : links) {
    // A link to an owner is identified from the start; one from a user once its hello came.
    if (l->fd >= 0 && l->to_owner == to_owner && l->identified && l->peer == name &&
        l->peer_boot == p->second.boot) {
      return l.get();
    }
  }
  return nullptr;
}

LocalLink* Distributed::Impl::link_to(const std::string& owner) {
  return find_link(owner, true);
}

LocalLink* Distributed::Impl::link_from(const std::string& user) {
  return find_link(user, false);
}

bool Distributed::Impl::linked(const std::string& name) const {
  auto p = peers.find(name);
  if (p == peers.end() || p->second.gone) {
    return false;
  }
  const LocalLink* to = find_link(name, true);
  return (to != nullptr && to->heard) || find_link(name, false) != nullptr;
}

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

bool Distributed::Impl::link_hello(LocalLink& l, const char* data, std::size_t size) {
  Hello h{};
  if (size != sizeof h) {
    link_close(l, fmt::format("a hello of {} bytes, not {}", size, sizeof h), true);
    return false;
  }
  std::memcpy(&h, data, sizeof h);
  h.from[sizeof h.from - 1] = '\0';
  h.to[sizeof h.to - 1] = '\0';
  const std::string from = get(h.from);
  std::string why;
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) {
    why = "no canemu daemon's hello";
  } else if (h.protocol != canemu_net_PROTOCOL || h.request_size != sizeof(canemu_net_Request) ||
             h.event_size != sizeof(canemu_net_Event)) {
    why = fmt::format(
        "protocol {} with requests of {} and events of {} bytes; this daemon: {}, {}, "
        "{}",
        h.protocol, h.request_size, h.event_size, canemu_net_PROTOCOL, sizeof(canemu_net_Request),
        sizeof(canemu_net_Event));
  } else if (!valid_name(from)) {
    why = fmt::format("from \"{}\", which is no daemon's name", printable(from));
  } else if (get(h.to) != cfg.name || h.to_boot != boot) {
    why = fmt::format("for daemon {} of another boot", printable(get(h.to)));
  }
  if (!why.empty()) {
    link_close(l, why, true);
    return false;
  }
  for (const auto& other : links) {
    if (other.get() != &l && other->fd >= 0 && !other->to_owner && other->peer == from) {
      link_close(*other, "replaced by a new link");
    }
  }
  l.identified = true;
  l.peer = from;
  l.peer_boot = h.from_boot;
  log::info("daemon {} is on this host: its requests and its events go over a same-host link",
            from);
  return true;
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

void Distributed::Impl::link_close(LocalLink& l, const std::string& why, bool malformed) {
  if (l.fd < 0) {
    return;
  }
  ::close(l.fd);  // also leaves `ep`
  l.fd = -1;
  l.backlog.clear();
  const std::string who = l.peer.empty() ? std::string("a daemon not identified yet") : l.peer;
  if (l.to_owner) {
    link_failed.insert({l.peer, l.peer_boot});  // this boot of the owner over DDS from now on
  }
  if (l.to_owner && !l.heard && !l.bye && !malformed) {
    // The owner closed it before answering anything: it refused the hello (its log says why).
    log::warning(
        "distributed: daemon {} closed the same-host link before answering ({}); it is "
        "spoken to over DDS",
        who, why);
    return;
  }
  if (l.bye) {
    l.gone_why = "it stopped";  // as its DDS announcement says, whichever comes first
    return;
  }
  if (malformed) {
    drop(NetDrop::malformed, fmt::format("same-host link with {} closed: {}", who, why));
  } else {
    log::warning("distributed: same-host link with {} closed: {}", who, why);
  }
  // Whatever went over the link may be lost with it: the other daemon is let go as one not
  // heard from (its nodes leave, and come back with its next hello or announcement).
  l.gone_why = fmt::format("its same-host link closed ({})", why);
}

void Distributed::Impl::links_bye() {
  stopping = true;
  for (const auto& l : links) {
    if (l->fd >= 0 && l->identified) {
      link_send(*l, kBye, "", 0, nullptr, 0, 0);
    }
  }
}

void Distributed::Impl::links_sweep() {
  // The other daemons of links closed since the last sweep are let go here, in the loop's own
  // turn: a link may close in the middle of a node's callback (a write that failed), where its
  // nodes must not go.
  for (std::size_t i = 0; i < links.size();) {
    LocalLink& l = *links[i];
    if (l.fd >= 0) {
      ++i;
      continue;
    }
    if (!stopping && l.identified && !l.gone_why.empty()) {
      auto p = peers.find(l.peer);
      if (p != peers.end() && p->second.boot == l.peer_boot && !p->second.gone) {
        peer_gone(p->second, l.gone_why);
      }
    }
    links.erase(links.begin() + static_cast<std::ptrdiff_t>(i));
  }
  const int64_t now = monotonic_ms();
  for (const auto& l : links) {
    if (l->fd >= 0 && !l->to_owner && !l->identified &&
        now - l->opened_ms > static_cast<int64_t>(cfg.timeout_ms)) {
      link_close(*l, fmt::format("no hello within {} ms", cfg.timeout_ms), true);
    }
  }
}

void Distributed::Impl::links_resume() {
  if (link_listen >= 0 && listen_paused) {
    listen_paused = !epoll_watch(ep, EPOLL_CTL_ADD, link_listen, EPOLLIN, &kListenTag);
  }
}

}  // namespace canemu::daemon

#endif  // CANEMU_HAVE_DDS
