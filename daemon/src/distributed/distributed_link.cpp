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

#include "distributed_link_wire.hpp"
#include "remote_node.hpp"

namespace canemu::daemon {

using namespace link_wire;  // the link's own messages

namespace {

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
