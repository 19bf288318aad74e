// A connection to canemud: connect, handshake, requests with replies. The VCI, SORCUS and
// Python layers build on it; it knows the protocol (ipc/), never the model.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/seqpacket.hpp"

namespace canemu::client {

using ipc::IpcError;
template <class T>
using Result = ipc::IpcResult<T>;

class Connection {
 public:
  // Connects to the daemon at `path` (see ipc::socket_path) and says hello. Fails with a message
  // that names the socket and says how to start canemud when nobody listens, that `path` is a
  // directory or a file when it is no socket (naming canemud's socket in that directory if there
  // is one), that this user may not use the socket when its permissions refuse (EACCES), and with
  // canemud's reason when canemud refuses this client (also when it closed the connection at
  // once after saying why).
  static Result<Connection> open(const std::string& path, const std::string& client_name,
                                 int timeout_ms = 2000);

  // Sends `request` and waits for its reply of type Reply (or an ErrorReply, returned as an
  // error naming the code and the daemon's message). Once canemud closed the connection, every
  // call fails with lost()'s reason. The wait polls the socket for 200 us (yielding the
  // processor between looks; CANEMU_REPLY_SPIN_US sets it, 0..10000, 0: none) before it blocks.
  template <class Request, class Reply>
  Result<Reply> call(Request request) {
    return call<Request, Reply>(request, timeout_ms_);
  }
  // The same, waiting up to `timeout_ms` for the reply (-1: as long as canemud is there; a
  // time step takes as long as its events do).
  template <class Request, class Reply>
  Result<Reply> call(Request request, int timeout_ms) {
    if (lost_) {
      return tl::unexpected(*lost_);
    }
    request.header.request_id = ++next_id_;
    auto sent = ipc::send_message(fd_.get(), request);
    if (!sent) {
      return tl::unexpected(broken());
    }
    auto got = receive(request.header.request_id, timeout_ms);
    if (!got) {
      return tl::unexpected(got.error());
    }
    return expect<Reply>();
  }

  uint32_t server_pid() const { return server_pid_; }
  int fd() const { return fd_.get(); }
  // Descriptors that came with the last reply (an opened channel's rings and events).
  std::vector<ipc::UniqueFd> take_fds() { return std::move(fds_); }

  // Asks for notifications (ipc::kEvent*); they queue up as they come.
  Result<void> subscribe(uint32_t events);
  // The oldest notification, waiting up to `timeout_ms` (0: only what came already).
  std::optional<ipc::Notification> next_notification(int timeout_ms);

  // Whether canemud closed this connection, without waiting: nothing while it is open; once it
  // is closed, why: what canemud said before it closed it (an ErrorReply: a refusal, access
  // revoked by a reload), else that canemud went away, naming the socket. Takes what came
  // meanwhile (notifications queue up). For a client that otherwise only uses its rings.
  std::optional<IpcError> lost();

 private:
  Connection(ipc::UniqueFd fd, int timeout_ms, std::string path)
      : fd_(std::move(fd)), timeout_ms_(timeout_ms), path_(std::move(path)) {}
  Result<void> receive(uint32_t request_id, int timeout_ms);
  // Takes one packet: queues it if it is a notification, keeps canemud's parting word (an
  // ErrorReply of no request). Returns its request id. The descriptors that came with it go
  // to `fds` (nullptr: closed).
  Result<uint32_t> receive_one(int timeout_ms, std::vector<ipc::UniqueFd>* fds);
  // The connection broke (a send or receive failed, or canemud closed it): reads what canemud
  // sent before it closed (a reset connection reports the reset first, then gives what is
  // queued) and returns the reason that lost() gives from now on.
  IpcError broken();
  template <class Reply>
  Result<Reply> expect() {
    const ipc::MsgHeader* h = reinterpret_cast<const ipc::MsgHeader*>(buffer_.data());
    if (h->type == static_cast<uint16_t>(ipc::MsgType::error_reply)) {
      return tl::unexpected(error_from_reply());
    }
    if (h->type != static_cast<uint16_t>(ipc::type_of<Reply>())) {
      return tl::unexpected(IpcError{0, "unexpected reply type " + std::to_string(h->type)});
    }
    Reply r;
    std::memcpy(&r, buffer_.data(), sizeof r);
    return r;
  }
  IpcError error_from_reply() const;

  ipc::UniqueFd fd_;
  int timeout_ms_;
  int64_t reply_spin_ns_ = 200'000;  // how long a call polls for its reply before it blocks
  std::string path_;
  std::optional<std::string> parting_;  // an ErrorReply of no request: "code: text"
  std::optional<IpcError> lost_;
  uint32_t next_id_ = 0;
  uint32_t server_pid_ = 0;
  std::vector<uint8_t> buffer_;
  std::vector<ipc::UniqueFd> fds_;
  std::deque<ipc::Notification> notifications_;
};

}  // namespace canemu::client
