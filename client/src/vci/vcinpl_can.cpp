// The CAN half of libvcinpl: CANMSG channels, BTR0/BTR1 initialization.
#include "can_api.hpp"
#include "vcinpl.h"

using namespace canemu::client::vci;
using canemu::ipc::VciOp;
using Kind = Object::Kind;

namespace {
// The multi-message calls: `send` queues, otherwise receives; a null count pointer or array is
// refused.
HRESULT many(HANDLE h, UINT32 timeout, void* msgs, UINT32 count, PUINT32 done, bool send) {
  ChannelObj* c = channel_of(h);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (msgs == nullptr || done == nullptr) {
    return VCI_E_INVALIDARG;
  }
  uint32_t n = 0;
  const HRESULT hr = send ? channel_send_many(*c, timeout, msgs, count, n)
                          : channel_read_many(*c, timeout, msgs, count, n);
  *done = n;
  return hr;
}

constexpr bool kV2 = false;
}

extern "C" {

// ---- control unit ----

HRESULT VCIAPI canControlOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanCtl) {
  return open_on_device(hDevice, dwCanNo, Kind::control, kV2, false, phCanCtl);
}

HRESULT VCIAPI canControlClose(HANDLE hCanCtl) { return close_handle(hCanCtl, Kind::control); }

HRESULT VCIAPI canControlGetCaps(HANDLE hCanCtl, PCANCAPABILITIES pCanCaps) {
  return line_struct(hCanCtl, Kind::control, canemu::ipc::kVciCapsOffset, pCanCaps);
}

HRESULT VCIAPI canControlGetStatus(HANDLE hCanCtl, PCANLINESTATUS pStatus) {
  return line_struct(hCanCtl, Kind::control, canemu::ipc::kVciLineOffset, pStatus);
}

HRESULT VCIAPI canControlDetectBitrate(HANDLE hCanCtl, UINT16 wTimeout, UINT32 dwCount,
                                       PUINT8 pabBtr0, PUINT8 pabBtr1, PINT32 plIndex) {
  Remote* r = remote_of(hCanCtl, Kind::control);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (dwCount == 0 || dwCount > 64 || pabBtr0 == nullptr || pabBtr1 == nullptr ||
      plIndex == nullptr) {
    return VCI_E_INVALIDARG;
  }
  CANBTRTABLE table{};
  table.bCount = static_cast<UINT8>(dwCount);
  std::memcpy(table.abBtr0, pabBtr0, dwCount);
  std::memcpy(table.abBtr1, pabBtr1, dwCount);
  uint32_t index = 0;
  const HRESULT hr =
      Library::get().detect(*r, false, &table, sizeof table, wTimeout, 0, 0, index);
  *plIndex = hr == VCI_OK ? static_cast<INT32>(index) : -1;
  return hr;
}

HRESULT VCIAPI canControlInitialize(HANDLE hCanCtl, UINT8 bMode, UINT8 bBtr0, UINT8 bBtr1) {
  CANINITLINE init{};
  init.bOpMode = bMode;
  init.bBtReg0 = bBtr0;
  init.bBtReg1 = bBtr1;
  return control_init(hCanCtl, init, kV2);
}

HRESULT VCIAPI canControlReset(HANDLE hCanCtl) {
  return simple_call(hCanCtl, Kind::control, VciOp::control_reset);
}

HRESULT VCIAPI canControlStart(HANDLE hCanCtl, BOOL fStart) {
  return simple_call(hCanCtl, Kind::control,
                     fStart ? VciOp::control_start : VciOp::control_stop);
}

HRESULT VCIAPI canControlSetAccFilter(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode,
                                      UINT32 dwMask) {
  return filter_call(hCanCtl, Kind::control, kFilterAcceptance, fExtend, 0, dwCode, dwMask,
                     nullptr);
}

HRESULT VCIAPI canControlAddFilterIds(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode,
                                      UINT32 dwMask) {
  return filter_call(hCanCtl, Kind::control, kFilterAddIds, fExtend, 0, dwCode, dwMask, nullptr);
}

HRESULT VCIAPI canControlRemFilterIds(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode,
                                      UINT32 dwMask) {
  return filter_call(hCanCtl, Kind::control, kFilterRemoveIds, fExtend, 0, dwCode, dwMask,
                     nullptr);
}

// ---- channels ----

HRESULT VCIAPI canChannelOpen(HANDLE hDevice, UINT32 dwCanNo, BOOL fExclusive,
                              PHANDLE phCanChn) {
  return open_on_device(hDevice, dwCanNo, Kind::channel, kV2, fExclusive != 0, phCanChn);
}

HRESULT VCIAPI canChannelClose(HANDLE hCanChn) { return close_handle(hCanChn, Kind::channel); }

HRESULT VCIAPI canChannelGetCaps(HANDLE hCanChn, PCANCAPABILITIES pCanCaps) {
  return line_struct(hCanChn, Kind::channel, canemu::ipc::kVciCapsOffset, pCanCaps);
}

HRESULT VCIAPI canChannelGetStatus(HANDLE hCanChn, PCANCHANSTATUS pStatus) {
  return channel_status(hCanChn, canemu::ipc::kVciLineOffset, pStatus);
}

HRESULT VCIAPI canChannelInitialize(HANDLE hCanChn, UINT16 wRxFifoSize, UINT16 wRxThreshold,
                                    UINT16 wTxFifoSize, UINT16 wTxThreshold) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (wRxFifoSize == 0) {
    return VCI_E_INVALIDARG;
  }
  return Library::get().init_channel(*c, wRxFifoSize, wRxThreshold, wTxFifoSize, wTxThreshold,
                                     0, CAN_FILTER_PASS);
}

HRESULT VCIAPI canChannelActivate(HANDLE hCanChn, BOOL fEnable) {
  return simple_call(hCanChn, Kind::channel,
                     fEnable ? VciOp::channel_activate : VciOp::channel_deactivate);
}

HRESULT VCIAPI canChannelPeekMessage(HANDLE hCanChn, PCANMSG pCanMsg) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pCanMsg == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return channel_peek(*c, pCanMsg);
}

HRESULT VCIAPI canChannelPostMessage(HANDLE hCanChn, PCANMSG pCanMsg) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pCanMsg == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return channel_post(*c, pCanMsg);
}

HRESULT VCIAPI canChannelWaitRxEvent(HANDLE hCanChn, UINT32 dwMsTimeout) {
  ChannelObj* c = channel_of(hCanChn);
  return c == nullptr ? VCI_E_INVHANDLE : channel_wait_rx(*c, dwMsTimeout);
}

HRESULT VCIAPI canChannelWaitTxEvent(HANDLE hCanChn, UINT32 dwMsTimeout) {
  ChannelObj* c = channel_of(hCanChn);
  return c == nullptr ? VCI_E_INVHANDLE : channel_wait_tx(*c, dwMsTimeout);
}

HRESULT VCIAPI canChannelReadMessage(HANDLE hCanChn, UINT32 dwMsTimeout, PCANMSG pCanMsg) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pCanMsg == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return channel_read(*c, dwMsTimeout, pCanMsg);
}

HRESULT VCIAPI canChannelSendMessage(HANDLE hCanChn, UINT32 dwMsTimeout, PCANMSG pCanMsg) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pCanMsg == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return channel_send(*c, dwMsTimeout, pCanMsg);
}

// ---- several messages at once ----

HRESULT VCIAPI canChannelPeekMsgMult(HANDLE hCanChn, CANMSG aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone) {
  return many(hCanChn, 0, aCanMsg, dwCount, pdwDone, false);
}

HRESULT VCIAPI canChannelPostMsgMult(HANDLE hCanChn, CANMSG aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone) {
  return many(hCanChn, 0, aCanMsg, dwCount, pdwDone, true);
}

HRESULT VCIAPI canChannelReadMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone) {
  return many(hCanChn, dwTimeout, aCanMsg, dwCount, pdwDone, false);
}

HRESULT VCIAPI canChannelSendMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone) {
  return many(hCanChn, dwTimeout, aCanMsg, dwCount, pdwDone, true);
}

HRESULT VCIAPI canChannelPeekMultipleMessages(HANDLE hCanChn, PUINT32 pdwCount, CANMSG aCanMsg[]) {
  return many(hCanChn, 0, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount, false);
}

HRESULT VCIAPI canChannelPostMultipleMessages(HANDLE hCanChn, PUINT32 pdwCount, CANMSG aCanMsg[]) {
  return many(hCanChn, 0, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount, true);
}

HRESULT VCIAPI canChannelReadMultipleMessages(HANDLE hCanChn, UINT32 dwTimeout, PUINT32 pdwCount,
                                              CANMSG aCanMsg[]) {
  return many(hCanChn, dwTimeout, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount,
              false);
}

HRESULT VCIAPI canChannelSendMultipleMessages(HANDLE hCanChn, UINT32 dwTimeout, PUINT32 pdwCount,
                                              CANMSG aCanMsg[]) {
  return many(hCanChn, dwTimeout, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount, true);
}

// ---- cyclic transmit list ----

HRESULT VCIAPI canSchedulerOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanShd) {
  return open_on_device(hDevice, dwCanNo, Kind::scheduler, kV2, false, phCanShd);
}

HRESULT VCIAPI canSchedulerClose(HANDLE hCanShd) { return close_handle(hCanShd, Kind::scheduler); }

HRESULT VCIAPI canSchedulerGetCaps(HANDLE hCanShd, PCANCAPABILITIES pCanCaps) {
  return line_struct(hCanShd, Kind::scheduler, canemu::ipc::kVciCapsOffset, pCanCaps);
}

HRESULT VCIAPI canSchedulerGetStatus(HANDLE hCanShd, PCANSCHEDULERSTATUS pStatus) {
  if (pStatus == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return scheduler_status(hCanShd, &pStatus->bTaskStat, pStatus->abMsgStat);
}

HRESULT VCIAPI canSchedulerActivate(HANDLE hCanShd, BOOL fEnable) {
  return simple_call(hCanShd, Kind::scheduler,
                     fEnable ? VciOp::scheduler_resume : VciOp::scheduler_suspend);
}

HRESULT VCIAPI canSchedulerReset(HANDLE hCanShd) {
  return simple_call(hCanShd, Kind::scheduler, VciOp::scheduler_reset);
}

HRESULT VCIAPI canSchedulerAddMessage(HANDLE hCanShd, PCANCYCLICTXMSG pMessage, PUINT32 pdwIndex) {
  if (pMessage == nullptr) {
    if (pdwIndex != nullptr) {
      *pdwIndex = 0xFFFFFFFFU;
    }
    return VCI_E_INVALIDARG;
  }
  CANCYCLICTXMSG2 m{};
  m.wCycleTime = pMessage->wCycleTime;
  m.bIncrMode = pMessage->bIncrMode;
  m.bByteIndex = pMessage->bByteIndex;
  m.dwMsgId = pMessage->dwMsgId;
  m.uMsgInfo = pMessage->uMsgInfo;
  std::memcpy(m.abData, pMessage->abData, sizeof pMessage->abData);
  return scheduler_add(hCanShd, m, pdwIndex);
}

HRESULT VCIAPI canSchedulerRemMessage(HANDLE hCanShd, UINT32 dwIndex) {
  return simple_call(hCanShd, Kind::scheduler, VciOp::scheduler_remove, {dwIndex});
}

HRESULT VCIAPI canSchedulerStartMessage(HANDLE hCanShd, UINT32 dwIndex, UINT16 wRepeat) {
  return simple_call(hCanShd, Kind::scheduler, VciOp::scheduler_start, {dwIndex, wRepeat});
}

HRESULT VCIAPI canSchedulerStopMessage(HANDLE hCanShd, UINT32 dwIndex) {
  return simple_call(hCanShd, Kind::scheduler, VciOp::scheduler_stop, {dwIndex});
}

}  // extern "C"
