// The VCI requests, each built once for the C and C++ APIs (see requests.hpp).
#include "requests.hpp"

#include <algorithm>
#include <cstring>
#include <vector>

#include <time.h>

#include <fmt/format.h>

namespace canemu::client::vci::req {

HRESULT open(ipc::VciOp op, uint16_t flags, const DeviceDesc& device, uint32_t controller,
             uint32_t& handle) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(op);
  m.flags = flags;
  ipc::copy_name(m.device, device.name);
  m.controller = controller;
  ipc::VciReply r{};
  const HRESULT hr = Library::get().call(m, r);
  handle = r.handle;
  return hr;
}

HRESULT open_can(Object::Kind kind, bool v2, bool exclusive, const DeviceDesc& device,
                 uint32_t controller, std::unique_ptr<Remote>& out) {
  ipc::VciOp op = ipc::VciOp::control_open;
  if (kind == Object::Kind::channel) {
    op = ipc::VciOp::channel_open;
  } else if (kind == Object::Kind::scheduler) {
    op = ipc::VciOp::scheduler_open;
  }
  const uint16_t flags =
      static_cast<uint16_t>((v2 ? ipc::kVciV2 : 0) | (exclusive ? ipc::kVciExclusive : 0));
  uint32_t handle = 0;
  if (HRESULT hr = open(op, flags, device, controller, handle); hr != VCI_OK) {
    return hr;
  }
  if (kind == Object::Kind::channel) {
    out = std::make_unique<ChannelObj>(handle, device, controller, v2);
  } else {
    out = std::make_unique<Remote>(kind, handle, device, controller);
  }
  return VCI_OK;
}

HRESULT simple(const Remote& object, ipc::VciOp op, std::initializer_list<uint32_t> args,
               ipc::VciReply* reply) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(op);
  m.handle = object.handle;
  std::size_t i = 0;
  for (uint32_t a : args) {
    m.args[i++] = a;
  }
  ipc::VciReply r{};
  const HRESULT hr = Library::get().call(m, r);
  if (reply != nullptr) {
    *reply = r;
  }
  return hr;
}

HRESULT line_info(const Remote& object, ipc::VciReply& reply) {
  return simple(object, ipc::VciOp::line_info, {}, &reply);
}

HRESULT line_info(const DeviceDesc& device, uint32_t controller, ipc::VciReply& reply) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::line_info);
  ipc::copy_name(m.device, device.name);
  m.controller = controller;
  return Library::get().call(m, reply);
}

HRESULT filter(const Remote& object, ipc::VciOp op, uint32_t kind, bool extended, uint8_t mode,
               uint32_t code, uint32_t mask, uint8_t* mode_out) {
  ipc::VciReply r{};
  const HRESULT hr = simple(
      object, op,
      {kind, static_cast<uint32_t>(extended ? CAN_FILTER_EXT : CAN_FILTER_STD), mode, code, mask},
      &r);
  if (mode_out != nullptr && hr == VCI_OK) {
    *mode_out = static_cast<uint8_t>(r.values[0]);
  }
  return hr;
}

HRESULT init_line(const Remote& control, const void* init, std::size_t size, bool v2) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::control_init);
  m.flags = v2 ? ipc::kVciV2 : 0;
  m.handle = control.handle;
  std::memcpy(m.payload, init, std::min(size, sizeof m.payload));
  ipc::VciReply reply{};
  return Library::get().call(m, reply);
}

HRESULT scheduler_add(const Remote& list, const CANCYCLICTXMSG2& msg, PUINT32 index) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::scheduler_add);
  m.handle = list.handle;
  std::memcpy(m.payload, &msg, sizeof msg);
  ipc::VciReply reply{};
  const HRESULT hr = Library::get().call(m, reply);
  if (index != nullptr) {
    *index = hr == VCI_OK ? reply.values[0] : 0xFFFFFFFFU;
  }
  return hr;
}

HRESULT detect(const Remote& control, bool v2, const void* table, std::size_t size,
               uint16_t timeout_ms, uint8_t op_mode, uint8_t ex_mode, uint32_t& index) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::control_detect);
  m.flags = v2 ? ipc::kVciV2 : 0;
  m.handle = control.handle;
  m.args[0] = timeout_ms;
  m.args[1] = op_mode;
  m.args[2] = ex_mode;
  std::memcpy(m.payload, table, std::min(size, sizeof m.payload));
  ipc::VciReply r{};
  if (HRESULT hr = Library::get().call(m, r); hr != VCI_OK) {
    return hr;
  }
  while (true) {
    const HRESULT hr = simple(control, ipc::VciOp::control_detect_result, {}, &r);
    if (hr != VCI_E_PENDING) {
      index = r.values[0];
      return hr;
    }
    const timespec pause{0, 1'000'000};
    ::nanosleep(&pause, nullptr);
  }
}

namespace {

// Sends an initialization `m` of `channel` (a channel or monitor) and maps the rings of its
// reply.
HRESULT map_rings(ChannelObj& channel, ipc::VciRequest& m, bool has_tx, uint32_t rx_threshold,
                  uint32_t tx_threshold) {
  ipc::VciReply r{};
  std::vector<ipc::UniqueFd> fds;
  uint64_t generation = 0;
  if (HRESULT hr = Library::get().call(m, r, &fds, &generation); hr != VCI_OK) {
    return hr;
  }
  const uint32_t element = channel.element_size();
  if (fds.size() != ipc::kChannelFdCount || r.values[2] != element) {
    set_detail(
        fmt::format("canemud sent {} descriptors and {}-byte elements", fds.size(), r.values[2]));
    return VCI_E_UNEXPECTED;
  }
  auto mapped = ipc::RingPair::map(std::move(fds), element);
  if (!mapped) {
    set_detail("the channel's rings could not be mapped");
    return VCI_E_UNEXPECTED;
  }
  auto rings = std::make_shared<Rings>(std::move(*mapped), has_tx);
  rings->can_fd = channel.controller < channel.device.controller_fd.size() &&
                  channel.device.controller_fd[channel.controller];
  rings->rx.set_threshold(std::max<uint32_t>(rx_threshold, 1));
  rings->tx.set_threshold(std::max<uint32_t>(tx_threshold, 1));
  rings->generation = generation;
  channel.rings = std::move(rings);
  return VCI_OK;
}

}  // namespace

HRESULT init_channel(ChannelObj& channel, uint32_t rx, uint32_t rx_threshold, uint32_t tx,
                     uint32_t tx_threshold, uint32_t filter_size, uint8_t filter_mode) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::channel_init);
  m.handle = channel.handle;
  m.args[0] = rx;
  m.args[1] = tx;
  m.args[2] = filter_size;
  m.args[3] = filter_mode;
  return map_rings(channel, m, tx != 0, rx_threshold, tx_threshold);
}

HRESULT init_lin_monitor(ChannelObj& monitor, uint32_t rx, uint32_t rx_threshold) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::lin_monitor_init);
  m.handle = monitor.handle;
  m.args[0] = rx;
  return map_rings(monitor, m, false, rx_threshold, 1);
}

}  // namespace canemu::client::vci::req
