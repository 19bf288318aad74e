// The CAN half of libvcinpl2: CANMSG2 channels, CANBTP initialization, filter modes and
// filters on v2 channels.
#include "can_api.hpp"
#include "vcinpl2.h"

using namespace canemu::client::vci;
using canemu::ipc::VciOp;
using Kind = Object::Kind;

#define CANEMU_VCI_V2 true
#define CANEMU_VCI_MSG CANMSG2
#define CANEMU_VCI_PMSG PCANMSG2
#define CANEMU_VCI_PCAPS PCANCAPABILITIES2
#define CANEMU_VCI_CAPS_OFFSET canemu::ipc::kVciCaps2Offset
#define CANEMU_VCI_PLINESTATUS PCANLINESTATUS2
#define CANEMU_VCI_LINE_OFFSET canemu::ipc::kVciLine2Offset
#define CANEMU_VCI_PCHANSTATUS PCANCHANSTATUS2
#include "can_api_shared.inc"

extern "C" {

// ---- version ----

HRESULT VCIAPI vciGetVersion(PUINT32 pdwMajorVersion, PUINT32 pdwMinorVersion, PUINT32 pdwRevNumber,
                             PUINT32 pdwBuildNumber) {
  if (pdwMajorVersion == nullptr || pdwMinorVersion == nullptr || pdwRevNumber == nullptr ||
      pdwBuildNumber == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *pdwMajorVersion = kVciMajorVersion;
  *pdwMinorVersion = kVciMinorVersion;
  *pdwRevNumber = kVciRevisionNumber;
  *pdwBuildNumber = vci_build_number();
  return VCI_OK;
}

// ---- control unit ----

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
  return req::detect(*r, true, &table, sizeof table, wTimeout, bOpMode, bExMode, *pdwIndex);
}

HRESULT VCIAPI canControlInitialize(HANDLE hCanCtl, UINT8 bOpMode, UINT8 bExMode, UINT8 bSFMode,
                                    UINT8 bEFMode, UINT32 dwSFIds, UINT32 dwEFIds, PCANBTP pBtpSDR,
                                    PCANBTP pBtpFDR) {
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

HRESULT VCIAPI canControlGetFilterMode(HANDLE hCanCtl, BOOL fExtend, PUINT8 pbMode) {
  if (pbMode == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return filter_call(hCanCtl, Kind::control, req::kFilterGetMode, fExtend, 0, 0, 0, pbMode);
}

HRESULT VCIAPI canControlSetFilterMode(HANDLE hCanCtl, BOOL fExtend, UINT8 bMode,
                                       PUINT8 pbPrevMode) {
  return filter_call(hCanCtl, Kind::control, req::kFilterSetMode, fExtend, bMode, 0, 0, pbPrevMode);
}

// ---- channels ----

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
  return req::init_channel(*c, wRxFifoSize, wRxThreshold, wTxFifoSize, wTxThreshold, dwFilterSize,
                           bFilterMode);
}

HRESULT VCIAPI canChannelGetControl(HANDLE hCanChn, PHANDLE phCanCtl) {
  return control_of_line(hCanChn, Kind::channel, kV2, phCanCtl);
}

HRESULT VCIAPI canChannelGetFilterMode(HANDLE hCanChn, BOOL fExtend, PUINT8 pbMode) {
  if (pbMode == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return filter_call(hCanChn, Kind::channel, req::kFilterGetMode, fExtend, 0, 0, 0, pbMode);
}

HRESULT VCIAPI canChannelSetFilterMode(HANDLE hCanChn, BOOL fExtend, UINT8 bMode,
                                       PUINT8 pbPrevMode) {
  return filter_call(hCanChn, Kind::channel, req::kFilterSetMode, fExtend, bMode, 0, 0, pbPrevMode);
}

HRESULT VCIAPI canChannelSetAccFilter(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode, UINT32 dwMask) {
  return filter_call(hCanChn, Kind::channel, req::kFilterAcceptance, fExtend, 0, dwCode, dwMask,
                     nullptr);
}

HRESULT VCIAPI canChannelAddFilterIds(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode, UINT32 dwMask) {
  return filter_call(hCanChn, Kind::channel, req::kFilterAddIds, fExtend, 0, dwCode, dwMask,
                     nullptr);
}

HRESULT VCIAPI canChannelRemFilterIds(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode, UINT32 dwMask) {
  return filter_call(hCanChn, Kind::channel, req::kFilterRemoveIds, fExtend, 0, dwCode, dwMask,
                     nullptr);
}

// ---- cyclic transmit list ----

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

HRESULT VCIAPI canSchedulerGetControl(HANDLE hCanShd, PHANDLE phCanCtl) {
  return control_of_line(hCanShd, Kind::scheduler, kV2, phCanCtl);
}

HRESULT VCIAPI canSchedulerAddMessage(HANDLE hCanShd, PCANCYCLICTXMSG2 pMessage, PUINT32 pdwIndex) {
  if (pMessage == nullptr) {
    if (pdwIndex != nullptr) {
      *pdwIndex = 0xFFFFFFFFU;
    }
    return VCI_E_INVALIDARG;
  }
  return scheduler_add(hCanShd, *pMessage, pdwIndex);
}

}  // extern "C"
