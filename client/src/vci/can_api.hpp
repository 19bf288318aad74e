// What the CAN halves of libvcinpl (CANMSG, BTR0/BTR1) and libvcinpl2 (CANMSG2, CANBTP) share:
// opening and closing the control unit, channels and the cyclic list, the calls that differ
// only in their structs, and the data path. Each library's file holds its extern "C" functions
// and converts to and from these.
#pragma once

#include <cstring>

#include "requests.hpp"
#include "vci_core.hpp"

namespace canemu::client::vci {

inline Remote* remote_of(HANDLE h, Object::Kind kind) {
  return static_cast<Remote*>(lookup(h, kind));
}
inline ChannelObj* channel_of(HANDLE h) {
  return static_cast<ChannelObj*>(lookup(h, Object::Kind::channel));
}

// Opens a control unit (control), channel or cyclic list on bus `can_no` of `device`.
inline HRESULT open_on_line(const DeviceDesc& device, UINT32 can_no, Object::Kind kind, bool v2,
                            bool exclusive, PHANDLE out) {
  std::unique_ptr<Remote> object;
  if (HRESULT hr = req::open_can(kind, v2, exclusive, device, can_no, object); hr != VCI_OK) {
    return hr;
  }
  *out = register_object(std::move(object));
  return VCI_OK;
}

// Opens a control unit (control), channel or cyclic list on bus `can_no` of device `hDevice`.
inline HRESULT open_on_device(HANDLE hDevice, UINT32 can_no, Object::Kind kind, bool v2,
                              bool exclusive, PHANDLE out) {
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *out = nullptr;
  auto* dev = static_cast<Device*>(lookup(hDevice, Object::Kind::device));
  if (dev == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (can_no >= dev->desc.controller_fd.size()) {
    set_call_detail(VCI_E_INVALIDARG, no_can_controller(dev->desc, can_no));
    return VCI_E_INVALIDARG;
  }
  const HRESULT hr = open_on_line(dev->desc, can_no, kind, v2, exclusive, out);
  if (hr == VCI_E_INVALIDARG && can_no < dev->desc.controller_lin.size() &&
      dev->desc.controller_lin[can_no]) {
    // canemud refused a CAN object on it
    set_call_detail(VCI_E_INVALIDARG, no_can_controller(dev->desc, can_no));
  }
  return hr;
}

// canChannelGetControl, canSchedulerGetControl: the control unit of the line a channel or
// cyclic list (`kind`) is on, opened as canControlOpen opens it.
inline HRESULT control_of_line(HANDLE h, Object::Kind kind, bool v2, PHANDLE out) {
  Remote* r = static_cast<Remote*>(lookup(h, kind));
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *out = nullptr;
  return open_on_line(r->device, r->controller, Object::Kind::control, v2, false, out);
}

inline HRESULT close_handle(HANDLE h, Object::Kind kind) {
  return unregister_object(h, kind) ? VCI_OK : VCI_E_INVHANDLE;
}

// One of the line-info structs (capabilities, line status) of any object on a controller.
template <class T>
HRESULT line_struct(HANDLE h, Object::Kind kind, std::size_t offset, T* out) {
  Remote* r = remote_of(h, kind);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  ipc::VciReply reply{};
  if (HRESULT hr = req::line_info(*r, reply); hr != VCI_OK) {
    return hr;
  }
  std::memcpy(out, reply.payload + offset, sizeof(T));
  return VCI_OK;
}

inline HRESULT simple_call(HANDLE h, Object::Kind kind, ipc::VciOp op,
                           std::initializer_list<uint32_t> args = {},
                           ipc::VciReply* reply = nullptr) {
  Remote* r = remote_of(h, kind);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  return req::simple(*r, op, args, reply);
}

// Filter calls: `op_kind` one of req::kFilter* (the model's FilterOp::Kind).
inline HRESULT filter_call(HANDLE h, Object::Kind kind, uint32_t op_kind, BOOL extended,
                           uint8_t mode, UINT32 code, UINT32 mask, PUINT8 mode_out) {
  Remote* r = remote_of(h, kind);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  const ipc::VciOp op =
      kind == Object::Kind::control ? ipc::VciOp::control_filter : ipc::VciOp::channel_filter;
  return req::filter(*r, op, op_kind, extended != 0, mode, code, mask, mode_out);
}

// Channel status: the line status (CANLINESTATUS or CANLINESTATUS2, at `line_offset`) and the
// channel's own flags and fill levels.
template <class Status>
HRESULT channel_status_of(ChannelObj& c, std::size_t line_offset, Status* out) {
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  ipc::VciReply info{};
  ipc::VciReply status{};
  if (HRESULT hr = req::line_info(c, info); hr != VCI_OK) {
    return hr;
  }
  if (HRESULT hr = req::simple(c, ipc::VciOp::channel_status, {}, &status); hr != VCI_OK) {
    return hr;
  }
  Status s{};
  std::memcpy(&s.sLineStatus, info.payload + line_offset, sizeof s.sLineStatus);
  s.fActivated = status.values[1] != 0;
  s.fRxOverrun = status.values[2] != 0;
  s.bRxFifoLoad = rx_load(c);
  s.bTxFifoLoad = tx_load(c);
  *out = s;
  return VCI_OK;
}

template <class Status>
HRESULT channel_status(HANDLE h, std::size_t line_offset, Status* out) {
  ChannelObj* c = channel_of(h);
  return c == nullptr ? VCI_E_INVHANDLE : channel_status_of(*c, line_offset, out);
}

// The cyclic list's status (CANSCHEDULERSTATUS's two fields).
inline HRESULT scheduler_status_of(const Remote& list, UINT8* task, UINT8* entries) {
  ipc::VciReply reply{};
  if (HRESULT hr = req::simple(list, ipc::VciOp::scheduler_status, {}, &reply); hr != VCI_OK) {
    return hr;
  }
  CANSCHEDULERSTATUS s;
  std::memcpy(&s, reply.payload, sizeof s);
  *task = s.bTaskStat;
  std::memcpy(entries, s.abMsgStat, sizeof s.abMsgStat);
  return VCI_OK;
}

inline HRESULT scheduler_status(HANDLE h, UINT8* task, UINT8* entries) {
  Remote* r = remote_of(h, Object::Kind::scheduler);
  return r == nullptr ? VCI_E_INVHANDLE : scheduler_status_of(*r, task, entries);
}

// Adds `msg` to the list; `index` (may be null) gets its index, 0xFFFFFFFF on failure.
inline HRESULT scheduler_add(HANDLE h, const CANCYCLICTXMSG2& msg, PUINT32 index) {
  Remote* r = remote_of(h, Object::Kind::scheduler);
  if (r == nullptr) {
    if (index != nullptr) {
      *index = 0xFFFFFFFFU;
    }
    return VCI_E_INVHANDLE;
  }
  return req::scheduler_add(*r, msg, index);
}

// A classic cyclic message in the v2 layout the daemon takes.
inline CANCYCLICTXMSG2 to_cyclic2(const CANCYCLICTXMSG& c) {
  CANCYCLICTXMSG2 m{};
  m.wCycleTime = c.wCycleTime;
  m.bIncrMode = c.bIncrMode;
  m.bByteIndex = c.bByteIndex;
  m.dwMsgId = c.dwMsgId;
  m.uMsgInfo = c.uMsgInfo;
  std::memcpy(m.abData, c.abData, sizeof c.abData);
  return m;
}

template <class Init>
HRESULT control_init(HANDLE h, const Init& init, bool v2) {
  Remote* r = remote_of(h, Object::Kind::control);
  return r == nullptr ? VCI_E_INVHANDLE : req::init_line(*r, &init, sizeof init, v2);
}

}  // namespace canemu::client::vci
