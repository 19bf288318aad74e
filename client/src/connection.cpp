#include "canemu/client/connection.hpp"

#include <cstring>

#include <unistd.h>

namespace canemu::client {

Result<Connection> Connection::open(const std::string& path, const std::string& client_name,
                                    int timeout_ms) {
  auto fd = ipc::connect_seqpacket(path);
  if (!fd) {
    IpcError e = fd.error();
    e.message += " (is canemud running? start it with 'make run' or 'canemud --socket " + path +
                 "', or set CANEMU_SOCKET)";
    return tl::unexpected(e);
  }
  Connection c(std::move(*fd), timeout_ms);
  auto hello = ipc::make_message<ipc::Hello>();
  hello.client_pid = static_cast<uint32_t>(::getpid());
  ipc::copy_name(hello.client_name, client_name);
  auto reply = c.call<ipc::Hello, ipc::HelloReply>(hello);
  if (!reply) {
    return tl::unexpected(reply.error());
  }
  c.server_pid_ = reply->server_pid;
  return c;
}

Result<uint32_t> Connection::receive_one(int timeout_ms) {
  auto n = ipc::receive_packet(fd_.get(), buffer_, timeout_ms, &fds_);
  if (!n) {
    return tl::unexpected(n.error());
  }
  if (*n == 0) {
    return tl::unexpected(IpcError{0, "canemud closed the connection"});
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
  }
  return h.request_id;
}

Result<void> Connection::receive(uint32_t request_id, int timeout_ms) {
  while (true) {
    auto id = receive_one(timeout_ms);
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
    auto id = receive_one(timeout_ms);
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
