/*
 * The VCI C++ API for Linux (libvciapi.so): the interfaces of IXXAT's VCI C++ SDK with their
 * names, methods, argument types and results, on canemud. Objects are reference counted in the
 * COM manner (QueryInterface, AddRef, Release; no class factories); every failing call that
 * returns an interface sets it to NULL. Interface and class identifiers are canemu's own
 * values (programs name them, never spell them out).
 *
 * Windows events: CreateEvent and friends come from canemu_events.h (included here).
 */
#ifndef VCISDK_H
#define VCISDK_H

#include "canemu_events.h"
#include "cantype.h"
#include "lintype.h"
#include "vcierr.h"
#include "vcitype.h"

#ifndef __cplusplus
#error "vcisdk.h is the VCI C++ API; C programs use vcinpl.h or vcinpl2.h"
#endif

typedef GUID IID;
typedef GUID CLSID;
typedef const GUID& REFIID;
typedef const GUID& REFCLSID;
typedef UINT32 ULONG;

/* How the library marks the identifiers it exports; nothing for programs. */
#ifndef VCIAPI_DATA
#define VCIAPI_DATA
#endif

extern "C" {
/* The interface and class identifiers, with the values of IXXAT's VCI 4 SDK (docs/vci.md). */
extern VCIAPI_DATA const IID IID_IUnknown;
extern VCIAPI_DATA const IID IID_IVciDeviceManager;
extern VCIAPI_DATA const IID IID_IVciEnumDevice;
extern VCIAPI_DATA const IID IID_IVciDevice;
extern VCIAPI_DATA const IID IID_IBalObject;
extern VCIAPI_DATA const IID IID_ICanSocket;
extern VCIAPI_DATA const IID IID_ICanSocket2;
extern VCIAPI_DATA const IID IID_ICanControl;
extern VCIAPI_DATA const IID IID_ICanControl2;
extern VCIAPI_DATA const IID IID_ICanChannel;
extern VCIAPI_DATA const IID IID_ICanChannel2;
extern VCIAPI_DATA const IID IID_ICanScheduler;
extern VCIAPI_DATA const IID IID_ICanScheduler2;
extern VCIAPI_DATA const IID IID_IFifoReader;
extern VCIAPI_DATA const IID IID_IFifoWriter;
extern VCIAPI_DATA const IID IID_IVciFifo;
extern VCIAPI_DATA const IID IID_IVciFifo2;
extern VCIAPI_DATA const IID IID_ILinSocket;
extern VCIAPI_DATA const IID IID_ILinControl;
extern VCIAPI_DATA const IID IID_ILinMonitor;
extern VCIAPI_DATA const CLSID CLSID_VCIBAL;
}

struct IUnknown {
  virtual HRESULT QueryInterface(REFIID riid, PVOID* ppv) = 0;
  virtual ULONG AddRef() = 0;
  virtual ULONG Release() = 0;

 protected:
  ~IUnknown() = default;
};

struct IVciFifo : IUnknown {
  virtual HRESULT GetCapacity(PUINT16 pwCapacity) = 0;
  virtual HRESULT GetEntrySize(PUINT16 pwSize) = 0;
  virtual HRESULT GetFreeCount(PUINT16 pwCount) = 0;
  virtual HRESULT GetFillCount(PUINT16 pwCount) = 0;
  virtual HRESULT GetFillLevel(PUINT16 pwLevel) = 0;
};

struct IVciFifo2 : IVciFifo {
  virtual HRESULT Reset() = 0;
};

struct IFifoReader : IUnknown {
  virtual HRESULT Lock() = 0;
  virtual HRESULT Unlock() = 0;
  virtual HRESULT AssignEvent(HANDLE hEvent) = 0;
  virtual HRESULT SetThreshold(UINT16 wThreshold) = 0;
  virtual HRESULT GetThreshold(PUINT16 pwThreshold) = 0;
  virtual HRESULT GetCapacity(PUINT16 pwCapacity) = 0;
  virtual HRESULT GetEntrySize(PUINT16 pwSize) = 0;
  virtual HRESULT GetFillCount(PUINT16 pwCount) = 0;
  virtual HRESULT GetFreeCount(PUINT16 pwCount) = 0;
  virtual HRESULT GetDataEntry(PVOID pvData) = 0;
  virtual HRESULT AcquireRead(PVOID* ppvData, PUINT16 pwCount) = 0;
  virtual HRESULT ReleaseRead(UINT16 wCount) = 0;
};

struct IFifoWriter : IUnknown {
  virtual HRESULT Lock() = 0;
  virtual HRESULT Unlock() = 0;
  virtual HRESULT AssignEvent(HANDLE hEvent) = 0;
  virtual HRESULT SetThreshold(UINT16 wThreshold) = 0;
  virtual HRESULT GetThreshold(PUINT16 pwThreshold) = 0;
  virtual HRESULT GetCapacity(PUINT16 pwCapacity) = 0;
  virtual HRESULT GetEntrySize(PUINT16 pwSize) = 0;
  virtual HRESULT GetFillCount(PUINT16 pwCount) = 0;
  virtual HRESULT GetFreeCount(PUINT16 pwCount) = 0;
  virtual HRESULT PutDataEntry(PVOID pvData) = 0;
  virtual HRESULT AcquireWrite(PVOID* ppvData, PUINT16 pwCount) = 0;
  virtual HRESULT ReleaseWrite(UINT16 wCount) = 0;
};

struct IVciEnumDevice : IUnknown {
  virtual HRESULT Next(UINT32 dwNumElem, PVCIDEVICEINFO paDevInfo, PUINT32 pdwFetched) = 0;
  virtual HRESULT Skip(UINT32 dwNumElem) = 0;
  virtual HRESULT Reset() = 0;
  virtual HRESULT AssignEvent(HANDLE hEvent) = 0;
};

struct IVciDevice : IUnknown {
  virtual HRESULT GetDeviceInfo(PVCIDEVICEINFO pInfo) = 0;
  virtual HRESULT GetDeviceCaps(PVCIDEVICECAPS pCaps) = 0;
  virtual HRESULT OpenComponent(REFCLSID rclsid, REFIID riid, PVOID* ppv) = 0;
};

struct IVciDeviceManager : IUnknown {
  virtual HRESULT EnumDevices(IVciEnumDevice** ppEnum) = 0;
  virtual HRESULT OpenDevice(REFVCIID rVciid, IVciDevice** ppDevice) = 0;
};

struct IBalObject : IUnknown {
  virtual HRESULT GetFeatures(PBALFEATURES pFeatures) = 0;
  virtual HRESULT OpenSocket(UINT32 dwBusNo, REFIID riid, PVOID* ppv) = 0;
};

struct ICanControl : IUnknown {
  virtual HRESULT DetectBaud(UINT16 wTimeoutMs, PCANBTRTABLE pBtrTable) = 0;
  virtual HRESULT InitLine(PCANINITLINE pInitParam) = 0;
  virtual HRESULT ResetLine() = 0;
  virtual HRESULT StartLine() = 0;
  virtual HRESULT StopLine() = 0;
  virtual HRESULT GetLineStatus(PCANLINESTATUS pStatus) = 0;
  virtual HRESULT SetAccFilter(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
  virtual HRESULT AddFilterIds(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
  virtual HRESULT RemFilterIds(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
};

struct ICanControl2 : IUnknown {
  virtual HRESULT DetectBaud(UINT8 bOpMode, UINT8 bExMode, UINT16 wTimeoutMs,
                             PCANBTPTABLE pBtpTable) = 0;
  virtual HRESULT InitLine(PCANINITLINE2 pInitParam) = 0;
  virtual HRESULT ResetLine() = 0;
  virtual HRESULT StartLine() = 0;
  virtual HRESULT StopLine() = 0;
  virtual HRESULT GetLineStatus(PCANLINESTATUS2 pStatus) = 0;
  virtual HRESULT GetFilterMode(UINT8 bSelect, PUINT8 pbMode) = 0;
  virtual HRESULT SetFilterMode(UINT8 bSelect, UINT8 bNewMode, PUINT8 pbPrevMode) = 0;
  virtual HRESULT SetAccFilter(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
  virtual HRESULT AddFilterIds(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
  virtual HRESULT RemFilterIds(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
};
typedef ICanControl* PCANCONTROL;
typedef ICanControl2* PCANCONTROL2;

struct ICanChannel : IUnknown {
  virtual HRESULT Initialize(UINT16 wRxFifoSize, UINT16 wTxFifoSize) = 0;
  virtual HRESULT GetReader(IFifoReader** ppReader) = 0;
  virtual HRESULT GetWriter(IFifoWriter** ppWriter) = 0;
  virtual HRESULT GetStatus(PCANCHANSTATUS pStatus) = 0;
  virtual HRESULT Activate() = 0;
  virtual HRESULT Deactivate() = 0;
};

struct ICanChannel2 : IUnknown {
  virtual HRESULT Initialize(UINT32 dwRxFifoSize, UINT32 dwTxFifoSize, UINT32 dwFilterSize,
                             UINT8 bFilterMode) = 0;
  virtual HRESULT GetReader(IFifoReader** ppReader) = 0;
  virtual HRESULT GetWriter(IFifoWriter** ppWriter) = 0;
  virtual HRESULT GetStatus(PCANCHANSTATUS2 pStatus) = 0;
  virtual HRESULT GetControl(PCANCONTROL2* ppControl) = 0;
  virtual HRESULT GetFilterMode(UINT8 bSelect, PUINT8 pbMode) = 0;
  virtual HRESULT SetFilterMode(UINT8 bSelect, UINT8 bNewMode, PUINT8 pbPrevMode) = 0;
  virtual HRESULT SetAccFilter(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
  virtual HRESULT AddFilterIds(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
  virtual HRESULT RemFilterIds(UINT8 bSelect, UINT32 dwCode, UINT32 dwMask) = 0;
  virtual HRESULT Activate() = 0;
  virtual HRESULT Deactivate() = 0;
};
typedef ICanChannel* PCANCHANNEL;
typedef ICanChannel2* PCANCHANNEL2;

struct ICanSocket : IUnknown {
  virtual HRESULT GetSocketInfo(PBALSOCKETINFO pSocketInfo) = 0;
  virtual HRESULT GetCapabilities(PCANCAPABILITIES pCanCaps) = 0;
  virtual HRESULT GetLineStatus(PCANLINESTATUS pLineStatus) = 0;
  virtual HRESULT CreateChannel(BOOL fExclusive, PCANCHANNEL* ppChannel) = 0;
};

struct ICanSocket2 : IUnknown {
  virtual HRESULT GetSocketInfo(PBALSOCKETINFO pSocketInfo) = 0;
  virtual HRESULT GetCapabilities(PCANCAPABILITIES2 pCanCaps) = 0;
  virtual HRESULT GetLineStatus(PCANLINESTATUS2 pLineStatus) = 0;
  virtual HRESULT CreateChannel(BOOL fExclusive, PCANCHANNEL2* ppChannel) = 0;
};

struct ICanScheduler : IUnknown {
  virtual HRESULT GetStatus(PCANSCHEDULERSTATUS pStatus) = 0;
  virtual HRESULT Resume() = 0;
  virtual HRESULT Suspend() = 0;
  virtual HRESULT Reset() = 0;
  virtual HRESULT AddMessage(PCANCYCLICTXMSG pMessage, PUINT32 pdwIndex) = 0;
  virtual HRESULT RemMessage(UINT32 dwIndex) = 0;
  virtual HRESULT StartMessage(UINT32 dwIndex, UINT16 wRepeat) = 0;
  virtual HRESULT StopMessage(UINT32 dwIndex) = 0;
};

struct ICanScheduler2 : IUnknown {
  virtual HRESULT GetStatus(PCANSCHEDULERSTATUS2 pStatus) = 0;
  virtual HRESULT Resume() = 0;
  virtual HRESULT Suspend() = 0;
  virtual HRESULT Reset() = 0;
  virtual HRESULT AddMessage(PCANCYCLICTXMSG2 pMessage, PUINT32 pdwIndex) = 0;
  virtual HRESULT RemMessage(UINT32 dwIndex) = 0;
  virtual HRESULT StartMessage(UINT32 dwIndex, UINT16 wRepeat) = 0;
  virtual HRESULT StopMessage(UINT32 dwIndex) = 0;
};

/* LIN (VCI C++ guide 5.3, 7.7): IBalObject::OpenSocket with IID_ILinSocket or IID_ILinControl
 * on a LIN controller's bus number (after the adapter's CAN controllers). A socket creates
 * monitors; a monitor's reader gives LINMSGs. bPid carries the 6-bit identifier (0..63). */
struct ILinControl : IUnknown {
  /* Resets first; bOpMode LIN_OPMODE_MASTER / LIN_OPMODE_ERRORS, wBitrate 1000..20000 or
   * LIN_BITRATE_AUTO (slave). */
  virtual HRESULT InitLine(PLININITLINE pInitParam) = 0;
  /* Stops the controller and empties the response table. */
  virtual HRESULT ResetLine() = 0;
  virtual HRESULT StartLine() = 0;
  virtual HRESULT StopLine() = 0;
  virtual HRESULT GetLineStatus(PLINLINESTATUS pStatus) = 0;
  /* fSend FALSE: a response table entry; TRUE: transmit (never waits; VCI_E_TXQUEUE_FULL while
   * the previous one is not done). */
  virtual HRESULT WriteMessage(BOOL fSend, PLINMSG pLinMsg) = 0;
};

struct ILinMonitor : IUnknown {
  /* A receive FIFO of at least wFifoSize LINMSGs (0: VCI_E_INVALIDARG). */
  virtual HRESULT Initialize(UINT16 wFifoSize) = 0;
  virtual HRESULT Activate() = 0;
  virtual HRESULT Deactivate() = 0;
  /* After Initialize; one reader at a time. */
  virtual HRESULT GetReader(IFifoReader** ppReader) = 0;
  virtual HRESULT GetStatus(PLINMONITORSTATUS pStatus) = 0;
};
typedef ILinMonitor* PLINMONITOR;

struct ILinSocket : IUnknown {
  virtual HRESULT GetSocketInfo(PBALSOCKETINFO pSocketInfo) = 0;
  virtual HRESULT GetCapabilities(PLINCAPABILITIES pLinCaps) = 0;
  virtual HRESULT GetLineStatus(PLINLINESTATUS pLineStatus) = 0;
  /* fExclusive TRUE: only when no other monitor exists, and none can be created while it
   * lives; VCI_E_ACCESSDENIED otherwise. */
  virtual HRESULT CreateMonitor(BOOL fExclusive, PLINMONITOR* ppMonitor) = 0;
};

extern "C" {
HRESULT VCIAPI VciInitialize(void);
/* The text for hrError, NUL-terminated, in at most dwLength characters. */
HRESULT VCIAPI VciFormatError(HRESULT hrError, PTCHAR pszError, UINT32 dwLength);
HRESULT VCIAPI VciGetVersion(PVCIVERSIONINFO pVersionInfo);
HRESULT VCIAPI VciCreateLuid(PVCIID pVciid);
/* 16 hexadecimal digits; the buffer holds at least 17 characters. */
HRESULT VCIAPI VciLuidToChar(REFVCIID rVciid, PCHAR pszLuid, LONG cbSize);
HRESULT VCIAPI VciCharToLuid(PCHAR pszLuid, PVCIID pVciid);
/* The registry form {8-4-4-4-12}; the buffer holds at least 39 characters. */
HRESULT VCIAPI VciGuidToChar(REFGUID rGuid, PCHAR pszGuid, LONG cbSize);
HRESULT VCIAPI VciCharToGuid(PCHAR pszGuid, PGUID pGuid);
HRESULT VCIAPI VciGetDeviceManager(IVciDeviceManager** ppDevMgr);
HRESULT VCIAPI VciQueryDeviceByHwid(REFGUID rHwid, IVciDevice** ppDevice);
HRESULT VCIAPI VciQueryDeviceByClass(REFGUID rClass, UINT32 dwInst, IVciDevice** ppDevice);
/* A FIFO of at least wCapacity elements of wElementSize bytes; its VCIID lets this process
 * reach it again with VciAccessFifo. */
HRESULT VCIAPI VciCreateFifo(PVCIID pResid, UINT16 wCapacity, UINT16 wElementSize, REFIID riid,
                             PVOID* ppv);
HRESULT VCIAPI VciAccessFifo(REFVCIID rResid, REFIID riid, PVOID* ppv);
}

#endif /* VCISDK_H */
