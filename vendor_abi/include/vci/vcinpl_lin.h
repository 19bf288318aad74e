/*
 * vcinpl_lin.h - the LIN functions of the VCI C API, the same in libvcinpl.so and
 * libvcinpl2.so; vcinpl.h and vcinpl2.h include it (as the vendor's headers declare them
 * alike). Structures and constants come from lintype.h.
 *
 * dwLinNo is the controller's bus number on the device: an adapter's LIN controllers come
 * after its CAN controllers (VCIDEVICECAPS.BusCtrlTypes lists them in that order, a LIN one as
 * VCI_LIN_CTRL(LIN_CTRL_UNKNOWN)). A number that is not a LIN controller's gives
 * VCI_E_INVALIDARG. bPid carries the 6-bit identifier (0..63) both ways. docs/lin.md and
 * docs/vci.md describe what the emulated controller does.
 */
#ifndef CANEMU_VCI_VCINPL_LIN_H
#define CANEMU_VCI_VCINPL_LIN_H

#include "lintype.h"
#include "vcierr.h"
#include "vcitype.h"

#ifndef VCIAPI
#define VCIAPI
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- LIN control unit ----------------------------------------------------------------- */

/* Opens the control unit of LIN controller dwLinNo; VCI_OK, VCI_E_ACCESSDENIED when another
 * client holds it, VCI_E_INVALIDARG when dwLinNo is not a LIN controller. */
HRESULT VCIAPI linControlOpen(HANDLE hDevice, UINT32 dwLinNo, PHANDLE phLinCtl);

/* Closes it; the controller keeps running while monitors are open, else it is reset. */
HRESULT VCIAPI linControlClose(HANDLE hLinCtl);

/* LIN_FEATURE_*, the time stamp clock (1 MHz) and divisor (1). */
HRESULT VCIAPI linControlGetCaps(HANDLE hLinCtl, PLINCAPABILITIES pLinCaps);

/* Operating mode, bit rate (the detected one with LIN_BITRATE_AUTO) and LIN_STATUS_*. */
HRESULT VCIAPI linControlGetStatus(HANDLE hLinCtl, PLINLINESTATUS pStatus);

/* Resets the controller, then sets bMode (LIN_OPMODE_MASTER, LIN_OPMODE_ERRORS) and wBitrate
 * (1000..20000, or LIN_BITRATE_AUTO as slave); the line stays stopped. VCI_E_INVALIDARG for
 * other values. */
HRESULT VCIAPI linControlInitialize(HANDLE hLinCtl, UINT8 bMode, UINT16 wBitrate);

/* Stops the controller and empties its response table; monitors get LIN_INFO_RESET. */
HRESULT VCIAPI linControlReset(HANDLE hLinCtl);

/* Starts (LIN_INFO_START) or stops (LIN_INFO_STOP) the controller; VCI_E_INVALID_STATE
 * before linControlInitialize. */
HRESULT VCIAPI linControlStart(HANDLE hLinCtl, BOOL fStart);

/* fSend FALSE: a response table entry (LIN_MSGTYPE_DATA, ID 0..63, 1..8 bytes, ecs its
 * checksum), at any time. fSend TRUE: master DATA (ido: the header alone), SLEEP, or WAKEUP
 * (master or slave), never waiting: VCI_E_TXQUEUE_FULL while the previous one is not done,
 * VCI_E_INVALID_STATE when stopped, VCI_E_INVALIDARG for what the mode does not allow. */
HRESULT VCIAPI linControlWriteMessage(HANDLE hLinCtl, BOOL fSend, PLINMSG pLinMsg);

/* ---- LIN message monitors ------------------------------------------------------------- */

/* Opens a monitor (fExclusive: the only one, and only when none is open); VCI_OK,
 * VCI_E_ACCESSDENIED, VCI_E_INVALIDARG when dwLinNo is not a LIN controller. */
HRESULT VCIAPI linMonitorOpen(HANDLE hDevice, UINT32 dwLinNo, BOOL fExclusive, PHANDLE phLinMon);

HRESULT VCIAPI linMonitorClose(HANDLE hLinMon);
HRESULT VCIAPI linMonitorGetCaps(HANDLE hLinMon, PLINCAPABILITIES pLinCaps);

/* Line status, activation, overrun flag, receive FIFO load in percent. */
HRESULT VCIAPI linMonitorGetStatus(HANDLE hLinMon, PLINMONITORSTATUS pStatus);

/* A receive FIFO of at least wFifoSize LINMSGs (0: VCI_E_INVALIDARG), the receive event at
 * wThreshold messages; clears the overrun flag. VCI_E_INVALID_STATE while active. */
HRESULT VCIAPI linMonitorInitialize(HANDLE hLinMon, UINT16 wFifoSize, UINT16 wThreshold);

/* Connects (fEnable TRUE) or disconnects the monitor; messages arrive while it is active and
 * the controller runs. */
HRESULT VCIAPI linMonitorActivate(HANDLE hLinMon, BOOL fEnable);

/* The next message without waiting; VCI_OK, VCI_E_RXQUEUE_EMPTY. */
HRESULT VCIAPI linMonitorPeekMessage(HANDLE hLinMon, PLINMSG pLinMsg);

/* Up to dwCount messages without waiting, count in *pdwDone; VCI_E_RXQUEUE_EMPTY when none. */
HRESULT VCIAPI linMonitorPeekMsgMult(HANDLE hLinMon, LINMSG aLinMsg[], UINT32 dwCount,
                                     PUINT32 pdwDone);

/* Waits up to dwTimeout ms until the FIFO reaches its threshold; VCI_OK, VCI_E_TIMEOUT. */
HRESULT VCIAPI linMonitorWaitRxEvent(HANDLE hLinMon, UINT32 dwTimeout);

/* The next message, waiting up to dwTimeout ms; VCI_OK, VCI_E_TIMEOUT. */
HRESULT VCIAPI linMonitorReadMessage(HANDLE hLinMon, UINT32 dwTimeout, PLINMSG pLinMsg);

/* Up to dwCount messages, waiting up to dwTimeout ms for the first; VCI_OK, VCI_E_TIMEOUT. */
HRESULT VCIAPI linMonitorReadMsgMult(HANDLE hLinMon, UINT32 dwTimeout, LINMSG aLinMsg[],
                                     UINT32 dwCount, PUINT32 pdwDone);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* CANEMU_VCI_VCINPL_LIN_H */
