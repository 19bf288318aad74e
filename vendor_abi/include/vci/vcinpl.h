/*
 * vcinpl.h - canemu's declarations of the classic VCI C API (libvcinpl.so).
 *
 * libvcinpl.so is meant to be a drop-in for IXXAT's native VCI library (vcinpl.dll on
 * Windows): same exported names, same argument order, same argument and structure types,
 * same HRESULT codes. This is the "classic" flavour: CANMSG with 8 data bytes, the
 * controller initialised with SJA1000 bus timing registers (BTR0/BTR1, 16 MHz), and the
 * CANCAPABILITIES / CANLINESTATUS / CANCHANSTATUS / CANSCHEDULERSTATUS /
 * CANCYCLICTXMSG structures. The CAN FD flavour is vcinpl2.h (libvcinpl2.so); it uses the
 * same function names with other argument types, so a translation unit includes one of the
 * two headers, never both.
 *
 * Types, structures and constants come from vcitype.h, vcierr.h and cantype.h. VCIAPI is
 * the calling-convention marker and is empty on Linux. Every function returns VCI_OK (0)
 * on success and a VCI_E_* code otherwise, except the vciFormatError family (void).
 * Common codes: VCI_E_INVHANDLE (bad or closed handle), VCI_E_INVPOINTER / VCI_E_INVALIDARG
 * (bad pointer or argument), VCI_E_ACCESSDENIED, VCI_E_TIMEOUT (a wait elapsed),
 * VCI_E_NO_MORE_ITEMS (enumeration done), VCI_E_RXQUEUE_EMPTY, VCI_E_TXQUEUE_FULL.
 *
 * Where the prototypes were confirmed: notes/vci-c-api-research.md. Timeouts are in
 * milliseconds; 0 means "test and return at once", INFINITE (0xFFFFFFFF) means "wait
 * forever".
 */
#ifndef CANEMU_VCI_VCINPL_H
#define CANEMU_VCI_VCINPL_H

#include "cantype.h"
#include "vcierr.h"
#include "vcinpl_general.h" /* error texts, identifiers, events */
#include "vcinpl_lin.h"     /* the LIN functions */
#include "vcitype.h"

#ifndef VCIAPI
#define VCIAPI
#endif

/*
 * Error-frame codes (abData[0] of CAN_MSGTYPE_ERROR messages) keep their VCI 3 numbering in
 * the classic API: "other" is 7, and the VCI 4 codes for fast-data-bit and DLC errors do
 * not exist here (the library reports them as CAN_ERROR_OTHER). vcinpl2.h keeps the VCI 4
 * numbering. Define CANEMU_VCINPL_KEEP_VCI4_ERROR_CODES to see cantype.h's values instead.
 */
#if !defined(CANEMU_VCINPL_KEEP_VCI4_ERROR_CODES) && defined(CAN_ERROR_OTHER)
#if CAN_ERROR_OTHER != 7
#undef CAN_ERROR_OTHER
#define CAN_ERROR_OTHER 7
#undef CAN_ERROR_FDB
#undef CAN_ERROR_DLC
#endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- library ------------------------------------------------------------------------- */

/* Prepares the library for use (idempotent); VCI_OK, or an error if the emulator daemon
 * cannot be reached. */
HRESULT VCIAPI vciInitialize(void);

/* The VCI version these libraries implement: 4.0; VCI_OK, VCI_E_INVALIDARG when a pointer
 * is NULL. */
HRESULT VCIAPI vciGetVersion(PUINT32 pdwMajorVersion, PUINT32 pdwMinorVersion);

/* The same with the revision (0) and the build number, canemu's own version
 * (major * 10000 + minor * 100 + patch). */
HRESULT VCIAPI vciGetVersionEx(PUINT32 pdwMajorVersion, PUINT32 pdwMinorVersion,
                               PUINT32 pdwRevNumber, PUINT32 pdwBuildNumber);

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

/* Opens the device with VCI id rVciid and stores its handle in *phDevice; VCI_OK,
 * VCI_E_INVALIDARG / VCI_E_NO_MORE_ITEMS for an unknown id. */
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
 * another client holds it, VCI_E_INVALIDARG for a line that does not exist. */
HRESULT VCIAPI canControlOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanCtl);

/* Closes the control unit (the line keeps running if it was started); VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlClose(HANDLE hCanCtl);

/* Fills *pCanCaps with the controller's capabilities (clock, divisors, features); VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlGetCaps(HANDLE hCanCtl, PCANCAPABILITIES pCanCaps);

/* Fills *pStatus with the line's mode, BTR values, bus load and CAN_STATUS_* flags; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlGetStatus(HANDLE hCanCtl, PCANLINESTATUS pStatus);

/* Tries the dwCount BTR0/BTR1 pairs until one sees valid traffic within wTimeout ms and
 * stores its index in *plIndex; VCI_OK, VCI_E_TIMEOUT when none matched. */
HRESULT VCIAPI canControlDetectBitrate(HANDLE hCanCtl, UINT16 wTimeout, UINT32 dwCount,
                                       PUINT8 pabBtr0, PUINT8 pabBtr1, PINT32 plIndex);

/* Resets the controller and sets operating mode (CAN_OPMODE_*) and bus timing (BTR0/BTR1,
 * SJA1000 at 16 MHz); the line stays stopped; VCI_OK, VCI_E_INVALIDARG for bad values,
 * VCI_E_ACCESSDENIED (python-can treats that one as success). */
HRESULT VCIAPI canControlInitialize(HANDLE hCanCtl, UINT8 bMode, UINT8 bBtr0, UINT8 bBtr1);

/* Stops the line and returns the controller to its uninitialized state; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canControlReset(HANDLE hCanCtl);

/* Starts (fStart TRUE) or stops the line; VCI_OK, VCI_E_INVALID_STATE when not initialized. */
HRESULT VCIAPI canControlStart(HANDLE hCanCtl, BOOL fStart);

/* Sets the acceptance code and mask of the 11-bit (fExtend FALSE) or 29-bit filter
 * (id in bits 1.., RTR in bit 0); VCI_OK, VCI_E_INVALID_STATE while the line runs. */
HRESULT VCIAPI canControlSetAccFilter(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* Adds the ids selected by dwCode/dwMask (same bit layout) to the 11- or 29-bit filter
 * list; VCI_OK, VCI_E_INVALID_STATE while the line runs, an error when the list is full. */
HRESULT VCIAPI canControlAddFilterIds(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* Removes the ids selected by dwCode/dwMask from the filter list; VCI_OK,
 * VCI_E_INVALID_STATE. */
HRESULT VCIAPI canControlRemFilterIds(HANDLE hCanCtl, BOOL fExtend, UINT32 dwCode, UINT32 dwMask);

/* ---- CAN message channel ------------------------------------------------------------- */

/* Opens a message channel on line dwCanNo (fExclusive TRUE: no other channel may exist);
 * VCI_OK, VCI_E_ACCESSDENIED, VCI_E_INVALIDARG for a line that does not exist. */
HRESULT VCIAPI canChannelOpen(HANDLE hDevice, UINT32 dwCanNo, BOOL fExclusive, PHANDLE phCanChn);

/* Closes the channel and drops its FIFOs; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canChannelClose(HANDLE hCanChn);

/* Fills *pCanCaps with the capabilities of the channel's controller; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canChannelGetCaps(HANDLE hCanChn, PCANCAPABILITIES pCanCaps);

/* Fills *pStatus with line status, activation, overrun flag and FIFO loads; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canChannelGetStatus(HANDLE hCanChn, PCANCHANSTATUS pStatus);

/* Creates the receive and transmit FIFOs (sizes in messages) and the event thresholds;
 * VCI_OK, VCI_E_INVALIDARG for a zero size, VCI_E_INVALID_STATE when active. */
HRESULT VCIAPI canChannelInitialize(HANDLE hCanChn, UINT16 wRxFifoSize, UINT16 wRxThreshold,
                                    UINT16 wTxFifoSize, UINT16 wTxThreshold);

/* Connects (fEnable TRUE) or disconnects the channel from the line; VCI_OK,
 * VCI_E_INVALID_STATE when not initialized. */
HRESULT VCIAPI canChannelActivate(HANDLE hCanChn, BOOL fEnable);

/* Takes the next received message without waiting (pCanMsg NULL: just drop it); VCI_OK,
 * VCI_E_RXQUEUE_EMPTY. */
HRESULT VCIAPI canChannelPeekMessage(HANDLE hCanChn, PCANMSG pCanMsg);

/* Queues one message for transmission without waiting; VCI_OK, VCI_E_TXQUEUE_FULL. */
HRESULT VCIAPI canChannelPostMessage(HANDLE hCanChn, PCANMSG pCanMsg);

/* Waits up to dwTimeout ms until the receive FIFO reaches its threshold; VCI_OK,
 * VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelWaitRxEvent(HANDLE hCanChn, UINT32 dwTimeout);

/* Waits up to dwTimeout ms until the transmit FIFO has room (threshold); VCI_OK,
 * VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelWaitTxEvent(HANDLE hCanChn, UINT32 dwTimeout);

/* Takes the next received message, waiting up to dwTimeout ms; VCI_OK, VCI_E_TIMEOUT,
 * VCI_E_RXQUEUE_EMPTY. */
HRESULT VCIAPI canChannelReadMessage(HANDLE hCanChn, UINT32 dwTimeout, PCANMSG pCanMsg);

/* Queues one message, waiting up to dwTimeout ms for room; VCI_OK, VCI_E_TIMEOUT,
 * VCI_E_TXQUEUE_FULL. */
HRESULT VCIAPI canChannelSendMessage(HANDLE hCanChn, UINT32 dwTimeout, PCANMSG pCanMsg);

/* Takes up to dwCount received messages without waiting, count in *pdwDone; VCI_OK,
 * VCI_E_RXQUEUE_EMPTY when none. */
HRESULT VCIAPI canChannelPeekMsgMult(HANDLE hCanChn, CANMSG aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone);

/* Queues up to dwCount messages without waiting, count queued in *pdwDone; VCI_OK,
 * VCI_E_TXQUEUE_FULL when none fit. */
HRESULT VCIAPI canChannelPostMsgMult(HANDLE hCanChn, CANMSG aCanMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone);

/* Takes up to dwCount received messages, waiting up to dwTimeout ms for the first, count
 * in *pdwDone; VCI_OK, VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelReadMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone);

/* Queues up to dwCount messages, waiting up to dwTimeout ms for room, count in *pdwDone;
 * VCI_OK, VCI_E_TIMEOUT. */
HRESULT VCIAPI canChannelSendMsgMult(HANDLE hCanChn, UINT32 dwTimeout, CANMSG aCanMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone);

/* Older multi-message forms (VCI 3 exports, kept by VCI 4 as legacy): *pdwCount is the
 * array size on entry and the number of messages handled on return; note the count comes
 * before the array. Same codes as the *MsgMult functions. */

/* Legacy bulk peek; VCI_OK, VCI_E_RXQUEUE_EMPTY. */
HRESULT VCIAPI canChannelPeekMultipleMessages(HANDLE hCanChn, PUINT32 pdwCount, CANMSG aCanMsg[]);

/* Legacy bulk post; VCI_OK, VCI_E_TXQUEUE_FULL. */
HRESULT VCIAPI canChannelPostMultipleMessages(HANDLE hCanChn, PUINT32 pdwCount, CANMSG aCanMsg[]);

/* Legacy bulk read with timeout; VCI_OK, VCI_E_TIMEOUT, VCI_E_RXQUEUE_EMPTY. */
HRESULT VCIAPI canChannelReadMultipleMessages(HANDLE hCanChn, UINT32 dwTimeout, PUINT32 pdwCount,
                                              CANMSG aCanMsg[]);

/* Legacy bulk send with timeout; VCI_OK, VCI_E_TIMEOUT, VCI_E_TXQUEUE_FULL. */
HRESULT VCIAPI canChannelSendMultipleMessages(HANDLE hCanChn, UINT32 dwTimeout, PUINT32 pdwCount,
                                              CANMSG aCanMsg[]);

/* ---- cyclic transmit scheduler ------------------------------------------------------- */

/* Opens the cyclic message scheduler of line dwCanNo; VCI_OK, VCI_E_ACCESSDENIED when
 * another client holds it, an error when the line has no scheduler. */
HRESULT VCIAPI canSchedulerOpen(HANDLE hDevice, UINT32 dwCanNo, PHANDLE phCanShd);

/* Closes the scheduler (its messages stop); VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerClose(HANDLE hCanShd);

/* Fills *pCanCaps with the controller capabilities (dwClockFreq / dwCmsDivisor give the
 * tick rate of wCycleTime); VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerGetCaps(HANDLE hCanShd, PCANCAPABILITIES pCanCaps);

/* Fills *pStatus with the task state and the state of each of the 16 entries; VCI_OK,
 * VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerGetStatus(HANDLE hCanShd, PCANSCHEDULERSTATUS pStatus);

/* Runs (fEnable TRUE) or halts the whole scheduler; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerActivate(HANDLE hCanShd, BOOL fEnable);

/* Halts the scheduler and removes all its messages; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canSchedulerReset(HANDLE hCanShd);

/* Adds a cyclic message (stopped) and stores its list index in *pdwIndex; VCI_OK,
 * VCI_E_INVALIDARG for a cycle time of 0 or above dwCmsMaxTicks, an error when all
 * CAN_MAX_CTX_MSGS (16) entries are used. */
HRESULT VCIAPI canSchedulerAddMessage(HANDLE hCanShd, PCANCYCLICTXMSG pMessage, PUINT32 pdwIndex);

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

#endif /* CANEMU_VCI_VCINPL_H */
