// The CAN half of libvcinpl: CANMSG channels, BTR0/BTR1 initialization.
#include "can_api.hpp"
#include "vcinpl.h"

using namespace canemu::client::vci;
using canemu::ipc::VciOp;
using Kind = Object::Kind;

#define CANEMU_VCI_V2 false
#define CANEMU_VCI_MSG CANMSG
#define CANEMU_VCI_PMSG PCANMSG
#define CANEMU_VCI_PCAPS PCANCAPABILITIES
#define CANEMU_VCI_CAPS_OFFSET canemu::ipc::kVciCapsOffset
#define CANEMU_VCI_PLINESTATUS PCANLINESTATUS
#define CANEMU_VCI_LINE_OFFSET canemu::ipc::kVciLineOffset
#define CANEMU_VCI_PCHANSTATUS PCANCHANSTATUS
#include "can_api_shared.inc"

extern "C" {

// ---- version ----

HRESULT VCIAPI vciGetVersionEx(PUINT32 pdwMajorVersion, PUINT32 pdwMinorVersion,
                               PUINT32 pdwRevNumber, PUINT32 pdwBuildNumber) {
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

HRESULT VCIAPI vciGetVersion(PUINT32 pdwMajorVersion, PUINT32 pdwMinorVersion) {
  UINT32 revision = 0;
  UINT32 build = 0;
  return vciGetVersionEx(pdwMajorVersion, pdwMinorVersion, &revision, &build);
}

// ---- control unit ----

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
  const HRESULT hr = req::detect(*r, false, &table, sizeof table, wTimeout, 0, 0, index);
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

// ---- channels ----

HRESULT VCIAPI canChannelInitialize(HANDLE hCanChn, UINT16 wRxFifoSize, UINT16 wRxThreshold,
                                    UINT16 wTxFifoSize, UINT16 wTxThreshold) {
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (wRxFifoSize == 0) {
    return VCI_E_INVALIDARG;
  }
  return req::init_channel(*c, wRxFifoSize, wRxThreshold, wTxFifoSize, wTxThreshold, 0,
                           CAN_FILTER_PASS);
}

// ---- several messages at once ----

HRESULT VCIAPI canChannelPeekMultipleMessages(HANDLE hCanChn, PUINT32 pdwCount, CANMSG aCanMsg[]) {
  return many(hCanChn, 0, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount, false);
}

HRESULT VCIAPI canChannelPostMultipleMessages(HANDLE hCanChn, PUINT32 pdwCount, CANMSG aCanMsg[]) {
  return many(hCanChn, 0, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount, true);
}

HRESULT VCIAPI canChannelReadMultipleMessages(HANDLE hCanChn, UINT32 dwTimeout, PUINT32 pdwCount,
                                              CANMSG aCanMsg[]) {
  return many(hCanChn, dwTimeout, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount, false);
}

HRESULT VCIAPI canChannelSendMultipleMessages(HANDLE hCanChn, UINT32 dwTimeout, PUINT32 pdwCount,
                                              CANMSG aCanMsg[]) {
  return many(hCanChn, dwTimeout, aCanMsg, pdwCount != nullptr ? *pdwCount : 0, pdwCount, true);
}

// ---- cyclic transmit list ----

HRESULT VCIAPI canSchedulerGetStatus(HANDLE hCanShd, PCANSCHEDULERSTATUS pStatus) {
  if (pStatus == nullptr) {
    return VCI_E_INVALIDARG;
  }
  return scheduler_status(hCanShd, &pStatus->bTaskStat, pStatus->abMsgStat);
}

HRESULT VCIAPI canSchedulerAddMessage(HANDLE hCanShd, PCANCYCLICTXMSG pMessage, PUINT32 pdwIndex) {
  if (pMessage == nullptr) {
    if (pdwIndex != nullptr) {
      *pdwIndex = 0xFFFFFFFFU;
    }
    return VCI_E_INVALIDARG;
  }
  return scheduler_add(hCanShd, to_cyclic2(*pMessage), pdwIndex);
}

}  // extern "C"
