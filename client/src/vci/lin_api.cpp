// The LIN functions of the VCI C API, the same in libvcinpl and libvcinpl2 (vcinpl.h and
// vcinpl2.h declare them alike): control units and monitors of an adapter's LIN controllers.
// dwLinNo is the controller's bus number on the device, after its CAN controllers.
#include "can_api.hpp"
#include "lin_core.hpp"
#include "vcinpl_lin.h"

using namespace canemu::client::vci;
using Kind = Object::Kind;

namespace {

HRESULT open_lin(HANDLE hDevice, UINT32 no, Kind kind, bool exclusive, PHANDLE out) {
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *out = nullptr;
  auto* dev = static_cast<Device*>(lookup(hDevice, Kind::device));
  if (dev == nullptr) {
    return VCI_E_INVHANDLE;
  }
  std::unique_ptr<Remote> object;
  if (HRESULT hr = lin_open(dev->desc, no, kind, exclusive, object); hr != VCI_OK) {
    return hr;
  }
  *out = register_object(std::move(object));
  return VCI_OK;
}

template <class F>
HRESULT on_control(HANDLE h, F f) {
  Remote* r = remote_of(h, Kind::lin_control);
  return r == nullptr ? VCI_E_INVHANDLE : f(*r);
}

template <class F>
HRESULT on_monitor(HANDLE h, F f) {
  auto* m = static_cast<ChannelObj*>(lookup(h, Kind::lin_monitor));
  return m == nullptr ? VCI_E_INVHANDLE : f(*m);
}

HRESULT caps_of(HANDLE h, Kind kind, PLINCAPABILITIES caps) {
  Remote* r = remote_of(h, kind);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  return caps == nullptr ? VCI_E_INVALIDARG : lin_info(r->device, r->controller, r, caps, nullptr);
}

}  // namespace

extern "C" {

// ---- control unit ----

HRESULT VCIAPI linControlOpen(HANDLE hDevice, UINT32 dwLinNo, PHANDLE phLinCtl) {
  return open_lin(hDevice, dwLinNo, Kind::lin_control, false, phLinCtl);
}

HRESULT VCIAPI linControlClose(HANDLE hLinCtl) {
  return close_handle(hLinCtl, Kind::lin_control);
}

HRESULT VCIAPI linControlGetCaps(HANDLE hLinCtl, PLINCAPABILITIES pLinCaps) {
  return caps_of(hLinCtl, Kind::lin_control, pLinCaps);
}

HRESULT VCIAPI linControlGetStatus(HANDLE hLinCtl, PLINLINESTATUS pStatus) {
  return on_control(hLinCtl, [&](Remote& r) {
    return pStatus == nullptr ? VCI_E_INVALIDARG
                              : lin_info(r.device, r.controller, &r, nullptr, pStatus);
  });
}

HRESULT VCIAPI linControlInitialize(HANDLE hLinCtl, UINT8 bMode, UINT16 wBitrate) {
  return on_control(hLinCtl, [&](Remote& r) { return lin_init(r, bMode, wBitrate); });
}

HRESULT VCIAPI linControlReset(HANDLE hLinCtl) {
  return simple_call(hLinCtl, Kind::lin_control, canemu::ipc::VciOp::lin_reset);
}

HRESULT VCIAPI linControlStart(HANDLE hLinCtl, BOOL fStart) {
  return simple_call(hLinCtl, Kind::lin_control,
                     fStart ? canemu::ipc::VciOp::lin_start : canemu::ipc::VciOp::lin_stop);
}

HRESULT VCIAPI linControlWriteMessage(HANDLE hLinCtl, BOOL fSend, PLINMSG pLinMsg) {
  return on_control(hLinCtl, [&](Remote& r) { return lin_write(r, fSend != 0, pLinMsg); });
}

// ---- message monitors ----

HRESULT VCIAPI linMonitorOpen(HANDLE hDevice, UINT32 dwLinNo, BOOL fExclusive, PHANDLE phLinMon) {
  return open_lin(hDevice, dwLinNo, Kind::lin_monitor, fExclusive != 0, phLinMon);
}

HRESULT VCIAPI linMonitorClose(HANDLE hLinMon) {
  return close_handle(hLinMon, Kind::lin_monitor);
}

HRESULT VCIAPI linMonitorGetCaps(HANDLE hLinMon, PLINCAPABILITIES pLinCaps) {
  return caps_of(hLinMon, Kind::lin_monitor, pLinCaps);
}

HRESULT VCIAPI linMonitorGetStatus(HANDLE hLinMon, PLINMONITORSTATUS pStatus) {
  return on_monitor(hLinMon, [&](ChannelObj& m) { return lin_monitor_status(m, pStatus); });
}

HRESULT VCIAPI linMonitorInitialize(HANDLE hLinMon, UINT16 wFifoSize, UINT16 wThreshold) {
  return on_monitor(hLinMon, [&](ChannelObj& m) {
    return wFifoSize == 0 ? VCI_E_INVALIDARG : req::init_lin_monitor(m, wFifoSize, wThreshold);
  });
}

HRESULT VCIAPI linMonitorActivate(HANDLE hLinMon, BOOL fEnable) {
  return on_monitor(hLinMon, [&](ChannelObj& m) { return lin_monitor_activate(m, fEnable != 0); });
}

HRESULT VCIAPI linMonitorPeekMessage(HANDLE hLinMon, PLINMSG pLinMsg) {
  return on_monitor(hLinMon, [&](ChannelObj& m) {
    return pLinMsg == nullptr ? VCI_E_INVALIDARG : channel_peek(m, pLinMsg);
  });
}

HRESULT VCIAPI linMonitorPeekMsgMult(HANDLE hLinMon, LINMSG aLinMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone) {
  return linMonitorReadMsgMult(hLinMon, 0, aLinMsg, dwCount, pdwDone);
}

HRESULT VCIAPI linMonitorWaitRxEvent(HANDLE hLinMon, UINT32 dwTimeout) {
  return on_monitor(hLinMon, [&](ChannelObj& m) { return channel_wait_rx(m, dwTimeout); });
}

HRESULT VCIAPI linMonitorReadMessage(HANDLE hLinMon, UINT32 dwTimeout, PLINMSG pLinMsg) {
  return on_monitor(hLinMon, [&](ChannelObj& m) {
    return pLinMsg == nullptr ? VCI_E_INVALIDARG : channel_read(m, dwTimeout, pLinMsg);
  });
}

HRESULT VCIAPI linMonitorReadMsgMult(HANDLE hLinMon, UINT32 dwTimeout, LINMSG aLinMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone) {
  return on_monitor(hLinMon, [&](ChannelObj& m) {
    if (aLinMsg == nullptr || pdwDone == nullptr) {
      return VCI_E_INVALIDARG;
    }
    uint32_t n = 0;
    const HRESULT hr = channel_read_many(m, dwTimeout, aLinMsg, dwCount, n);
    *pdwDone = n;
    return hr;
  });
}

}  // extern "C"
