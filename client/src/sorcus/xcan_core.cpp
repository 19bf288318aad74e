#include "xcan_core.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include <sys/socket.h>
#include <unistd.h>

#include "canemu/ipc/seqpacket.hpp"

namespace canemu::client::xcan {

namespace {
constexpr std::size_t kMaxHandles = 4096;
// The callback this thread is running (canemu_xcan_callback_time), or none.
thread_local const ipc::XcanCallbackMsg* t_callback = nullptr;
}  // namespace

Library& Library::get() {
  static Library library;
  return library;
}

Library::~Library() {
  {
    std::lock_guard lock(mutex_);
    disconnect_locked();
  }
  if (receiver_.joinable()) {
    receiver_.join();
  }
  {
    std::lock_guard lock(queue_mutex_);
    stopping_ = true;
  }
  queued_.notify_all();
  if (caller_.joinable()) {
    caller_.join();
  }
}

ULONG Library::reconnect(const std::string& socket) {
  std::unique_lock lock(mutex_);
  disconnect_locked();
  lock.unlock();
  if (receiver_.joinable()) {
    receiver_.join();  // it takes the lock on its way out
  }
  lock.lock();
  connection_.reset();
  broken_ = false;
  handles_.clear();
  socket_ = socket;
  return socket.empty() ? ERR_OK : connect_locked();
}

MAX_HANDLE Library::add(Handle h) {
  std::lock_guard lock(mutex_);
  if (handles_.size() >= kMaxHandles) {
    return 0;
  }
  while (next_handle_ == 0 || handles_.contains(next_handle_)) {
    ++next_handle_;
  }
  const MAX_HANDLE id = next_handle_++;
  handles_[id] = std::move(h);
  return id;
}

std::optional<Library::Handle> Library::find(MAX_HANDLE h, Kind kind) {
  std::lock_guard lock(mutex_);
  auto it = handles_.find(h);
  if (it == handles_.end() || it->second.kind != kind) {
    return std::nullopt;
  }
  return it->second;
}

void Library::remove(MAX_HANDLE h) {
  std::lock_guard lock(mutex_);
  handles_.erase(h);
}

void Library::disconnect_locked() {
  if (connection_) {
    ::shutdown(connection_->fd(), SHUT_RDWR);  // the receive thread sees the end and leaves
  }
}

ULONG Library::connect_locked() {
  if (connection_ && !broken_) {
    return ERR_OK;
  }
  if (connection_) {
    // The receive thread has left (it set broken_ on its way out).
    if (receiver_.joinable()) {
      receiver_.join();
    }
    connection_.reset();
    // Channels of the old connection are gone on canemud's side.
    std::erase_if(handles_, [](const auto& e) { return e.second.kind == Kind::channel; });
  }
  auto c = Connection::open(ipc::socket_path(socket_), "xcan");
  if (!c) {
    return ERR_XCAN_NO_DAEMON;
  }
  connection_.emplace(std::move(*c));
  broken_ = false;
  receiver_ = std::thread([this, fd = connection_->fd()] { receive_loop(fd); });
  if (!caller_.joinable()) {
    caller_ = std::thread([this] { callback_loop(); });
  }
  return ERR_OK;
}

ULONG Library::call(ipc::XcanRequest& request, ipc::XcanReply& reply) {
  Waiter w;
  std::unique_lock lock(mutex_);
  if (ULONG e = connect_locked(); e != ERR_OK) {
    return e;
  }
  request.header.request_id = ++next_request_;
  if (request.header.request_id == 0) {
    request.header.request_id = ++next_request_;  // 0 marks unsolicited messages
  }
  waiters_[request.header.request_id] = &w;
  if (!ipc::send_message(connection_->fd(), request)) {
    waiters_.erase(request.header.request_id);
    return ERR_XCAN_NO_DAEMON;
  }
  // The receive thread ends every wait: with the reply, or as lost when the connection breaks
  // (a later connection of another thread cannot leave this one waiting).
  replied_.wait(lock, [&] { return w.done; });
  waiters_.erase(request.header.request_id);
  if (w.lost) {
    return ERR_XCAN_NO_DAEMON;
  }
  if (w.refused) {
    return ERR_XCAN_NO_MODULE;
  }
  reply = w.reply;
  return ERR_OK;
}

void Library::receive_loop(int fd) {
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
    const auto type = static_cast<ipc::MsgType>(h.type);
    if (type == ipc::MsgType::xcan_callback) {
      ipc::XcanCallbackMsg m;
      std::memcpy(&m, buffer.data(), sizeof m);
      deliver(m);
    } else if (type == ipc::MsgType::xcan_reply || type == ipc::MsgType::error_reply) {
      std::lock_guard lock(mutex_);
      auto it = waiters_.find(h.request_id);
      if (it != waiters_.end()) {
        Waiter& w = *it->second;
        w.done = true;
        w.refused = type == ipc::MsgType::error_reply;
        if (!w.refused) {
          std::memcpy(&w.reply, buffer.data(), sizeof w.reply);
        }
        replied_.notify_all();
      }
    }
  }
  std::lock_guard lock(mutex_);
  broken_ = true;
  for (auto& [id, w] : waiters_) {
    w->done = true;
    w->lost = true;
  }
  replied_.notify_all();
}

void Library::deliver(const ipc::XcanCallbackMsg& m) {
  MAX_HANDLE channel = 0;
  MAX_CALLBACK callback = nullptr;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, h] : handles_) {
      if (h.kind == Kind::channel && h.remote == m.channel) {
        channel = id;
        callback = h.callback;
        break;
      }
    }
  }
  if (callback == nullptr) {
    return;  // closed meanwhile, or opened without a function
  }
  if (m.sync != 0) {
    invoke(channel, callback, m);  // directly, on this thread, before the next message
    return;
  }
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(Queued{channel, callback, m});
  }
  queued_.notify_one();
}

std::optional<int64_t> Library::callback_time() {
  if (t_callback == nullptr) {
    return std::nullopt;
  }
  return t_callback->sim_time_ns;
}

ULONG Library::interfaces(std::vector<CANEMU_XCAN_INTERFACE>& out) {
  std::string socket;
  {
    std::lock_guard lock(mutex_);
    socket = socket_;
  }
  auto c = Connection::open(ipc::socket_path(socket), "xcan");
  if (!c) {
    return ERR_XCAN_NO_DAEMON;
  }
  auto status =
      c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  if (!status) {
    return ERR_XCAN_NO_DAEMON;
  }
  auto devices = c->call<ipc::DeviceListRequest, ipc::DeviceListReply>(
      ipc::make_message<ipc::DeviceListRequest>());
  if (!devices) {
    return ERR_XCAN_NO_DAEMON;
  }
  // The device list names the modules (in configuration order) and the bus of each interface;
  // the status gives those buses' transceiver and bit rate.
  const uint16_t buses = std::min<uint16_t>(status->bus_count, ipc::kMaxStatusBuses);
  const uint16_t count = std::min<uint16_t>(devices->count, ipc::kMaxDevices);
  for (uint16_t d = 0; d < count; ++d) {
    const ipc::DeviceEntry& e = devices->devices[d];
    if (e.model != static_cast<uint8_t>(ipc::WireDeviceModel::sorcus_x_can_2i)) {
      continue;
    }
    for (uint8_t k = 0; k < e.controller_count && k < XCAN_INTERFACES; ++k) {
      const std::string bus = ipc::name_of(e.buses[k]);
      const ipc::StatusBus* b = std::find_if(
          status->buses, status->buses + buses,
          [&](const ipc::StatusBus& candidate) { return ipc::name_of(candidate.name) == bus; });
      CANEMU_XCAN_INTERFACE info{};
      std::snprintf(info.szDevice, sizeof info.szDevice, "%s", ipc::name_of(e.name).c_str());
      std::snprintf(info.szBus, sizeof info.szBus, "%s", bus.c_str());
      info.usChannel = k;
      if (b != status->buses + buses) {
        info.usLowSpeed = b->low_speed;
        info.ulBitrate = b->bitrate;
      }
      out.push_back(info);
    }
  }
  return ERR_OK;
}

void Library::invoke(MAX_HANDLE channel, MAX_CALLBACK callback, const ipc::XcanCallbackMsg& m) {
  const ipc::XcanCallbackMsg* outer = t_callback;  // a direct callback may run in a buffered one
  t_callback = &m;
  struct Restore {
    const ipc::XcanCallbackMsg* outer;
    ~Restore() { t_callback = outer; }
  } restore{outer};
  switch (static_cast<ipc::XcanCallbackArg>(m.arg)) {
    case ipc::XcanCallbackArg::data:
      callback(channel, m.size, m.data);
      return;
    case ipc::XcanCallbackArg::status: {
      const ULONG status = m.status;
      callback(channel, sizeof status, &status);
      return;
    }
    case ipc::XcanCallbackArg::message: {
      XCAN_MESSAGE message;
      std::memcpy(&message, m.data, sizeof message);
      callback(channel, sizeof message, &message);
      return;
    }
    case ipc::XcanCallbackArg::none:
    default:
      callback(channel, 0, nullptr);
      return;
  }
}

void Library::callback_loop() {
  std::unique_lock lock(queue_mutex_);
  while (true) {
    queued_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) {
      return;  // stopping, nothing left
    }
    const Queued q = queue_.front();
    queue_.pop_front();
    lock.unlock();
    invoke(q.channel, q.callback, q.message);
    lock.lock();
  }
}

}  // namespace canemu::client::xcan
