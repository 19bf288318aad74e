/*
 * vcinpl2.h - canemu's declarations of the VCI 4 "2" C API (libvcinpl2.so).
 *
 * libvcinpl2.so is meant to be a drop-in for IXXAT's CAN FD capable native library
 * (vcinpl2.dll on Windows): same exported names, argument order, argument and structure
 * types and HRESULT codes. Compared with the classic API (vcinpl.h) it moves to CANMSG2
 * (64 data bytes), initialises the controller with CANBTP bit timing for the nominal (SDR)
 * and fast data (FDR) phases plus extended modes and 11/29-bit filter lists, and reports
 * CANCAPABILITIES2 / CANLINESTATUS2 / CANCHANSTATUS2 / CANSCHEDULERSTATUS2; channels get
 * their own filters. The function names are the classic ones with other argument types, so
 * a translation unit includes one of vcinpl.h / vcinpl2.h, never both.
 *
 * Types, structures and constants come from vcitype.h, vcierr.h and cantype.h. VCIAPI is
 * empty on Linux. Every function returns VCI_OK (0) on success and a VCI_E_* code
 * otherwise, except the vciFormatError family (void). Error-frame codes keep cantype.h's
 * VCI 4 numbering here (CAN_ERROR_OTHER is 8, CAN_ERROR_DLC 7, CAN_ERROR_FDB 5).
 *
 * Where the prototypes were confirmed: notes/vci-c-api-research.md. Timeouts are in
 * milliseconds; 0 means "test and return at once", INFINITE (0xFFFFFFFF) "wait forever".
 */
#ifndef CANEMU_VCI_VCINPL2_H
#define CANEMU_VCI_VCINPL2_H

#include "cantype.h"
#include "vcierr.h"
#include "vcinpl_general.h" /* error texts, identifiers, events */
#include "vcinpl_lin.h"     /* the LIN functions */
#include "vcitype.h"

#ifndef VCIAPI
#define VCIAPI
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- library ------------------------------------------------------------------------- */

/* Prepares the library for use (idempotent); VCI_OK, or an error if the emulator daemon
 * cannot be reached. */
HRESULT VCIAPI vciInitialize(void);

/* The VCI version these libraries implement, 4.0, and canemu's own as the build number
 * (major * 10000 + minor * 100 + patch); the revision is 0. VCI_OK, VCI_E_INVALIDARG when a
 * pointer is NULL. */
HRESULT VCIAPI vciGetVersion(PUINT32 pdwMajorVersion, PUINT32 pdwMinorVersion, PUINT32 pdwRevNumber,
                             PUINT32 pdwBuildNumber);

/* Error texts, identifiers and events: vcinpl_general.h. */

/* ---- device enumeration -------------------------------------------------------------- */

/* Opens a device enumerator and stores its handle in *phEnum; VCI_OK, VCI_E_INVPOINTER. */
HRESULT VCIAPI vciEnumDeviceOpen(PHANDLE phEnum);

/* Closes a device enumerator; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciEnumDeviceClose(HANDLE hEnum);

/* Fills *pInfo with the next device of the enumeration; VCI_OK, VCI_E_NO_MORE_ITEMS at the
 * end, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciEnumDeviceNext(HANDLE hEnum, PVCIDEVICEINFO pInfo);

/* Restarts the enumeration at the first device; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciEnumDeviceReset(HANDLE hEnum);

/* Waits until the device list changes or dwTimeout ms pass; VCI_OK on a change,
 * VCI_E_TIMEOUT. */
HRESULT VCIAPI vciEnumDeviceWaitEvent(HANDLE hEnum, UINT32 dwTimeout);

/* Looks up the device whose unique hardware id is rHwid and stores its VCI id;
 * VCI_OK, an error (not VCI_OK) when no device has that id. */
HRESULT VCIAPI vciFindDeviceByHwid(REFGUID rHwid, PVCIID pVciid);

/* Looks up instance dwInst (0 = first) of device class rClass and stores its VCI id;
 * VCI_OK, or an error when there is no such instance. */
HRESULT VCIAPI vciFindDeviceByClass(REFGUID rClass, UINT32 dwInst, PVCIID pVciid);

/* There is no device selection dialog on Linux: the "choice" is the device named by the
 * environment variable CANEMU_VCI_DEVICE (its name in canemud's configuration, or its VCIID
 * as vciLuidToChar writes it) when that is set, otherwise the first device of the
 * enumeration. Its VCI id goes to *pVciid; VCI_OK, VCI_E_INVALIDARG for NULL,
 * VCI_E_NO_MORE_ITEMS when there is no device or none of that name (vciFormatError says
 * which), VCI_E_DISCONNECTED without canemud. hwndParent is ignored. */
HRESULT VCIAPI vciSelectDeviceDlg(HWND hwndParent, PVCIID pVciid);

/* ---- device -------------------------------------------------------------------------- */

/* Opens the device with VCI id rVciid and stores its handle in *phDevice; VCI_OK, an
 * error for an unknown id. */
HRESULT VCIAPI vciDeviceOpen(REFVCIID rVciid, PHANDLE phDevice);

/* vciSelectDeviceDlg's choice, opened as vciDeviceOpen opens it; VCI_OK and the codes of
 * both. */
HRESULT VCIAPI vciDeviceOpenDlg(HWND hwndParent, PHANDLE phDevice);

/* Closes a device handle (objects opened on it stay usable until closed); VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI vciDeviceClose(HANDLE hDevice);

/* Fills *pInfo with the device's identity and versions; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciDeviceGetInfo(HANDLE hDevice, PVCIDEVICEINFO pInfo);

/* Fills *pCaps with the device's bus controllers; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciDeviceGetCaps(HANDLE hDevice, PVCIDEVICECAPS pCaps);

/* ---- CAN controller ------------------------------------------------------------------ */

/* Opens the control unit of CAN line dwCanNo of the device; VCI_OK, VCI_E_ACCESSDENIED when
 * another client holds it, an error for a line that does not exist. */
HRESULT VCIAPI canControlOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanCtl);

/* Closes the control unit (the line keeps running if it was started); VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlClose(HANDLE hCanCtl);

/* Fills *pCanCaps with the controller's capabilities (clocks, divisors, timing ranges,
 * CAN_FEATURE_* flags); VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlGetCaps(HANDLE hCanCtl, PCANCAPABILITIES2 pCanCaps);

/* Fills *pStatus with modes, bus load, current SDR/FDR timing and CAN_STATUS_* flags;
 * VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlGetStatus(HANDLE hCanCtl, PCANLINESTATUS2 pStatus);

/* Tries the dwCount SDR/FDR timing pairs (arrays paBtpSDR/paBtpFDR) in the given modes
 * until one sees valid traffic within wTimeout ms and stores its index in *pdwIndex;
 * VCI_OK, VCI_E_TIMEOUT when none matched. */
HRESULT VCIAPI canControlDetectBitrate(HANDLE hCanCtl, UINT8 bOpMode, UINT8 bExMode,
                                       UINT16 wTimeout, UINT32 dwCount, PCANBTP paBtpSDR,
                                       PCANBTP paBtpFDR, PUINT32 pdwIndex);

/* Resets the controller and sets operating mode (CAN_OPMODE_*), extended mode
 * (CAN_EXMODE_*), the mode (CAN_FILTER_*) and size of the line's 11/29-bit filter lists
 * and the SDR/FDR bit timing; the line stays stopped; VCI_OK, VCI_E_INVALIDARG for bad
 * timing or modes, VCI_E_ACCESSDENIED (python-can treats that one as success). */
HRESULT VCIAPI canControlInitialize(HANDLE hCanCtl, UINT8 bOpMode, UINT8 bExMode, UINT8 bSFMode,
                                    UINT8 bEFMode, UINT32 dwSFIds, UINT32 dwEFIds, PCANBTP pBtpSDR,
                                    PCANBTP pBtpFDR);

/* Stops the line and returns the controller to its uninitialized state; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlReset(HANDLE hCanCtl);

/* Starts (fStart TRUE) or stops the line; VCI_OK, VCI_E_INVALID_STATE when not initialized. */
HRESULT VCIAPI canControlStart(HANDLE hCanCtl, BOOL fStart);

/* Stores the current mode (CAN_FILTER_*) of the line's 11-bit (fExtend FALSE) or 29-bit
 * filter in *pbMode; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlGetFilterMode(HANDLE hCanCtl, BOOL fExtend, PUINT8 pbMode);

/* Sets the mode of the line's 11- or 29-bit filter and stores the previous one in *pbPrev;
 * VCI_OK, VCI_E_INVALIDARG, VCI_E_INVALID_STATE while the line runs. */
HRESULT VCIAPI canControlSetFilterMode(HANDLE hCanCtl, BOOL fExtend, UINT8 bMode, PUINT8 pbPrev);

/* Sets the acceptance code and mask of the line's 11- or 29-bit filter (id in bits 1..,
 * RTR in bit 0); VCI_OK, VCI_E_INVALID_STATE while the line runs. */
HRESULT VCIAPI canControlSetAccFilter(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* Adds the ids selected by dwCode/dwMask to the line's filter list; VCI_OK,
 * VCI_E_INVALID_STATE, an error when the list is full. */
HRESULT VCIAPI canControlAddFilterIds(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* Removes the ids selected by dwCode/dwMask from the line's filter list; VCI_OK,
 * VCI_E_INVALID_STATE. */
HRESULT VCIAPI canControlRemFilterIds(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* ---- CAN message channel ------------------------------------------------------------- */

/* Opens a message channel on line dwCanNo (fExclusive TRUE: no other channel may exist);
 * VCI_OK, VCI_E_ACCESSDENIED, an error for a line that does not exist. */
HRESULT VCIAPI canChannelOpen(HANDLE hDevice, UINT32 dwCanNo, BOOL fExclusive, PHANDLE phCanChn);

/* Closes the channel and drops its FIFOs; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canChannelClose(HANDLE hCanChn);

/* Fills *pCanCaps with the capabilities of the channel's controller; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canChannelGetCaps(HANDLE hCanChn, PCANCAPABILITIES2 pCanCaps);

/* Fills *pStatus with line status, activation, overrun flag and FIFO loads; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canChannelGetStatus(HANDLE hCanChn, PCANCHANSTATUS2 pStatus);

/* Opens the control unit of the channel's line, as canControlOpen on the channel's device
 * and line would, and stores its handle in *phCanCtl (close it with canControlClose);
 * VCI_OK, VCI_E_INVHANDLE, VCI_E_INVALIDARG for a null pointer, VCI_E_ACCESSDENIED while
 * another handle holds the control unit. */
HRESULT VCIAPI canChannelGetControl(HANDLE hCanChn, PHANDLE phCanCtl);

/* Creates the FIFOs (sizes in messages), the event thresholds and the channel's own
 * filter (list size dwFilterSize, mode bFilterMode = CAN_FILTER_*, optionally
 * | CAN_FILTER_SRRA); VCI_OK, VCI_E_INVALIDARG, VCI_E_INVALID_STATE when active. */
HRESULT VCIAPI canChannelInitialize(HANDLE hCanChn, UINT16 wRxFifoSize, UINT16 wRxThreshold,
                                    UINT16 wTxFifoSize, UINT16 wTxThreshold, UINT32 dwFilterSize,
                                    UINT8 bFilterMode);

/* Stores the mode of the channel's 11- or 29-bit filter in *pbMode; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canChannelGetFilterMode(HANDLE hCanChn, BOOL fExtend, PUINT8 pbMode);

/* Sets the mode of the channel's 11- or 29-bit filter, previous one in *pbPrev; VCI_OK,
 * VCI_E_INVALIDARG, VCI_E_INVALID_STATE while active. */
HRESULT VCIAPI canChannelSetFilterMode(HANDLE hCanChn, BOOL fExtend, UINT8 bMode, PUINT8 pbPrev);

/* Sets the acceptance code and mask of the channel's 11- or 29-bit filter; VCI_OK,
 * VCI_E_INVALID_STATE while active. */
HRESULT VCIAPI canChannelSetAccFilter(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* Adds the ids selected by dwCode/dwMask to the channel's filter list; VCI_OK,
 * VCI_E_INVALID_STATE, an error when the list is full. */
HRESULT VCIAPI canChannelAddFilterIds(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* Removes the ids selected by dwCode/dwMask from the channel's filter list; VCI_OK,
 * VCI_E_INVALID_STATE. */
HRESULT VCIAPI canChannelRemFilterIds(HANDLE hCanChn, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* Connects (fEnable TRUE) or disconnects the channel from the line; VCI_OK,
 * VCI_E_INVALID_STATE when not initialized. */
HRESULT VCIAPI canChannelActivate(HANDLE hCanChn, BOOL fEnable);

/* Takes the next received message without waiting (pCanMsg NULL: just drop it); VCI_OK,
 * VCI_E_RXQUEUE_EMPTY. */
HRESULT VCIAPI canChannelPeekMessage(HANDLE hCanChn, PCANMSG2 pCanMsg);

/* Takes up to dwCount received messages without waiting, count in *pdwDone; VCI_OK,
 * VCI_E_RXQUEUE_EMPTY when none. */
HRESULT VCIAPI canChannelPeekMsgMult(HANDLE hCanChn, CANMSG2 aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone);

/* Queues one message for transmission without waiting; VCI_OK, VCI_E_TXQUEUE_FULL. */
HRESULT VCIAPI canChannelPostMessage(HANDLE hCanChn, PCANMSG2 pCanMsg);

/* Queues up to dwCount messages without waiting, count queued in *pdwDone; VCI_OK,
 * VCI_E_TXQUEUE_FULL when none fit. */
HRESULT VCIAPI canChannelPostMsgMult(HANDLE hCanChn, CANMSG2 aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone);

/* Waits up to dwTimeout ms until the receive FIFO reaches its threshold; VCI_OK,
 * VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelWaitRxEvent(HANDLE hCanChn, UINT32 dwTimeout);

/* Waits up to dwTimeout ms until the transmit FIFO has room (threshold); VCI_OK,
 * VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelWaitTxEvent(HANDLE hCanChn, UINT32 dwTimeout);

/* Takes the next received message, waiting up to dwTimeout ms; VCI_OK, VCI_E_TIMEOUT,
 * VCI_E_RXQUEUE_EMPTY. */
HRESULT VCIAPI canChannelReadMessage(HANDLE hCanChn, UINT32 dwTimeout, PCANMSG2 pCanMsg);

/* Takes up to dwCount received messages, waiting up to dwTimeout ms for the first, count
 * in *pdwDone; VCI_OK, VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelReadMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG2 aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone);

/* Queues one message, waiting up to dwTimeout ms for room; VCI_OK, VCI_E_TIMEOUT,
 * VCI_E_TXQUEUE_FULL. */
HRESULT VCIAPI canChannelSendMessage(HANDLE hCanChn, UINT32 dwTimeout, PCANMSG2 pCanMsg);

/* Queues up to dwCount messages, waiting up to dwTimeout ms for room, count in *pdwDone;
 * VCI_OK, VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelSendMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG2 aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone);

/* ---- cyclic transmit scheduler ------------------------------------------------------- */

/* Opens the cyclic message scheduler of line dwCanNo; VCI_OK, VCI_E_ACCESSDENIED when
 * another client holds it, an error when the line has no scheduler. */
HRESULT VCIAPI canSchedulerOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanShd);

/* Closes the scheduler (its messages stop); VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerClose(HANDLE hCanShd);

/* Fills *pCanCaps with the controller capabilities (dwCmsClkFreq / dwCmsDivisor give the
 * tick rate of wCycleTime); VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerGetCaps(HANDLE hCanShd, PCANCAPABILITIES2 pCanCaps);

/* Fills *pStatus with the line status, the task state and each entry's state; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerGetStatus(HANDLE hCanShd, PCANSCHEDULERSTATUS2 pStatus);

/* Opens the control unit of the scheduler's line (as canChannelGetControl does for a
 * channel); VCI_OK, VCI_E_INVHANDLE, VCI_E_INVALIDARG, VCI_E_ACCESSDENIED. */
HRESULT VCIAPI canSchedulerGetControl(HANDLE hCanShd, PHANDLE phCanCtl);

/* Runs (fEnable TRUE) or halts the whole scheduler; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerActivate(HANDLE hCanShd, BOOL fEnable);

/* Halts the scheduler and removes all its messages; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerReset(HANDLE hCanShd);

/* Adds a cyclic message (stopped) and stores its list index in *pdwIndex; VCI_OK,
 * VCI_E_INVALIDARG for a cycle time of 0 or above dwCmsMaxTicks, an error when all
 * CAN_MAX_CTX_MSGS (16) entries are used. */
HRESULT VCIAPI canSchedulerAddMessage(HANDLE hCanShd, PCANCYCLICTXMSG2 pMessage, PUINT32 pdwIndex);

/* Removes entry dwIndex; VCI_OK, VCI_E_INVALIDARG for an unused index. */
HRESULT VCIAPI canSchedulerRemMessage(HANDLE hCanShd, UINT32 dwIndex);

/* Starts entry dwIndex for wRepeat transmissions (0 = until stopped); VCI_OK,
 * VCI_E_INVALIDARG. */
HRESULT VCIAPI canSchedulerStartMessage(HANDLE hCanShd, UINT32 dwIndex, UINT16 wRepeat);

/* Stops entry dwIndex but keeps it in the list; VCI_OK, VCI_E_INVALIDARG. */
HRESULT VCIAPI canSchedulerStopMessage(HANDLE hCanShd, UINT32 dwIndex);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* CANEMU_VCI_VCINPL2_H */
