#include "canemu/client/daemon_link.hpp"

#include <sys/socket.h>

#include <cstring>

#include "canemu/ipc/seqpacket.hpp"

namespace canemu::client {

DaemonLink::~DaemonLink() {
  std::unique_lock lock(mutex_);
  stop_receiver(lock);
}

void DaemonLink::stop_receiver(std::unique_lock<std::mutex>& lock) {
  if (connection_) {
    ::shutdown(connection_->fd(), SHUT_RDWR);  // the receive thread sees the end and leaves
  }
  lock.unlock();
  if (receiver_.joinable()) {
    receiver_.join();  // it takes the lock on its way out
  }
  lock.lock();
}

void DaemonLink::drop_locked(std::string why) {
  if (!connection_) {
    return;
  }
  lost_reason_ = std::move(why);
  if (concurrent_) {
    ::shutdown(connection_->fd(), SHUT_RDWR);  // the receive thread ends the waits and leaves
  } else {
    connection_.reset();
  }
}

void DaemonLink::reconnect(const std::string& socket, std::string why) {
  std::unique_lock lock(mutex_);
  if (concurrent_) {
    stop_receiver(lock);
  }
  if (connection_) {
    connection_.reset();
    lost_reason_ = std::move(why);
  }
  broken_ = false;
  socket_ = socket;
}

Result<void> DaemonLink::connect() {
  std::lock_guard lock(mutex_);
  return connect_locked();
}

uint64_t DaemonLink::generation() const {
  std::lock_guard lock(mutex_);
  return generation_;
}

Result<Connection> DaemonLink::open_another(const std::string& name) const {
  std::string socket;
  {
    std::lock_guard lock(mutex_);
    socket = socket_;
  }
  return Connection::open(ipc::socket_path(socket), name);
}

std::optional<std::string> DaemonLink::lost(uint64_t generation) {
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) {
    return std::nullopt;
  }
  if (generation == generation_ && connection_) {
    if (concurrent_) {
      if (!broken_) {
        return std::nullopt;
      }
    } else {
      auto gone = connection_->lost();
      if (!gone) {
        return std::nullopt;
      }
      drop_locked(gone->message);
    }
  }
  return generation == generation_ ? lost_reason_
                                   : "the connection to canemud it was opened on is closed";
}

Result<DaemonLink::Turn> DaemonLink::turn() {
  std::unique_lock lock(mutex_);
  if (auto up = connect_locked(); !up) {
    return tl::unexpected(up.error());
  }
  return Turn(this, std::move(lock));
}

Result<void> DaemonLink::connect_locked() {
  if (connection_ && !broken_) {
    return {};
  }
  if (connection_) {
    if (receiver_.joinable()) {
      receiver_.join();  // it has left: it set broken_ on its way out
    }
    connection_.reset();
  }
  auto c = Connection::open(ipc::socket_path(socket_), client_name_);
  if (!c) {
    return tl::unexpected(c.error());
  }
  connection_.emplace(std::move(*c));
  broken_ = false;
  ++generation_;
  lost_reason_.clear();
  if (concurrent_) {
    receiver_ = std::thread([this, fd = connection_->fd()] { receive_loop(fd); });
  }
  return {};
}

DaemonLink::Outcome DaemonLink::call_raw(const void* request, std::size_t size,
                                         uint32_t& request_id, std::vector<uint8_t>& reply) {
  Waiter w;
  std::unique_lock lock(mutex_);
  if (!connect_locked()) {
    return Outcome::no_daemon;
  }
  request_id = ++next_request_;
  if (request_id == 0) {
    request_id = ++next_request_;  // 0 marks unsolicited messages
  }
  waiters_[request_id] = &w;
  if (!ipc::send_packet(connection_->fd(), request, size)) {
    waiters_.erase(request_id);
    return Outcome::no_daemon;
  }
  // The receive thread ends every wait: with the reply, or as lost when the connection breaks.
  replied_.wait(lock, [&] { return w.done; });
  waiters_.erase(request_id);
  if (w.lost) {
    return Outcome::no_daemon;
  }
  reply = std::move(w.packet);
  return Outcome::replied;
}

void DaemonLink::receive_loop(int fd) {
  std::vector<uint8_t> buffer;
  while (true) {
    auto n = ipc::receive_packet(fd, buffer, -1);
    if (!n || *n == 0) {
      break;
    }
    if (ipc::check_message(buffer.data(), buffer.size()) != ipc::ErrorCode::none) {
      continue;
    }
    ipc::MsgHeader h;
    std::memcpy(&h, buffer.data(), sizeof h);
    if (h.request_id == 0) {
      if (on_unsolicited_) {
        on_unsolicited_(buffer);
      }
      continue;
    }
    std::lock_guard lock(mutex_);
    auto it = waiters_.find(h.request_id);
    if (it != waiters_.end()) {
      it->second->done = true;
      it->second->packet = buffer;
      replied_.notify_all();
    }
  }
  std::lock_guard lock(mutex_);
  broken_ = true;
  if (lost_reason_.empty()) {
    lost_reason_ = "canemud went away: the connection to canemud closed";
  }
  for (auto& [id, w] : waiters_) {
    w->done = true;
    w->lost = true;
  }
  replied_.notify_all();
}

}  // namespace canemu::client
