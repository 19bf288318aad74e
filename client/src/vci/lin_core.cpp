#include "lin_core.hpp"

#include <cstring>

namespace canemu::client::vci {

bool is_lin_controller(const DeviceDesc& device, uint32_t bus_no) {
  return bus_no < device.controller_lin.size() && device.controller_lin[bus_no];
}

HRESULT lin_open(const DeviceDesc& device, uint32_t bus_no, Object::Kind kind, bool exclusive,
                 std::unique_ptr<Remote>& out) {
  if (!is_lin_controller(device, bus_no)) {
    return VCI_E_INVALIDARG;
  }
  const bool monitor = kind == Object::Kind::lin_monitor;
  const auto op = monitor ? ipc::VciOp::lin_monitor_open : ipc::VciOp::lin_control_open;
  const uint16_t flags = exclusive ? ipc::kVciExclusive : 0;
  uint32_t handle = 0;
  if (HRESULT hr = req::open(op, flags, device, bus_no, handle); hr != VCI_OK) {
    return hr;
  }
  if (monitor) {
    out = std::make_unique<ChannelObj>(handle, device, bus_no, false, kind);
  } else {
    out = std::make_unique<Remote>(kind, handle, device, bus_no);
  }
  return VCI_OK;
}

HRESULT lin_info(const DeviceDesc& device, uint32_t bus_no, const Remote* object,
                 LINCAPABILITIES* caps, LINLINESTATUS* status) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::lin_info);
  if (object != nullptr) {
    m.handle = object->handle;
  } else {
    ipc::copy_name(m.device, device.name);
    m.controller = bus_no;
  }
  ipc::VciReply r{};
  if (HRESULT hr = Library::get().call(m, r); hr != VCI_OK) {
    return hr;
  }
  if (caps != nullptr) {
    std::memcpy(caps, r.payload + ipc::kVciCapsOffset, sizeof *caps);
  }
  if (status != nullptr) {
    std::memcpy(status, r.payload + ipc::kVciLineOffset, sizeof *status);
  }
  return VCI_OK;
}

HRESULT lin_init(const Remote& control, uint8_t op_mode, uint16_t bitrate) {
  return req::simple(control, ipc::VciOp::lin_init, {op_mode, bitrate});
}

HRESULT lin_write(const Remote& control, bool send, const LINMSG* msg) {
  if (msg == nullptr) {
    return VCI_E_INVALIDARG;
  }
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::lin_write);
  m.handle = control.handle;
  m.args[0] = send ? 1 : 0;
  std::memcpy(m.payload, msg, sizeof *msg);
  ipc::VciReply r{};
  return Library::get().call(m, r);
}

HRESULT lin_monitor_activate(const Remote& monitor, bool enable) {
  return req::simple(
      monitor, enable ? ipc::VciOp::lin_monitor_activate : ipc::VciOp::lin_monitor_deactivate);
}

HRESULT lin_monitor_status(ChannelObj& monitor, LINMONITORSTATUS* out) {
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  LINMONITORSTATUS s{};
  if (HRESULT hr = lin_info(monitor.device, monitor.controller, &monitor, nullptr, &s.sLineStatus);
      hr != VCI_OK) {
    return hr;
  }
  ipc::VciReply r{};
  if (HRESULT hr = req::simple(monitor, ipc::VciOp::lin_monitor_status, {}, &r); hr != VCI_OK) {
    return hr;
  }
  s.fActivated = r.values[1] != 0;
  s.fRxOverrun = r.values[2] != 0;
  s.bRxFifoLoad = monitor.rings ? rx_load(monitor) : 0;
  *out = s;
  return VCI_OK;
}

}  // namespace canemu::client::vci
