/*
 * canemu's extensions to the VCI C API: not part of IXXAT's API, exported by both libvcinpl.so
 * and libvcinpl2.so. Programs that must also build against IXXAT's libraries keep these calls
 * behind their own switch.
 */
#ifndef CANEMU_VCI_H
#define CANEMU_VCI_H

#include "vcierr.h"
#include "vcitype.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Error states of canemuGetControllerState. */
#define CANEMU_STATE_ACTIVE 0  /* both counters below 96 */
#define CANEMU_STATE_WARNING 1 /* a counter at 96 or above */
#define CANEMU_STATE_PASSIVE 2 /* a counter at 128 or above */
#define CANEMU_STATE_BUSOFF 3  /* transmit counter above 255 */

/* Line states of canemuGetControllerState. */
#define CANEMU_LINE_NOT_INITIALIZED 0
#define CANEMU_LINE_OFFLINE 1
#define CANEMU_LINE_ONLINE 2

/* Time modes of canemuGetTime. */
#define CANEMU_TIME_REALTIME 0
#define CANEMU_TIME_SCALED 1
#define CANEMU_TIME_STEPPED 2

/* Kinds of bus of CANEMU_BUSINFO. */
#define CANEMU_BUS_CAN 0
#define CANEMU_BUS_CANFD 1
#define CANEMU_BUS_LIN 2

#define CANEMU_MAX_CONTROLLERS 4

/* A bus of canemud's configuration (48 bytes). */
typedef struct _CANEMU_BUSINFO {
  CHAR szName[32];
  UINT8 bKind;     /* CANEMU_BUS_* */
  UINT8 bLowSpeed; /* 1: low-speed, fault-tolerant transceivers (ISO 11898-3) */
  UINT8 abReserved[2];
  UINT32 dwBitrate;     /* nominal bit rate, bit/s */
  UINT32 dwDataBitrate; /* CAN FD data-phase bit rate, bit/s; 0 on other buses */
  UINT32 dwReserved;
} CANEMU_BUSINFO, *PCANEMU_BUSINFO;

/* An adapter the VCI sees (184 bytes). */
typedef struct _CANEMU_DEVICEINFO {
  CHAR szName[32];
  VCIID VciObjectId;
  INT64 qwEpochNs;    /* simulated time of its power-on: its time stamps count from here */
  UINT8 bControllers; /* controllers (CAN, then LIN), 1 .. CANEMU_MAX_CONTROLLERS */
  UINT8 bEphemeral;   /* 1: made by canemuCreateDevice (by any process) */
  UINT8 abFd[CANEMU_MAX_CONTROLLERS]; /* controller N: 0 CAN, 1 CAN FD, 2 LIN controller */
  UINT8 abReserved[2];
  CHAR aszBus[CANEMU_MAX_CONTROLLERS][32]; /* the bus each controller is wired to */
} CANEMU_DEVICEINFO, *PCANEMU_DEVICEINFO;

/* A simulated CAN node canemud runs (80 bytes), docs/restbus.md. */
typedef struct _CANEMU_CANNODEINFO {
  CHAR szName[32];
  CHAR szBus[32];
  UINT8 bPowered; /* 1: on the bus; 0: switched off */
  UINT8 abReserved[3];
  UINT32 dwMessages; /* messages it sends */
  UINT64 qwFrames;   /* frames it sent whole */
} CANEMU_CANNODEINFO, *PCANEMU_CANNODEINFO;

/* Talks to the canemud listening at pszSocket from now on (NULL: $CANEMU_SOCKET or the
 * default path again). The connection to the previous daemon ends: objects opened there are
 * closed by that daemon, and their handles fail from now on (close them first).
 * VCI_OK, or VCI_E_DISCONNECTED when nobody listens there. */
HRESULT VCIAPI canemuConnect(const char* pszSocket);

/* The error state, transmit and receive error counters and line state of the controller that
 * hObject belongs to: a control unit, channel or cyclic list handle of the C API, or an
 * ICanControl(2)*, ICanChannel(2)* or ICanScheduler(2)* of the C++ API. Any pointer may be
 * NULL. VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI canemuGetControllerState(HANDLE hObject, PUINT8 pbErrorState, PUINT16 pwTec,
                                        PUINT16 pwRec, PUINT8 pbLineState);

/* Stepped time (canemud started with time = "stepped"): runs the emulation qwNanoseconds
 * further; everything due in that span happens before the call returns. The simulated time
 * after the step goes to *pqwNow (may be NULL). VCI_OK; VCI_E_INVALID_STATE when the daemon
 * does not run in stepped time; VCI_E_INVALIDARG for 0. */
HRESULT VCIAPI canemuStepTime(UINT64 qwNanoseconds, UINT64* pqwNow);

/* A new adapter with one controller on the bus named pszBus (an SJA1000 on a classic bus,
 * the CAN FD controller on a CAN FD bus, a LIN controller on a LIN bus), enumerated like the
 * configured ones from now on and gone when this process disconnects or calls canemuRemoveDevice.
 * pszName NULL or empty: canemud picks a name ("vci1", ...). Its VCIID goes to *pVciid (may be
 * NULL), its name to pszNameOut (cbNameOut bytes, at least 32; may be NULL). VCI_OK;
 * VCI_E_INVALIDARG for an unknown bus or a name that is taken or not a-z, 0-9, '_', '-' (1 to 28);
 * VCI_E_OUTOFMEMORY after 16 on one connection. */
HRESULT VCIAPI canemuCreateDevice(const char* pszBus, const char* pszName, PVCIID pVciid,
                                  PCHAR pszNameOut, UINT32 cbNameOut);
/* Removes an adapter canemuCreateDevice made; objects open on it work until closed. */
HRESULT VCIAPI canemuRemoveDevice(const char* pszName);

/* The dwIndex-th bus of canemud's configuration (from 0), in configuration order. VCI_OK;
 * VCI_E_NO_MORE_ITEMS past the last; VCI_E_INVALIDARG for a NULL pInfo. */
HRESULT VCIAPI canemuEnumBuses(UINT32 dwIndex, PCANEMU_BUSINFO pInfo);

/* The dwIndex-th adapter (from 0): the configured ones in configuration order, then the
 * ephemeral ones in order of creation. Same results as canemuEnumBuses. */
HRESULT VCIAPI canemuEnumDevices(UINT32 dwIndex, PCANEMU_DEVICEINFO pInfo);

/* The adapter named pszName (configured or ephemeral). VCI_OK; VCI_E_NO_MORE_ITEMS when there
 * is none; VCI_E_INVALIDARG for NULL arguments. */
HRESULT VCIAPI canemuFindDevice(const char* pszName, PCANEMU_DEVICEINFO pInfo);

/* canemud's simulated time in ns (may be NULL) and time mode, CANEMU_TIME_* (may be NULL). */
HRESULT VCIAPI canemuGetTime(UINT64* pqwNow, PUINT8 pbTimeMode);

/* A descriptor for poll/select/epoll that is readable whenever the receive FIFO of the
 * initialized C API channel hCanChn holds messages (it may also be readable when it holds
 * none: a read then finds it empty and the descriptor quiets down). Valid until the channel is
 * initialized again or closed; the channel owns it (do not close it). VCI_OK;
 * VCI_E_INVHANDLE; VCI_E_NOT_INITIALIZED before canChannelInitialize; VCI_E_INVALIDARG for a
 * NULL pFd. */
HRESULT VCIAPI canemuChannelEventFd(HANDLE hCanChn, int* pFd);

/* Simulated CAN nodes at run time (docs/restbus.md). canemud's refusal (why, one line per
 * error) is vciFormatError's detail of the failed call: "invalid argument (REASON)"; a refused
 * call changes nothing. */

/* Loads [[can_node]] tables (TOML text, at most 1 MiB; pszSource, may be NULL, names them in
 * canemud's errors): they are checked as a configuration file's are and all start, at the
 * instant canemud takes them, or none does. A node of a name that runs on its bus already is
 * replaced. VCI_OK; VCI_E_INVALIDARG for NULL tables, or when canemud refuses them. */
HRESULT VCIAPI canemuLoadCanNodes(const char* pszTables, const char* pszSource);

/* The dwIndex-th simulated CAN node (from 0), the configuration's then the loaded ones in the
 * order they started (at most the first 48). Same results as canemuEnumBuses. */
HRESULT VCIAPI canemuEnumCanNodes(UINT32 dwIndex, PCANEMU_CANNODEINFO pInfo);

/* Switches the node pszNode (NAME, or BUS/NAME where several buses have a node of that NAME)
 * off (fOn FALSE: it leaves the bus, its waiting frames are dropped, its signals stay) or on
 * (its controller is reset and its schedules start again from now). VCI_OK; VCI_E_INVALIDARG
 * for NULL or an unknown node. */
HRESULT VCIAPI canemuPowerCanNode(const char* pszNode, BOOL fOn);

/* Takes the node pszNode off its bus. VCI_OK; VCI_E_INVALIDARG for NULL or an unknown node. */
HRESULT VCIAPI canemuRemoveCanNode(const char* pszNode);

/* Sets the physical value of pszSignal, "MESSAGE.SIGNAL", of the message a simulated node sends
 * on the bus pszBus; its next frame carries it (an on-change message goes at once). VCI_OK;
 * VCI_E_INVALIDARG for NULL, a pszSignal that is not MESSAGE.SIGNAL, or canemud's refusal: no
 * such message on the bus or signal in it, a value outside the signal's range or bits, a
 * checksum signal. */
HRESULT VCIAPI canemuSetSignal(const char* pszBus, const char* pszSignal, double dValue);

/* The physical value of pszSignal ("MESSAGE.SIGNAL" on pszBus) that its next frame carries
 * (what was set, rounded to the signal's bits) into *pdValue. Same results as canemuSetSignal
 * (a NULL pdValue is VCI_E_INVALIDARG). */
HRESULT VCIAPI canemuGetSignal(const char* pszBus, const char* pszSignal, double* pdValue);

#ifdef __cplusplus
}
#endif

#endif /* CANEMU_VCI_H */
