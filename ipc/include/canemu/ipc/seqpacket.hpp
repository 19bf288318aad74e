// AF_UNIX SOCK_SEQPACKET sockets for the control protocol: listen, connect, one message per
// packet. Failing system calls are named in the error.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::ipc {

struct IpcError {
  int error_number = 0;  // errno, 0 when not from a system call
  std::string message;   // "connect /run/canemu/canemud.sock: No such file or directory"
};

template <class T>
using IpcResult = tl::expected<T, IpcError>;

// Where the daemon listens: `explicit_path`, else $CANEMU_SOCKET, else
// $RUNTIME_DIRECTORY/canemud.sock, else /run/canemu/canemud.sock.
std::string socket_path(const std::string& explicit_path = {});

// A listening socket at `path` (a stale socket file is replaced), non-blocking, close-on-exec.
IpcResult<UniqueFd> listen_seqpacket(const std::string& path, int backlog = 64);
// A connected socket (blocking), close-on-exec.
IpcResult<UniqueFd> connect_seqpacket(const std::string& path);

inline constexpr std::size_t kMaxPassedFds = 8;

// Sends one message, with `fds` (at most kMaxPassedFds) attached; the whole packet or an error.
IpcResult<void> send_packet(int fd, const void* data, std::size_t size,
                            std::span<const int> fds = {});
template <class T>
IpcResult<void> send_message(int fd, const T& message) {
  return send_packet(fd, &message, sizeof message);
}

// Receives one packet into `buffer` (resized to what came). An empty packet means the peer
// closed. `timeout_ms` < 0 waits forever; 0 does not wait (ETIMEDOUT when nothing is there).
// Descriptors that came with it go to `fds` (opened close-on-exec); without `fds` they are closed.
IpcResult<std::size_t> receive_packet(int fd, std::vector<uint8_t>& buffer, int timeout_ms = -1,
                                      std::vector<UniqueFd>* fds = nullptr);

}  // namespace canemu::ipc
