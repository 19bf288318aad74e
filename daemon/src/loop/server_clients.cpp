// canemud's clients: accepted, refused, counted, served one request at a time, dropped.
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <utility>

#include <poll.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/loop/server.hpp"
#include "canemu/ipc/clock.hpp"
#include "loop/epoll.hpp"

namespace canemu::daemon {

using ipc::monotonic_ns;

void Server::fill_clients(ipc::ClientListReply& r) {
  // The page from r.first on; total counts them all.
  r.total = 0;
  std::size_t n = 0;
  for (auto& [fd, c] : clients_) {
    if (c.closing || !c.refused.empty()) {
      continue;
    }
    if (r.total++ >= r.first && n < ipc::kClientPage) {
      ipc::ClientEntry& e = r.clients[n++];
      ipc::copy_name(e.name, c.session.name);
      e.pid = c.session.pid;
      e.uid = c.session.uid;
      // Channels of ephemeral devices and VCI channels alike.
      const auto vci_channels =
          std::count_if(c.session.vci.handles.begin(), c.session.vci.handles.end(),
                        [](const auto& h) { return h.second->kind() == VciHandle::Kind::channel; });
      e.channels =
          static_cast<uint32_t>(c.session.channels.size()) + static_cast<uint32_t>(vci_channels);
    }
  }
  r.count = static_cast<uint16_t>(n);
}

void Server::accept_clients() {
  while (true) {
    const int fd = ::accept4(listen_.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE) {
        // Out of descriptors: stop accepting until a client leaves, instead of spinning on a
        // listening socket that stays readable.
        ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, listen_.get(), nullptr);
        accepting_ = false;
        log::warning("out of file descriptors; not accepting for now");
      }
      return;  // EAGAIN: no more; other errors: the client is gone already
    }
    Client c;
    c.fd.reset(fd);
    c.accepted_ns = monotonic_ns();
    ucred cred{};
    socklen_t len = sizeof cred;
    if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0) {
      continue;  // unknown peer: refused (closed when c goes out of scope)
    }
    c.session.uid = cred.uid;
    c.session.gid = cred.gid;
    c.session.pid = static_cast<uint32_t>(cred.pid);
    c.session.vci.pid = c.session.pid;
    c.session.vci.uid = c.session.uid;
    c.session.admin = access_.admin(fd, c.session.uid, c.session.gid);
    // Slots: the connections being served (not refused, not on their way out).
    const auto served = [this] {
      return static_cast<std::size_t>(std::count_if(
          clients_.begin(), clients_.end(),
          [](const auto& e) { return e.second.refused.empty() && !e.second.closing; }));
    };
    const auto waiting = static_cast<std::size_t>(std::count_if(
        clients_.begin(), clients_.end(), [](const auto& e) { return !e.second.refused.empty(); }));
    const std::size_t limit = c.session.admin ? kMaxClients : kMaxClients - kAdminSlots;
    if (served() >= limit) {
      evict_silent(c.accepted_ns - kSilentEvictNs);  // frees a slot, if one was silent long
    }
    if (served() >= limit) {
      const std::string why =
          c.session.admin ? fmt::format("canemud serves at most {} clients", kMaxClients)
                          : fmt::format(
                                "canemud serves at most {} clients (the last {} of {} are kept for "
                                "administrators)",
                                limit, kAdminSlots, kMaxClients);
      reply_error(c, 0, ipc::ErrorCode::no_resources, why);
      log_refusal(fmt::format("refused uid {} (pid {}): {}", c.session.uid, c.session.pid, why));
      continue;
    }
    if (!access_.allowed(fd, c.session.uid, c.session.gid)) {
      c.refused =
          fmt::format("uid {} is not allowed by the [security] configuration", c.session.uid);
      log_refusal(fmt::format("refused uid {} (pid {}): not allowed by [security]", c.session.uid,
                              c.session.pid));
    } else if (const std::size_t held = connections_of(c.session.uid);
               c.session.uid != 0 && held >= sim_.config().security.max_clients_per_user) {
      c.refused = fmt::format(
          "uid {} has {} connections to canemud; [security] max_clients_per_user allows {}",
          c.session.uid, held, sim_.config().security.max_clients_per_user);
      c.refused_code = ipc::ErrorCode::no_resources;
      log_refusal(fmt::format("refused uid {} (pid {}): {} connections, the most one user may have",
                              c.session.uid, c.session.pid, held));
    }
    if (!c.refused.empty() && waiting >= kMaxRefusedWaiting) {
      reply_error(c, 0, c.refused_code, c.refused);
      continue;  // closed when c goes out of scope
    }
    if (!epoll_add(epoll_.get(), fd)) {
      continue;
    }
    c.serial = ++client_serials_;
    clients_.emplace(fd, std::move(c));
  }
}

void Server::log_refusal(const std::string& line) {
  const int64_t now = monotonic_ns();
  end_refusal_window(now);
  if (refusals_logged_ == 0 && refusals_unlogged_ == 0) {
    refusal_window_ns_ = now;
  }
  if (refusals_logged_ < kRefusalLines) {
    ++refusals_logged_;
    log::warning("{}", line);
  } else {
    ++refusals_unlogged_;
  }
}

void Server::end_refusal_window(int64_t now_ns) {
  if ((refusals_logged_ == 0 && refusals_unlogged_ == 0) ||
      now_ns - refusal_window_ns_ < kRefusalWindowNs) {
    return;
  }
  if (refusals_unlogged_ > 0) {
    log::warning("{} more connection{} refused in {} s (the first {} were logged)",
                 refusals_unlogged_, refusals_unlogged_ == 1 ? "" : "s",
                 kRefusalWindowNs / 1'000'000'000, kRefusalLines);
  }
  refusals_logged_ = 0;
  refusals_unlogged_ = 0;
}

bool Server::evict_silent(int64_t before_ns) {
  Client* oldest = nullptr;
  for (auto& [fd, c] : clients_) {
    if (!c.closing && !c.session.greeted && c.refused.empty() && c.accepted_ns < before_ns &&
        (oldest == nullptr || c.accepted_ns < oldest->accepted_ns)) {
      oldest = &c;
    }
  }
  if (oldest == nullptr) {
    return false;
  }
  reply_error(*oldest, 0, ipc::ErrorCode::no_resources,
              fmt::format("canemud is full and this connection had not said hello for {} s",
                          kSilentEvictNs / 1'000'000'000));
  log_refusal(
      fmt::format("closed a connection of uid {} (pid {}): no hello, and its slot was "
                  "wanted",
                  oldest->session.uid, oldest->session.pid));
  oldest->closing = true;
  return true;
}

int Server::housekeeping() {
  const int64_t now = monotonic_ns();
  end_refusal_window(now);
  int64_t next = refusals_unlogged_ > 0 ? refusal_window_ns_ + kRefusalWindowNs : INT64_MAX;
  for (auto& [fd, c] : clients_) {
    if (c.closing || c.session.greeted) {
      continue;
    }
    const int64_t deadline = c.accepted_ns + kHelloDeadlineNs;
    if (now < deadline) {
      next = std::min(next, deadline);
      continue;
    }
    // Silent since it connected: told why (a refused one its refusal) and closed.
    if (c.refused.empty()) {
      reply_error(
          c, 0, ipc::ErrorCode::not_hello,
          fmt::format("no hello within {} s of connecting", kHelloDeadlineNs / 1'000'000'000));
      log_refusal(fmt::format("closed a connection of uid {} (pid {}): no hello within {} s",
                              c.session.uid, c.session.pid, kHelloDeadlineNs / 1'000'000'000));
    } else {
      reply_error(c, 0, c.refused_code, c.refused);
    }
    c.closing = true;
  }
  drop_closing();
  if (next == INT64_MAX) {
    return -1;
  }
  return static_cast<int>(std::min<int64_t>((next - now) / 1'000'000 + 1, INT32_MAX));
}

// Connections of `uid` being served (refused and closing ones not counted).
std::size_t Server::connections_of(uint32_t uid) const {
  return static_cast<std::size_t>(
      std::count_if(clients_.begin(), clients_.end(), [&](const auto& e) {
        return e.second.session.uid == uid && e.second.refused.empty() && !e.second.closing;
      }));
}

// After a reload: a client the new [security] no longer allows is told why and dropped.
void Server::drop_revoked_clients() {
  for (auto& [fd, c] : clients_) {
    c.session.admin = access_.admin(fd, c.session.uid, c.session.gid);
    if (!c.closing && c.refused.empty() && !access_.allowed(fd, c.session.uid, c.session.gid)) {
      log::warning("reload: uid {} (pid {}, \"{}\") is no longer allowed; connection closed",
                   c.session.uid, c.session.pid, c.session.name);
      reply_error(c, 0, ipc::ErrorCode::permission_denied,
                  fmt::format("uid {} is no longer allowed by the [security] configuration",
                              c.session.uid));
      c.closing = true;  // dropped after this batch, with everything it opened
    }
  }
}

// Counts clients whose socket is still open; the ones that went away are dropped after the
// current batch of events (never while one of their requests is being answered).
uint16_t Server::live_clients() {
  uint16_t live = 0;
  for (auto& [fd, c] : clients_) {
    pollfd p{fd, POLLRDHUP, 0};
    if (::poll(&p, 1, 0) == 1 && (p.revents & (POLLRDHUP | POLLHUP | POLLERR))) {
      c.closing = true;
    } else if (c.refused.empty()) {
      ++live;
    }
  }
  return live;
}

void Server::drop_closing() {
  if (stepping()) {
    return;  // a client's channels and devices leave the world after the step
  }
  std::vector<int> gone;
  for (const auto& [fd, c] : clients_) {
    if (c.closing) {
      gone.push_back(fd);
    }
  }
  for (int fd : gone) {
    drop(fd);
  }
}

void Server::drop(int fd) {
  ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, fd, nullptr);
  auto it = clients_.find(fd);
  if (it == clients_.end()) {
    return;
  }
  // Its channels stop their nodes and their devices go (notified after this batch); what it
  // opened through the VCI is closed.
  dispatcher_.end_session(it->second.session);
  clients_.erase(it);
  if (!accepting_ && epoll_add(epoll_.get(), listen_.get())) {
    accepting_ = true;  // a descriptor is free again
  }
}

void Server::serve(int fd) {
  auto it = clients_.find(fd);
  if (it == clients_.end()) {
    return;
  }
  if (it->second.closing || !it->second.held.empty()) {
    return;  // a held request first (its later ones wait in the socket)
  }
  auto n = ipc::receive_packet(fd, buffer_, 0);
  if (!n && n.error().error_number == ETIMEDOUT) {
    return;  // nothing to read: a stale event for a descriptor number reused in this batch
  }
  if (!n || *n == 0) {
    it->second.closing = true;  // closed, oversized or broken: dropped after this batch
    return;
  }
  if (!it->second.refused.empty()) {
    ipc::MsgHeader h{};
    std::memcpy(&h, buffer_.data(), std::min(sizeof h, buffer_.size()));
    reply_error(it->second, h.request_id, it->second.refused_code, it->second.refused);
    it->second.closing = true;
    return;
  }
  if (stepping() && !reads_only(buffer_)) {
    it->second.held = buffer_;
    waits_for_steps_ = true;
    return;
  }
  handle(it->second, buffer_);
}

bool Server::reads_only(const std::vector<uint8_t>& packet) {
  ipc::MsgHeader h{};
  if (packet.size() < sizeof h) {
    return true;  // answered with an error at once
  }
  std::memcpy(&h, packet.data(), sizeof h);
  switch (static_cast<ipc::MsgType>(h.type)) {
    case ipc::MsgType::hello:
    case ipc::MsgType::status_request:
    case ipc::MsgType::channel_status_request:
    case ipc::MsgType::device_list_request:
    case ipc::MsgType::client_list_request:
    case ipc::MsgType::subscribe_request:
    case ipc::MsgType::fault_list_request:
    case ipc::MsgType::recorder_list_request:
    case ipc::MsgType::bridge_list_request:
    case ipc::MsgType::peer_list_request:
    case ipc::MsgType::timeline_request:
      return true;
    default:
      return false;
  }
}

void Server::reply_error(Client& c, uint32_t request_id, ipc::ErrorCode code,
                         const std::string& text) {
  auto e = ipc::make_message<ipc::ErrorReply>(request_id);
  e.code = static_cast<uint32_t>(code);
  ipc::copy_name(e.message, text);
  (void)ipc::send_message(c.fd.get(), e);
}

void Server::handle(Client& c, const std::vector<uint8_t>& packet) {
  current_ = &c;
  dispatcher_.handle(c.session, packet.data(), packet.size(),
                     [&c](const void* data, std::size_t size, std::span<const int> fds) {
                       // A client that does not read its replies is dropped, not waited for.
                       if (!ipc::send_packet(c.fd.get(), data, size, fds)) {
                         c.closing = true;
                       }
                     });
}

uint16_t Server::client_count() {
  return live_clients();
}

}  // namespace canemu::daemon
