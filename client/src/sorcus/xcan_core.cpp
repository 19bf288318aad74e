#include "xcan_core.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include <unistd.h>

#include "canemu/client/lists.hpp"
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

Library::Library()
    : callbacks_([](const Queued& q) { invoke(q.channel, q.callback, q.message); },
                 CallbackThread<Queued>::AtEnd::run_queued),
      link_("xcan", [this](const std::vector<uint8_t>& packet) {
        ipc::MsgHeader h;
        std::memcpy(&h, packet.data(), sizeof h);
        if (h.type == static_cast<uint16_t>(ipc::MsgType::xcan_callback)) {
          ipc::XcanCallbackMsg m;
          std::memcpy(&m, packet.data(), sizeof m);
          deliver(m);
        }
      }) {}

ULONG Library::reconnect(const std::string& socket) {
  {
    std::lock_guard lock(mutex_);
    handles_.clear();
  }
  link_.reconnect(socket);
  return socket.empty() ? ERR_OK : connect();
}

ULONG Library::connect() {
  if (!link_.connect()) {
    return ERR_XCAN_NO_DAEMON;
  }
  std::lock_guard lock(mutex_);
  if (const uint64_t g = link_.generation(); g != generation_) {
    // Channels of the old connection are gone on canemud's side.
    if (generation_ != 0) {
      std::erase_if(handles_, [](const auto& e) { return e.second.kind == Kind::channel; });
    }
    generation_ = g;
  }
  callbacks_.start();
  return ERR_OK;
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

ULONG Library::call(ipc::XcanRequest& request, ipc::XcanReply& reply) {
  if (ULONG e = connect(); e != ERR_OK) {
    return e;
  }
  switch (link_.call(request, reply)) {
    case DaemonLink::Outcome::replied:
      return ERR_OK;
    case DaemonLink::Outcome::refused:
      return ERR_XCAN_NO_MODULE;
    case DaemonLink::Outcome::no_daemon:
      break;
  }
  return ERR_XCAN_NO_DAEMON;
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
  callbacks_.push(Queued{channel, callback, m});
}

std::optional<int64_t> Library::callback_time() {
  if (t_callback == nullptr) {
    return std::nullopt;
  }
  return t_callback->sim_time_ns;
}

ULONG Library::interfaces(std::vector<CANEMU_XCAN_INTERFACE>& out) {
  auto c = link_.open_another("xcan");
  if (!c) {
    return ERR_XCAN_NO_DAEMON;
  }
  auto status = client::fetch_status(*c);
  if (!status) {
    return ERR_XCAN_NO_DAEMON;
  }
  auto devices = client::fetch_device_list(*c);
  if (!devices) {
    return ERR_XCAN_NO_DAEMON;
  }
  // The device list names the modules (in configuration order) and the bus of each interface;
  // the status gives those buses' transceiver and bit rate.
  for (const ipc::DeviceEntry& e : devices->devices) {
    if (e.model != static_cast<uint8_t>(ipc::WireDeviceModel::sorcus_x_can_2i)) {
      continue;
    }
    for (uint8_t k = 0; k < e.controller_count && k < XCAN_INTERFACES; ++k) {
      const std::string bus = ipc::name_of(e.buses[k]);
      const auto b = std::find_if(
          status->buses.begin(), status->buses.end(),
          [&](const ipc::StatusBus& candidate) { return ipc::name_of(candidate.name) == bus; });
      CANEMU_XCAN_INTERFACE info{};
      std::snprintf(info.szDevice, sizeof info.szDevice, "%s", ipc::name_of(e.name).c_str());
      std::snprintf(info.szBus, sizeof info.szBus, "%s", bus.c_str());
      info.usChannel = k;
      if (b != status->buses.end()) {
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

}  // namespace canemu::client::xcan
