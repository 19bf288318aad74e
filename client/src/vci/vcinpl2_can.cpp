// The CAN half of libvcinpl2: CANMSG2 channels, CANBTP initialization, filter modes and
// filters on v2 channels.
#include "can_api.hpp"
#include "vcinpl2.h"

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

constexpr bool kV2 = true;
}

extern "C" {

// ---- control unit ----

HRESULT VCIAPI canControlOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanCtl) {
  return open_on_device(hDevice, dwCanNo, Kind::control, kV2, false, phCanCtl);
}

HRESULT VCIAPI canControlClose(HANDLE hCanCtl) { return close_handle(hCanCtl, Kind::control); }

HRESULT VCIAPI canControlGetCaps(HANDLE hCanCtl, PCANCAPABILITIES2 pCanCaps) {
  return line_struct(hCanCtl, Kind::control, canemu::ipc::kVciCaps2Offset, pCanCaps);
}

HRESULT VCIAPI canControlGetStatus(HANDLE hCanCtl, PCANLINESTATUS2 pStatus) {
  return line_struct(hCanCtl, Kind::control, canemu::ipc::kVciLine2Offset, pStatus);
}

HRESULT VCIAPI canControlDetectBitrate(HANDLE hCanCtl, UINT8 bOpMode, UINT8 bExMode,
                                       UINT16 wTimeout, UINT32 dwCount, PCANBTP paBtpSDR,
                                       PCANBTP paBtpFDR, PUINT32 pdwIndex) {
  Remote* r = remote_of(hCanCtl, Kind::control);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (dwCount == 0 || dwCount > 64 || paBtpSDR == nullptr || pdwIndex == nullptr) {
    return VCI_E_INVALIDARG;
  }
  CANBTPTABLE table{};
  table.bCount = static_cast<UINT8>(dwCount);
  for (UINT32 i = 0; i < dwCount; ++i) {
    table.asBTP[i].sSdr = paBtpSDR[i];
    if (paBtpFDR != nullptr) {
      table.asBTP[i].sFdr = paBtpFDR[i];
    }
  }
  return Library::get().detect(*r, true, &table, sizeof table, wTimeout, bOpMode, bExMode,
                               *pdwIndex);
}

HRESULT VCIAPI canControlInitialize(HANDLE hCanCtl, UINT8 bOpMode, UINT8 bExMode, UINT8 bSFMode,
                                    UINT8 bEFMode, UINT32 dwSFIds, UINT32 dwEFIds,
                                    PCANBTP pBtpSDR, PCANBTP pBtpFDR) {
  if (pBtpSDR == nullptr) {
    return VCI_E_INVALIDARG;
  }
  CANINITLINE2 init{};
  init.bOpMode = bOpMode;
  init.bExMode = bExMode;
  init.bSFMode = bSFMode;
  init.bEFMode = bEFMode;
  init.dwSFIds = dwSFIds;
  init.dwEFIds = dwEFIds;
  init.sBtpSdr = *pBtpSDR;
  if (pBtpFDR != nullptr) {
    init.sBtpFdr = *pBtpFDR;
  }
  return control_init(hCanCtl, init, kV2);
}

HRESULT VCIAPI canControlReset(HANDLE hCanCtl) {
  return simple_call(hCanCtl, Kind::control, VciOp::control_reset);
}

HRESULT VCIAPI canControlStart(HANDLE hCanCtl, BOOL fStart) {
  return simple_call(hCanCtl, Kind::control,
                     fStart ? VciOp::control_start : VciOp::control_stop);
}

HRESULT VCIAPI canControlGetFilterMode(HANDLE hCanCtl, BOOL fExtend, PUINT8 pbMode) {
  if (pbMode == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return filter_call(hCanCtl, Kind::control, kFilterGetMode, fExtend, 0, 0, 0, pbMode);
}

HRESULT VCIAPI canControlSetFilterMode(HANDLE hCanCtl, BOOL fExtend, UINT8 bMode,
                                       PUINT8 pbPrevMode) {
  return filter_call(hCanCtl, Kind::control, kFilterSetMode, fExtend, bMode, 0, 0, pbPrevMode);
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

HRESULT VCIAPI canChannelGetCaps(HANDLE hCanChn, PCANCAPABILITIES2 pCanCaps) {
  return line_struct(hCanChn, Kind::channel, canemu::ipc::kVciCaps2Offset, pCanCaps);
}

HRESULT VCIAPI canChannelGetStatus(HANDLE hCanChn, PCANCHANSTATUS2 pStatus) {
  return channel_status(hCanChn, canemu::ipc::kVciLine2Offset, pStatus);
}

HRESULT VCIAPI canChannelInitialize(HANDLE hCanChn, UINT16 wRxFifoSize, UINT16 wRxThreshold,
                                    UINT16 wTxFifoSize, UINT16 wTxThreshold, UINT32 dwFilterSize,
                                    UINT8 bFilterMode) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (wRxFifoSize == 0) {
    return VCI_E_INVALIDARG;
  }
  return Library::get().init_channel(*c, wRxFifoSize, wRxThreshold, wTxFifoSize, wTxThreshold,
                                     dwFilterSize, bFilterMode);
}

HRESULT VCIAPI canChannelGetFilterMode(HANDLE hCanChn, BOOL fExtend, PUINT8 pbMode) {
  if (pbMode == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return filter_call(hCanChn, Kind::channel, kFilterGetMode, fExtend, 0, 0, 0, pbMode);
}

HRESULT VCIAPI canChannelSetFilterMode(HANDLE hCanChn, BOOL fExtend, UINT8 bMode,
                                       PUINT8 pbPrevMode) {
  return filter_call(hCanChn, Kind::channel, kFilterSetMode, fExtend, bMode, 0, 0, pbPrevMode);
}

HRESULT VCIAPI canChannelSetAccFilter(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode,
                                      UINT32 dwMask) {
  return filter_call(hCanChn, Kind::channel, kFilterAcceptance, fExtend, 0, dwCode, dwMask,
                     nullptr);
}

HRESULT VCIAPI canChannelAddFilterIds(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode,
                                      UINT32 dwMask) {
  return filter_call(hCanChn, Kind::channel, kFilterAddIds, fExtend, 0, dwCode, dwMask, nullptr);
}

HRESULT VCIAPI canChannelRemFilterIds(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode,
                                      UINT32 dwMask) {
  return filter_call(hCanChn, Kind::channel, kFilterRemoveIds, fExtend, 0, dwCode, dwMask,
                     nullptr);
}

HRESULT VCIAPI canChannelActivate(HANDLE hCanChn, BOOL fEnable) {
  return simple_call(hCanChn, Kind::channel,
                     fEnable ? VciOp::channel_activate : VciOp::channel_deactivate);
}

HRESULT VCIAPI canChannelPeekMessage(HANDLE hCanChn, PCANMSG2 pCanMsg) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pCanMsg == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return channel_peek(*c, pCanMsg);
}

HRESULT VCIAPI canChannelPostMessage(HANDLE hCanChn, PCANMSG2 pCanMsg) {
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

HRESULT VCIAPI canChannelReadMessage(HANDLE hCanChn, UINT32 dwMsTimeout, PCANMSG2 pCanMsg) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pCanMsg == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return channel_read(*c, dwMsTimeout, pCanMsg);
}

HRESULT VCIAPI canChannelSendMessage(HANDLE hCanChn, UINT32 dwMsTimeout, PCANMSG2 pCanMsg) {
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

HRESULT VCIAPI canChannelPeekMsgMult(HANDLE hCanChn, CANMSG2 aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone) {
  return many(hCanChn, 0, aCanMsg, dwCount, pdwDone, false);
}

HRESULT VCIAPI canChannelPostMsgMult(HANDLE hCanChn, CANMSG2 aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone) {
  return many(hCanChn, 0, aCanMsg, dwCount, pdwDone, true);
}

HRESULT VCIAPI canChannelReadMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG2 aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone) {
  return many(hCanChn, dwTimeout, aCanMsg, dwCount, pdwDone, false);
}

HRESULT VCIAPI canChannelSendMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG2 aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone) {
  return many(hCanChn, dwTimeout, aCanMsg, dwCount, pdwDone, true);
}

// ---- cyclic transmit list ----

HRESULT VCIAPI canSchedulerOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanShd) {
  return open_on_device(hDevice, dwCanNo, Kind::scheduler, kV2, false, phCanShd);
}

HRESULT VCIAPI canSchedulerClose(HANDLE hCanShd) { return close_handle(hCanShd, Kind::scheduler); }

HRESULT VCIAPI canSchedulerGetCaps(HANDLE hCanShd, PCANCAPABILITIES2 pCanCaps) {
  return line_struct(hCanShd, Kind::scheduler, canemu::ipc::kVciCaps2Offset, pCanCaps);
}

HRESULT VCIAPI canSchedulerGetStatus(HANDLE hCanShd, PCANSCHEDULERSTATUS2 pStatus) {
  if (pStatus == nullptr) {
    return VCI_E_INVALIDARG;
  }
  if (HRESULT hr = line_struct(hCanShd, Kind::scheduler, canemu::ipc::kVciLine2Offset,
                              &pStatus->sLineStatus);
      hr != VCI_OK) {
    return hr;
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

HRESULT VCIAPI canSchedulerAddMessage(HANDLE hCanShd, PCANCYCLICTXMSG2 pMessage,
                                      PUINT32 pdwIndex) {
  if (pMessage == nullptr) {
    if (pdwIndex != nullptr) {
      *pdwIndex = 0xFFFFFFFFU;
    }
    return VCI_E_INVALIDARG;
  }
  return scheduler_add(hCanShd, *pMessage, pdwIndex);
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
