#include "lin_tap.hpp"

#include <cstring>

#include <fmt/format.h>

#include "canemu/client/lists.hpp"
#include "vci/vcierr.h"

namespace canemu::cli {

namespace {

ipc::VciRequest request(ipc::VciOp op, const std::string& device, uint32_t handle,
                        std::initializer_list<uint32_t> args = {}) {
  auto m = ipc::make_message<ipc::VciRequest>();
  m.op = static_cast<uint16_t>(op);
  m.handle = handle;
  ipc::copy_name(m.device, device);
  std::size_t i = 0;
  for (uint32_t a : args) {
    m.args[i++] = a;
  }
  return m;
}

}  // namespace

client::Result<ipc::VciReply> vci_call(client::Connection& c, ipc::VciRequest m,
                                       std::vector<ipc::UniqueFd>* fds) {
  const auto op = m.op;
  auto r = c.call<ipc::VciRequest, ipc::VciReply>(m);
  if (r && fds != nullptr) {
    *fds = c.take_fds();
  }
  if (r && r->hresult != VCI_OK) {
    return tl::unexpected(
        ipc::IpcError{EPROTO, fmt::format("canemud refused VCI request {}: 0x{:08X}", op,
                                          static_cast<uint32_t>(r->hresult))});
  }
  return r;
}

client::Result<LinTap> LinTap::open(client::Connection& c, const std::string& bus, uint8_t mode,
                                    uint32_t bitrate) {
  auto create = request(ipc::VciOp::device_create, "", 0);
  ipc::copy_name(reinterpret_cast<char(&)[ipc::kNameSize]>(create.payload), bus);
  auto created = vci_call(c, create);
  if (!created) {
    return tl::unexpected(created.error());
  }
  char name_text[ipc::kNameSize] = {};
  std::memcpy(name_text, created->payload, sizeof name_text - 1);
  const std::string device = ipc::name_of(name_text);
  auto monitor = vci_call(c, request(ipc::VciOp::lin_monitor_open, device, 0));
  std::vector<ipc::UniqueFd> fds;
  if (monitor) {
    monitor =
        vci_call(c, request(ipc::VciOp::lin_monitor_init, device, monitor->handle, {4096}), &fds);
  }
  if (monitor) {
    monitor = vci_call(c, request(ipc::VciOp::lin_monitor_activate, device, monitor->handle));
  }
  auto control = monitor ? vci_call(c, request(ipc::VciOp::lin_control_open, device, 0)) : monitor;
  if (control) {
    const uint32_t handle = control->handle;
    auto r = vci_call(c, request(ipc::VciOp::lin_init, device, handle, {mode, bitrate}));
    control = r ? vci_call(c, request(ipc::VciOp::lin_start, device, handle)) : r;
    if (control) {
      control->handle = handle;
    }
  }
  if (!control) {
    return tl::unexpected(control.error());
  }
  auto rings = ipc::RingPair::map(std::move(fds), sizeof(LINMSG));
  if (!rings) {
    return tl::unexpected(rings.error());
  }
  // Time stamps count microseconds from the adapter's power-on.
  int64_t epoch_ns = 0;
  auto list = client::fetch_device_list(c);
  for (std::size_t i = 0; list && i < list->devices.size(); ++i) {
    if (ipc::name_of(list->devices[i].name) == device) {
      epoch_ns = list->devices[i].epoch_ns;
    }
  }
  LinTap tap(device, control->handle, std::move(*rings), epoch_ns);
  tap.rx_.set_threshold(1);
  return tap;
}

client::Result<std::optional<LinTap::Message>> LinTap::next(int timeout_ms) {
  while (true) {
    LINMSG m;
    const ipc::RingStatus status = rx_.get(&m);
    if (status == ipc::RingStatus::empty) {
      if (timeout_ms == 0 || !rx_.wait(timeout_ms)) {
        return std::nullopt;
      }
      continue;
    }
    if (status != ipc::RingStatus::ok) {
      return tl::unexpected(ipc::IpcError{EPROTO, "the monitor's ring is corrupted"});
    }
    if (m.uMsgInfo.Bytes.bType == LIN_MSGTYPE_TMOVR) {
      wraps_ += m.uMsgInfo.Bytes.bDlen;
      continue;
    }
    return Message{m, epoch_ns_ + static_cast<int64_t>(((wraps_ << 32) | m.dwTime) * 1000)};
  }
}

}  // namespace canemu::cli
