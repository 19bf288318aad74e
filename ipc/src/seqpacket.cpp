#include "canemu/ipc/seqpacket.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <memory>

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

namespace canemu::ipc {

namespace {

// Where a packet lands before it goes to the caller's vector: room for the largest message,
// one per thread. Receiving into the vector itself would mean resizing it to that size first,
// which writes 16 KiB of zeros for every packet, however small.
uint8_t* landing() {
  thread_local const std::unique_ptr<uint8_t[]> room =
      std::make_unique_for_overwrite<uint8_t[]>(kMaxMessageSize);
  return room.get();
}

IpcError system_error(const std::string& what) {
  const int e = errno;
  return IpcError{e, what + ": " + std::strerror(e)};
}

tl::expected<sockaddr_un, IpcError> address(const std::string& path) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof a.sun_path) {
    return tl::unexpected(
        IpcError{ENAMETOOLONG, "socket path \"" + path + "\" is empty or longer than " +
                                   std::to_string(sizeof a.sun_path - 1) + " bytes"});
  }
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  return a;
}

}  // namespace

std::string socket_path(const std::string& explicit_path) {
  if (!explicit_path.empty()) {
    return explicit_path;
  }
  if (const char* s = std::getenv("CANEMU_SOCKET"); s != nullptr && *s != '\0') {
    return s;
  }
  if (const char* d = std::getenv("RUNTIME_DIRECTORY"); d != nullptr && *d != '\0') {
    // systemd may pass several directories separated by ':'; the first is ours.
    std::string dir(d);
    dir = dir.substr(0, dir.find(':'));
    return dir + "/canemud.sock";
  }
  return "/run/canemu/canemud.sock";
}

IpcResult<UniqueFd> listen_seqpacket(const std::string& path, int backlog) {
  auto a = address(path);
  if (!a) {
    return tl::unexpected(a.error());
  }
  UniqueFd fd(::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!fd.valid()) {
    return tl::unexpected(system_error("socket"));
  }
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) {
    // Replace a socket left by an earlier run, but never one a running daemon listens on.
    UniqueFd probe(::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0));
    if (probe.valid() &&
        ::connect(probe.get(), reinterpret_cast<const sockaddr*>(&*a), sizeof *a) == 0) {
      return tl::unexpected(IpcError{EADDRINUSE, "another canemud is listening on " + path});
    }
    ::unlink(path.c_str());
  }
  if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&*a), sizeof *a) != 0) {
    return tl::unexpected(system_error("bind " + path));
  }
  if (::listen(fd.get(), backlog) != 0) {
    return tl::unexpected(system_error("listen " + path));
  }
  return fd;
}

IpcResult<UniqueFd> connect_seqpacket(const std::string& path) {
  auto a = address(path);
  if (!a) {
    return tl::unexpected(a.error());
  }
  UniqueFd fd(::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0));
  if (!fd.valid()) {
    return tl::unexpected(system_error("socket"));
  }
  if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&*a), sizeof *a) != 0) {
    return tl::unexpected(system_error("connect " + path));
  }
  return fd;
}

IpcResult<void> send_packet(int fd, const void* data, std::size_t size, std::span<const int> fds) {
  if (fds.size() > kMaxPassedFds) {
    return tl::unexpected(IpcError{EINVAL, "send: too many descriptors"});
  }
  iovec iov{const_cast<void*>(data), size};
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int) * kMaxPassedFds)] = {};
  if (!fds.empty()) {
    msg.msg_control = control;
    msg.msg_controllen = CMSG_SPACE(sizeof(int) * fds.size());
    cmsghdr* c = CMSG_FIRSTHDR(&msg);
    c->cmsg_level = SOL_SOCKET;
    c->cmsg_type = SCM_RIGHTS;
    c->cmsg_len = CMSG_LEN(sizeof(int) * fds.size());
    std::memcpy(CMSG_DATA(c), fds.data(), sizeof(int) * fds.size());
  }
  while (true) {
    const ssize_t n = ::sendmsg(fd, &msg, MSG_NOSIGNAL);
    if (n == static_cast<ssize_t>(size)) {
      return {};
    }
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n < 0) {
      return tl::unexpected(system_error("send"));
    }
    return tl::unexpected(IpcError{EMSGSIZE, "send: short packet"});
  }
}

IpcResult<std::size_t> receive_packet(int fd, std::vector<uint8_t>& buffer, int timeout_ms,
                                      std::vector<UniqueFd>* fds) {
  buffer.clear();
  if (fds != nullptr) {
    fds->clear();
  }
  // Without a wait, recvmsg alone says whether a packet is there (no poll before it).
  const int no_wait = timeout_ms == 0 ? MSG_DONTWAIT : 0;
  if (timeout_ms > 0) {
    pollfd p{fd, POLLIN, 0};
    int r;
    do {
      r = ::poll(&p, 1, timeout_ms);
    } while (r < 0 && errno == EINTR);
    if (r < 0) {
      return tl::unexpected(system_error("poll"));
    }
    if (r == 0) {
      return tl::unexpected(
          IpcError{ETIMEDOUT, "no reply within " + std::to_string(timeout_ms) + " ms"});
    }
  }
  while (true) {
    uint8_t* const room = landing();
    iovec iov{room, kMaxMessageSize};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int) * kMaxPassedFds)];
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd, &msg, MSG_TRUNC | MSG_CMSG_CLOEXEC | no_wait);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n < 0 && no_wait != 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      return tl::unexpected(IpcError{ETIMEDOUT, "no reply within 0 ms"});
    }
    if (n < 0) {
      return tl::unexpected(system_error("recv"));
    }
    // Whatever descriptors came are owned here, kept only if asked for.
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS) {
        const std::size_t count = (c->cmsg_len - CMSG_LEN(0)) / sizeof(int);
        for (std::size_t k = 0; k < count; ++k) {
          int passed;
          std::memcpy(&passed, CMSG_DATA(c) + k * sizeof(int), sizeof passed);
          UniqueFd owned(passed);
          if (fds != nullptr) {
            fds->push_back(std::move(owned));
          }
        }
      }
    }
    if (static_cast<std::size_t>(n) > kMaxMessageSize) {
      return tl::unexpected(IpcError{
          EMSGSIZE, "recv: packet larger than " + std::to_string(kMaxMessageSize) + " bytes"});
    }
    buffer.assign(room, room + n);
    return static_cast<std::size_t>(n);
  }
}

}  // namespace canemu::ipc
