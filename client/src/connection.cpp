#include "canemu/client/connection.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include "canemu/ipc/clock.hpp"

namespace canemu::client {

namespace {

// "code: text" of an ErrorReply in `packet` (checked), nothing for another message.
std::optional<std::string> error_text(const uint8_t* packet, std::size_t size) {
  ipc::MsgHeader h;
  std::memcpy(&h, packet, sizeof h);
  if (h.type != static_cast<uint16_t>(ipc::MsgType::error_reply) ||
      size < sizeof(ipc::ErrorReply)) {
    return std::nullopt;
  }
  ipc::ErrorReply e;
  std::memcpy(&e, packet, sizeof e);
  return std::string(ipc::to_string(static_cast<ipc::ErrorCode>(e.code))) + ": " +
         ipc::name_of(e.message);
}

// What a path is when it is not a socket (stat's st_mode), with its article.
std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) {
    return "a directory";
  }
  if (S_ISREG(mode)) {
    return "a regular file";
  }
  if (S_ISFIFO(mode)) {
    return "a FIFO";
  }
  if (S_ISCHR(mode)) {
    return "a character device";
  }
  if (S_ISBLK(mode)) {
    return "a block device";
  }
  return "no socket";
}

bool is_socket(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode);
}

// Why connecting to `path` failed (not EACCES), as the user can act on it: a path that is no
// socket is named for what it is (a directory, with canemud's socket in it if there is one);
// otherwise canemud is not running there, and how to start it.
std::string not_reached(const std::string& path, const IpcError& e) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISSOCK(st.st_mode)) {
    const std::string inside = path + (path.ends_with('/') ? "" : "/") + "canemud.sock";
    if (S_ISDIR(st.st_mode) && is_socket(inside)) {
      return path + " is a directory, not canemud's socket: did you mean " + inside + "?";
    }
    return path + " is " + kind_of(st.st_mode) +
           ", not canemud's socket: give the socket's own path (what canemud --socket was "
           "given; under systemd /run/canemu/canemud.sock)";
  }
  const std::string start = ": start it with 'systemctl start canemud' or 'canemud --socket " +
                            path + "', or set CANEMU_SOCKET to the socket it listens on";
  if (e.error_number == ENOENT || e.error_number == ECONNREFUSED) {
    return "canemud is not running at " + path + start;  // no socket, or nobody behind it
  }
  if (e.error_number == EPROTOTYPE) {
    return path + " is a socket of another kind, not canemud's (a SOCK_SEQPACKET socket)";
  }
  if (e.error_number == ENAMETOOLONG) {
    return e.message;  // the path itself cannot be a socket's
  }
  return "canemud is not reachable at " + path + " (" + std::strerror(e.error_number) + ")";
}

}  // namespace

Result<Connection> Connection::open(const std::string& path, const std::string& client_name,
                                    int timeout_ms) {
  auto fd = ipc::connect_seqpacket(path);
  if (!fd) {
    IpcError e = fd.error();
    if (e.error_number == EACCES) {
      // canemud may well run: the socket's permissions keep this user out.
      e.message = "this user is not allowed to use canemud's socket " + path + " (" +
                  std::strerror(EACCES) +
                  "): it is not in the socket's group (canemu under systemd) or not among "
                  "the users and groups [security] allows (docs/security.md)";
    } else {
      e.message = not_reached(path, e);
    }
    return tl::unexpected(e);
  }
  Connection c(std::move(*fd), timeout_ms, path);
  if (const char* spin = std::getenv("CANEMU_REPLY_SPIN_US"); spin != nullptr && *spin != 0) {
    char* end = nullptr;
    const long us = std::strtol(spin, &end, 10);
    if (*end == 0 && us >= 0 && us <= 10'000) {
      c.reply_spin_ns_ = int64_t{us} * 1000;
    }
  }
  auto hello = ipc::make_message<ipc::Hello>();
  hello.client_pid = static_cast<uint32_t>(::getpid());
  ipc::copy_name(hello.client_name, client_name);
  auto reply = c.call<ipc::Hello, ipc::HelloReply>(hello);
  if (!reply) {
    if (c.lost_ && c.parting_) {
      // Refused and closed at once (canemud's client limit, or too many refused peers wait):
      // its answer came before the close.
      return tl::unexpected(
          IpcError{reply.error().error_number, "canemud refused the connection: " + *c.parting_});
    }
    return tl::unexpected(reply.error());
  }
  c.server_pid_ = reply->server_pid;
  return c;
}

Result<uint32_t> Connection::receive_one(int timeout_ms, std::vector<ipc::UniqueFd>* fds) {
  auto n = ipc::receive_packet(fd_.get(), buffer_, timeout_ms, fds);
  if (!n) {
    const int e = n.error().error_number;
    if (e == ETIMEDOUT || e == EMSGSIZE) {
      return tl::unexpected(n.error());  // nothing yet, or one oversized packet: still open
    }
    return tl::unexpected(broken());
  }
  if (*n == 0) {
    return tl::unexpected(broken());
  }
  const ipc::ErrorCode check = ipc::check_message(buffer_.data(), *n);
  if (check != ipc::ErrorCode::none) {
    return tl::unexpected(
        IpcError{0, "malformed reply from canemud (" + std::string(ipc::to_string(check)) + ")"});
  }
  ipc::MsgHeader h;
  std::memcpy(&h, buffer_.data(), sizeof h);
  if (h.type == static_cast<uint16_t>(ipc::MsgType::notification)) {
    ipc::Notification note;
    std::memcpy(&note, buffer_.data(), sizeof note);
    notifications_.push_back(note);
  } else if (h.request_id == 0) {
    if (auto text = error_text(buffer_.data(), *n)) {
      parting_ = std::move(text);  // why canemud closes the connection next
    }
  }
  return h.request_id;
}

IpcError Connection::broken() {
  if (lost_) {
    return *lost_;
  }
  // A refusal or a revocation is an ErrorReply just before the close. A connection closed with
  // a request of ours unread reports ECONNRESET once, before what is queued.
  std::vector<uint8_t> packet;
  for (int resets = 0; !parting_;) {
    auto n = ipc::receive_packet(fd_.get(), packet, 0);
    if (!n && n.error().error_number == ECONNRESET && ++resets < 2) {
      continue;
    }
    if (!n || *n == 0) {
      break;
    }
    if (ipc::check_message(packet.data(), *n) == ipc::ErrorCode::none) {
      parting_ = error_text(packet.data(), *n);
    }
  }
  lost_ = parting_
              ? IpcError{ECONNRESET, "canemud closed the connection: " + *parting_}
              : IpcError{ECONNRESET, "canemud went away: the connection to " + path_ + " closed"};
  return *lost_;
}

std::optional<IpcError> Connection::lost() {
  // Everything that came; a closed connection ends it (a receive that fails other than by
  // finding nothing calls broken()).
  while (!lost_ && receive_one(0, nullptr)) {
  }
  return lost_;
}

Result<void> Connection::receive(uint32_t request_id, int timeout_ms) {
  // A reply usually comes within microseconds: looking for it for a while (yielding the
  // processor between looks) spares the wake-up of a process that went to sleep, about half
  // of a short request's time on a VM. Then it blocks.
  if (timeout_ms != 0 && reply_spin_ns_ > 0) {
    const int64_t until = ipc::monotonic_ns() + reply_spin_ns_;
    do {
      auto id = receive_one(0, &fds_);
      if (id && *id == request_id) {
        return {};
      }
      if (!id && id.error().error_number != ETIMEDOUT) {
        return tl::unexpected(id.error());
      }
      if (!id) {
        ::sched_yield();
      }
    } while (ipc::monotonic_ns() < until);
  }
  while (true) {
    auto id = receive_one(timeout_ms, &fds_);
    if (!id) {
      return tl::unexpected(id.error());
    }
    if (*id == request_id) {
      return {};
    }
  }
}

Result<void> Connection::subscribe(uint32_t events) {
  auto m = ipc::make_message<ipc::SubscribeRequest>();
  m.events = events;
  auto r = call<ipc::SubscribeRequest, ipc::SubscribeReply>(m);
  if (!r) {
    return tl::unexpected(r.error());
  }
  return {};
}

std::optional<ipc::Notification> Connection::next_notification(int timeout_ms) {
  while (notifications_.empty()) {
    auto id = receive_one(timeout_ms, &fds_);
    if (!id) {
      return std::nullopt;  // nothing within the time (or the connection broke)
    }
  }
  ipc::Notification n = notifications_.front();
  notifications_.pop_front();
  return n;
}

IpcError Connection::error_from_reply() const {
  ipc::ErrorReply e;
  std::memcpy(&e, buffer_.data(), sizeof e);
  return IpcError{
      0, "canemud: " + std::string(ipc::to_string(static_cast<ipc::ErrorCode>(e.code))) + ": " +
             ipc::name_of(e.message)};
}

}  // namespace canemu::client
