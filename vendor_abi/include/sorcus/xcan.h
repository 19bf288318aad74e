/*
 * xcan.h - the generic channel services of the SORCUS X-CAN-2i module device driver, as
 * libxcan.so gives them on canemud's emulated X-CAN-2i modules (canemu).
 *
 * The manual (chapter 10.9.2) names the services and shows max_load_mdd's call; it gives no
 * prototypes for the others, no name for opening and closing a channel and no callback type.
 * The prototypes below are canemu's, written to the manual's calls (`max_write_channel_block
 * (hChan, &ulSize, &arcData)`); docs/sorcus.md lists the decisions. Data types and constants
 * are in xcan_types.h.
 *
 * Every function returns ERR_OK or an error code (xcan_types.h, and the two below). Functions
 * may be called from any thread; a blocking service (a send with XCAN_NO_INT, an active receive
 * read) blocks only its caller, until the emulation's time has passed `usTimeout` µs at most
 * (with stepped time: until somebody steps it that far).
 */
#ifndef CANEMU_SORCUS_XCAN_H
#define CANEMU_SORCUS_XCAN_H

#include "xcan_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef XCANAPI
#define XCANAPI
#endif

/* A handle of a module, an MDD or a channel; 0 is none. */
typedef ULONG MAX_HANDLE;

/* The callback function of a channel. `pData` points to what the channel's kind passes:
 * nothing (ulSize 0, pData NULL) for a send object, up to 8 data bytes for a receive object,
 * the bus state word (a ULONG, XCAN_STATUS) for the bus-control device, an XCAN_MESSAGE for the
 * acceptance-filter device. Buffered callbacks (the default) run one after the other on one
 * thread of the library; with _CP_SYNC_CALLBACK they run on the library's receive thread as
 * the daemon's message is read, before any later message (reply or callback) is handled: such
 * a callback must not call a service of this library that waits for canemud. */
typedef void (*MAX_CALLBACK)(MAX_HANDLE hChan, ULONG ulSize, const void* pData);

/* Error codes of the library itself. */
#define ERR_XCAN_NO_DAEMON 0x60 /* canemud cannot be reached, or the connection broke */
#define ERR_XCAN_NO_MODULE 0x61 /* no such X-CAN-2i, slot, layer or program number */

/* canemu: the carrier of the X-CAN-2i named `pszDevice` in canemud's configuration (a
 * [[device]] with model = "sorcus-x-can-2i"); stands for opening the MAX board. The socket is
 * found as for every canemu client (CANEMU_SOCKET, then the usual places). */
XCANAPI ULONG canemu_open_module(const char* pszDevice, MAX_HANDLE* phModul);

/* canemu: talk to the canemud listening at `pszSocket` from now on (NULL: the usual search);
 * drops the connection and every handle of this process. ERR_OK once connected (NULL: always).
 * Not while another thread of the process is in a function of this library. */
XCANAPI ULONG canemu_xcan_connect(const char* pszSocket);

/* canemu: one CAN interface of an X-CAN-2i in canemud's configuration (72 bytes). */
typedef struct CANEMU_XCAN_INTERFACE {
  char szDevice[32]; /* its module: the [[device]] name (canemu_open_module) */
  char szBus[32];    /* the bus its 82527 is wired to */
  USHORT usChannel;  /* CPS_XCAN.usChannel: 0 or 1 */
  USHORT usLowSpeed; /* 1: the low-speed fault-tolerant transceiver */
  ULONG ulBitrate;   /* the bus's configured bit rate in bit/s */
} CANEMU_XCAN_INTERFACE;

/* canemu: the ulIndex-th (from 0) interface of canemud's X-CAN-2i modules: the modules in
 * configuration order, each with interface 0 then 1. ERR_OK; ERR_XCAN_NO_MODULE after the last
 * (or for a NULL pInfo); ERR_XCAN_NO_DAEMON. */
XCANAPI ULONG canemu_xcan_enum_interfaces(ULONG ulIndex, CANEMU_XCAN_INTERFACE* pInfo);

/* canemu: called inside a callback function, the simulated instant of the event it reports
 * (ns since canemud's start; the end of the frame, or the error), as canemu's time stamps
 * count. ERR_OK; ERR_XCAN_NOT_READY when the calling thread is not in a callback (or for a
 * NULL pullTime). */
XCANAPI ULONG canemu_xcan_callback_time(unsigned long long* pullTime);

/* Loads the MDD: slot 1, layer 0, program number 0x803A (mxcan2); the manual's
 * `max_load_mdd (hModul, 1, 0, 0, 0x803A, NULL, &hMDD)`. */
XCANAPI ULONG max_load_mdd(MAX_HANDLE hModul, USHORT usSlot, USHORT usLayer, USHORT usReserved,
                           USHORT usProgNo, const void* pReserved, MAX_HANDLE* phMDD);

/* Opens a channel from a CPS_XCAN; `pfnCallback` may be NULL (no callbacks). */
XCANAPI ULONG max_open_channel(MAX_HANDLE hMDD, const CPS_XCAN* pCPS, MAX_CALLBACK pfnCallback,
                               MAX_HANDLE* phChan);
XCANAPI ULONG max_close_channel(MAX_HANDLE hChan);

/* *pulSize bytes of pData. */
XCANAPI ULONG max_write_channel_block(MAX_HANDLE hChan, ULONG* pulSize, const void* pData);
/* In: *pulSize the room at pData; out: the bytes read (ERR_XCAN_DATA_SIZE and nothing copied
 * when there is not room for them). */
XCANAPI ULONG max_read_channel_block(MAX_HANDLE hChan, ULONG* pulSize, void* pData);
XCANAPI ULONG max_write_channel_ulong(MAX_HANDLE hChan, ULONG ulValue);
XCANAPI ULONG max_read_channel_ulong(MAX_HANDLE hChan, ULONG* pulValue);
XCANAPI ULONG max_channel_control(MAX_HANDLE hChan, USHORT usCommand);
XCANAPI ULONG max_channel_info(MAX_HANDLE hChan, USHORT usInfo, ULONG* pulInfo);
XCANAPI ULONG max_clear_error(MAX_HANDLE hChan);

#ifdef __cplusplus
}
static_assert(sizeof(CANEMU_XCAN_INTERFACE) == 72, "CANEMU_XCAN_INTERFACE must be 72 bytes");
#elif defined(__STDC_VERSION__) && (__STDC_VERSION__ >= 201112L)
_Static_assert(sizeof(CANEMU_XCAN_INTERFACE) == 72, "CANEMU_XCAN_INTERFACE must be 72 bytes");
#endif

#endif /* CANEMU_SORCUS_XCAN_H */
