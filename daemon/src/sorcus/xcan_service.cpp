#include "canemu/daemon/sorcus/xcan_service.hpp"

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "service_replies.hpp"

namespace canemu::daemon {

namespace {

using model::sorcus::CallbackArg;
using model::sorcus::Reply;

void put_data(ipc::XcanReply& r, const std::vector<uint8_t>& data) {
  r.size = static_cast<uint16_t>(std::min(data.size(), ipc::kXcanDataSize));
  if (r.size > 0) {  // an empty vector's data() may be null
    std::memcpy(r.data, data.data(), r.size);
  }
}

}  // namespace

XcanService::~XcanService() {
  for (const std::shared_ptr<XcanDevice>& d : hooked_) {
    d->on_callback = nullptr;
    d->on_completed = nullptr;
  }
}

void XcanService::hook(const std::shared_ptr<XcanDevice>& device) {
  if (!hooked_.insert(device).second) {
    return;
  }
  XcanDevice* d = device.get();
  d->on_callback = [this, d](const model::sorcus::XcanCallback& c) { on_callback(*d, c); };
  d->on_completed = [this, d](const model::sorcus::XcanCompletion& c) { on_completed(*d, c); };
}

void XcanService::on_callback(const XcanDevice& device, const model::sorcus::XcanCallback& c) {
  auto it = routes_.find(Key{&device, c.channel});
  if (it == routes_.end()) {
    return;  // a channel closed with its callback under way
  }
  auto m = ipc::make_message<ipc::XcanCallbackMsg>(0);
  m.channel = it->second.channel;
  m.sync = c.sync ? 1 : 0;
  m.sim_time_ns = c.at.ns();
  switch (c.arg) {
    case CallbackArg::none:
      m.arg = static_cast<uint8_t>(ipc::XcanCallbackArg::none);
      break;
    case CallbackArg::data:
      m.arg = static_cast<uint8_t>(ipc::XcanCallbackArg::data);
      m.size = std::min<uint8_t>(c.size, 8);
      std::memcpy(m.data, c.data.data(), m.size);
      break;
    case CallbackArg::status:
      m.arg = static_cast<uint8_t>(ipc::XcanCallbackArg::status);
      m.status = c.status;
      break;
    case CallbackArg::message:
      m.arg = static_cast<uint8_t>(ipc::XcanCallbackArg::message);
      static_assert(sizeof c.message <= sizeof m.data);
      std::memcpy(m.data, &c.message, sizeof c.message);
      m.size = sizeof c.message;
      break;
  }
  it->second.session->outbox.push_back(bytes_of(m));
}

void XcanService::on_completed(const XcanDevice& device, const model::sorcus::XcanCompletion& c) {
  auto it = waiting_.find(Key{&device, c.request});
  if (it == waiting_.end()) {
    return;
  }
  const Waiting w = it->second;
  waiting_.erase(it);
  --w.session->pending;
  auto r = ipc::make_message<ipc::XcanReply>(w.request_id);
  r.error = c.error;
  r.channel = w.channel;
  r.sim_time_ns = c.at.ns();
  put_data(r, c.data);
  w.session->outbox.push_back(bytes_of(r));
}

void XcanService::fail_waiting(XcanSession& session, uint32_t channel, uint32_t error) {
  for (auto it = waiting_.begin(); it != waiting_.end();) {
    if (it->second.session == &session && it->second.channel == channel) {
      auto r = ipc::make_message<ipc::XcanReply>(it->second.request_id);
      r.error = error;
      r.channel = channel;
      r.sim_time_ns = sim_.scheduler().now().ns();
      session.outbox.push_back(bytes_of(r));
      --session.pending;
      it = waiting_.erase(it);
    } else {
      ++it;
    }
  }
}

void XcanService::close(XcanSession& session, uint32_t channel) {
  auto it = session.channels.find(channel);
  if (it == session.channels.end()) {
    return;
  }
  const XcanSession::Channel ch = it->second;
  session.channels.erase(it);
  routes_.erase(Key{ch.device.get(), ch.handle});
  // A request still waiting on it ends now: the channel it waited on is gone.
  fail_waiting(session, channel, ERR_XCAN_INVALID_HANDLE);
  (void)ch.device->module().close_channel(ch.handle);
}

void XcanService::close_all(XcanSession& session) {
  std::vector<uint32_t> open;
  for (const auto& [id, ch] : session.channels) {
    open.push_back(id);
  }
  for (uint32_t id : open) {
    close(session, id);
  }
  session.outbox.clear();
}

void XcanService::handle(XcanSession& s, const ipc::XcanRequest& m, const Send& send) {
  const uint32_t request_id = m.header.request_id;
  // What the events before this request made goes first.
  while (!s.outbox.empty()) {
    send(s.outbox.front().data(), s.outbox.front().size(), {});
    s.outbox.pop_front();
  }
  const auto op = static_cast<ipc::XcanOp>(m.op);
  auto r = ipc::make_message<ipc::XcanReply>(request_id);
  r.sim_time_ns = sim_.scheduler().now().ns();
  auto reply = [&] { send(&r, sizeof r, {}); };

  if (m.op < static_cast<uint16_t>(ipc::XcanOp::module_check) ||
      m.op > static_cast<uint16_t>(ipc::XcanOp::clear_error)) {
    protocol_error(send, request_id, ipc::ErrorCode::bad_argument,
                   fmt::format("X-CAN request: no operation {}", m.op));
    return;
  }
  if (m.reserved != 0 || (m.flags & ~ipc::kXcanCallback) != 0 ||
      (op != ipc::XcanOp::open && m.flags != 0)) {
    protocol_error(send, request_id, ipc::ErrorCode::bad_argument,
                   fmt::format("X-CAN request: flags {:#x} not allowed", m.flags));
    return;
  }
  if (op == ipc::XcanOp::module_check || op == ipc::XcanOp::open) {
    if (std::memchr(m.device, 0, sizeof m.device) == nullptr) {
      protocol_error(send, request_id, ipc::ErrorCode::bad_argument,
                     "X-CAN request: device name not terminated");
      return;
    }
    const std::string name = ipc::name_of(m.device);
    std::shared_ptr<XcanDevice> device = sim_.devices().find_xcan(name);
    if (!device) {
      protocol_error(send, request_id, ipc::ErrorCode::no_such_bus,
                     fmt::format("no X-CAN-2i named \"{}\"", name));
      return;
    }
    if (op == ipc::XcanOp::module_check) {
      r.value = static_cast<uint32_t>(device->module().variant());
      reply();
      return;
    }
    if (s.channels.size() >= kMaxXcanChannelsPerClient) {
      protocol_error(
          send, request_id, ipc::ErrorCode::no_resources,
          fmt::format("at most {} X-CAN channels per client", kMaxXcanChannelsPerClient));
      return;
    }
    CPS_XCAN cps;
    static_assert(sizeof cps == sizeof m.cps);
    std::memcpy(&cps, m.cps, sizeof cps);
    hook(device);
    auto h = device->module().open_channel(cps, (m.flags & ipc::kXcanCallback) != 0);
    if (!h) {
      r.error = h.error();
      reply();
      return;
    }
    const uint32_t id = s.next_channel++;
    s.channels[id] = XcanSession::Channel{device, *h};
    routes_[Key{device.get(), *h}] = Route{&s, id};
    r.channel = id;
    reply();
    return;
  }

  auto it = s.channels.find(m.channel);
  if (it == s.channels.end()) {
    r.error = ERR_XCAN_INVALID_HANDLE;
    r.channel = m.channel;
    reply();
    return;
  }
  r.channel = m.channel;
  XcanDevice& device = *it->second.device;
  model::sorcus::XcanModule& module = device.module();
  const model::sorcus::ChannelHandle h = it->second.handle;
  auto answer = [&](const Reply& got) {
    if (got.pending) {
      ++s.pending;
      waiting_[Key{&device, *got.pending}] = Waiting{&s, m.channel, request_id, m.op};
      return;  // answered by on_completed
    }
    r.error = got.error;
    put_data(r, got.data);
    reply();
  };
  if ((op == ipc::XcanOp::write_block || op == ipc::XcanOp::read_block) &&
      s.pending >= kMaxXcanPendingPerClient) {
    // A client that waits for its replies never gets here.
    protocol_error(
        send, request_id, ipc::ErrorCode::no_resources,
        fmt::format("at most {} X-CAN services may wait at once", kMaxXcanPendingPerClient));
    return;
  }
  switch (op) {
    case ipc::XcanOp::close:
      close(s, m.channel);
      // Requests that waited on it are answered before the close.
      while (!s.outbox.empty()) {
        send(s.outbox.front().data(), s.outbox.front().size(), {});
        s.outbox.pop_front();
      }
      reply();
      return;
    case ipc::XcanOp::write_block:
      if (m.size > ipc::kXcanDataSize) {
        r.error = ERR_XCAN_DATA_SIZE;
        reply();
        return;
      }
      answer(module.write_block(h, std::span<const uint8_t>(m.data, m.size)));
      return;
    case ipc::XcanOp::read_block:
      answer(module.read_block(h));
      return;
    case ipc::XcanOp::write_ulong:
      r.error = module.write_ulong(h, m.value);
      reply();
      return;
    case ipc::XcanOp::read_ulong: {
      auto v = module.read_ulong(h);
      r.error = v ? ERR_OK : v.error();
      r.value = v ? *v : 0;
      reply();
      return;
    }
    case ipc::XcanOp::control:
    case ipc::XcanOp::info: {
      if (m.value > 0xFFFF) {
        protocol_error(send, request_id, ipc::ErrorCode::bad_argument,
                       fmt::format("X-CAN request: command {} is not a USHORT", m.value));
        return;
      }
      const auto what = static_cast<USHORT>(m.value);
      if (op == ipc::XcanOp::control) {
        r.error = module.control(h, what);
      } else {
        auto v = module.info(h, what);
        r.error = v ? ERR_OK : v.error();
        r.value = v ? *v : 0;
      }
      reply();
      return;
    }
    case ipc::XcanOp::clear_error:
      r.error = module.clear_error(h);
      reply();
      return;
    default:
      protocol_error(send, request_id, ipc::ErrorCode::bad_argument,
                     fmt::format("X-CAN request: no operation {}", m.op));
      return;
  }
}

}  // namespace canemu::daemon
