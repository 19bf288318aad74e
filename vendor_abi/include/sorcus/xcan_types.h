/*
 * xcan_types.h - data types and constants of the SORCUS X-CAN-2i module device driver (MDD)
 * (canemu).
 *
 * This project's own declarations of the names the SORCUS manual chapter "10.9. X-CAN-2i"
 * uses (../shared/spec/sorcus-digest.md §3.1, §3.3, §4). The manual gives names and meanings but
 * no numeric values, no member order and no structure sizes (digest §7 points 1 and 2): every
 * value below is canemu's, defined once here for the firmware model, the daemon and the client
 * library. Programs built against SORCUS's own headers are not binary compatible with it.
 * Error codes the manual leaves silent are named here; where the situation is the one of an
 * SL-CANi diagnosis code (digest §3.4), the value is that code. docs/sorcus.md lists them all.
 *
 * Valid C11 and C++; includes only the C library. Every structure has natural alignment and no
 * padding (sizes checked below).
 */
#ifndef CANEMU_SORCUS_XCAN_TYPES_H
#define CANEMU_SORCUS_XCAN_TYPES_H

#include <stdint.h>

typedef uint8_t UCHAR;
typedef uint16_t USHORT;
typedef uint32_t ULONG; /* 32-bit, as in vci/vcitype.h */

/* ------------------------------------------------------------------------------------------
 * Channel parameter structure (CPS) and its members (§10.9.2)
 * ------------------------------------------------------------------------------------------ */

/* .usDevice */
#define DEVICE_CTRL 1    /* bus-control device or acceptance-filter device */
#define DEVICE_BUS_OUT 2 /* channel to a send object, or the general-ID send channel */
#define DEVICE_BUS_IN 3  /* channel to a receive object */

/* .usChannel: the CAN interface, 0 or 1. */
#define XCAN_INTERFACES 2

/* .usIndexFirst = .usIndexLast of the bus-control device. The acceptance-filter device is the
 * other DEVICE_CTRL channel and must have both indices 0, so this value lies outside 0..28. */
#define XCAN_BUS_CTRL_INDEX 0x0100

/* .ulCanID values that are not identifiers. */
#define XCAN_GENERAL_ID 0xFFFFFFFEu /* general-ID send channel (§10.9.2.9) */
#define XCAN_AUTO_ID 0xFFFFFFFFu    /* acceptance filter: keep the automatic ID (§10.9.2.8) */

/* Highest identifier an object may have. The manual says "0 bis 7F0h" / "0 bis 1FFFFFF0h";
 * canemu reads "bis" as exclusive, which for 11 bits is the CAN 2.0A rule (7F0h..7FFh are
 * forbidden). */
#define XCAN_MAX_ID_11 0x7EFu
#define XCAN_MAX_ID_29 0x1FFFFFEFu

/* .usFlags. The generic channel flags (_CP_*) and the X-CAN flags share the word. */
#define _CP_SYNC_CALLBACK 0x0001 /* call the callback directly (real-time programs only) */
#define _CP_EXCLUSIVE 0x0002     /* exclusive channel (mandatory for XCAN_GENERAL_ID) */
#define XCAN_REMOTE 0x0010       /* remote frames: passive send, active receive, filter, message */
#define XCAN_NO_INT 0x0020       /* no callback; the service waits up to .usTimeout µs */
#define _XCAN_NO_INT XCAN_NO_INT /* the spelling of §10.9.2.9 */
#define XCAN_EXCL_BUFFER 0x0040  /* reserve a controller buffer (1..13) for the object */
#define XCAN_NEW_ONLY 0x0080     /* passive receive: read only new data */
#define XCAN_29BIT_ID 0x0100     /* 29-bit identifier: XCAN_MESSAGE, and objects in mixed format */

typedef struct CPS_XCAN {
  USHORT usDevice;     /* DEVICE_* */
  USHORT usChannel;    /* CAN interface 0 or 1 */
  USHORT usIndexFirst; /* XCAN_BUS_CTRL_INDEX (bus control) or 0 (acceptance filter) */
  USHORT usIndexLast;  /* = usIndexFirst */
  USHORT usFlags;      /* _CP_* | XCAN_* */
  USHORT usTimeout;    /* µs, 0..65535: the longest wait of a blocking service */
  ULONG ulCanID;       /* identifier, XCAN_GENERAL_ID or XCAN_AUTO_ID */
} CPS_XCAN;

/* ------------------------------------------------------------------------------------------
 * Bus-control device data (§10.9.2.3), data type DATA_USHORT
 * ------------------------------------------------------------------------------------------ */

#define XCAN_MIXED_FORMAT 0x00FF /* MsgFormat: 11- and 29-bit identifiers on one interface */

typedef struct XCAN_BITPARAMS {
  USHORT Tq;        /* time quantum in ns, 125..8000, a multiple of 125 */
  USHORT Tseg1;     /* t_SEG1 / t_Q, 3..16 */
  USHORT Tseg2;     /* t_SEG2 / t_Q, 2..8 */
  USHORT Tsjw;      /* t_SJW / t_Q, 1..4 */
  USHORT SpB;       /* samples per bit, 1 or 3 */
  USHORT Rbus;      /* termination: HS 0 off / 1 110 ohm; LS 0 5.6 kohm / 1 510 ohm */
  USHORT MsgFormat; /* 11, 29 or XCAN_MIXED_FORMAT */
} XCAN_BITPARAMS;

/* The factory setting: 20 kbit/s (manual table note 3), 11-bit identifiers, termination off. */
#define XCAN_DEFAULT_BITPARAMS \
  { 2500, 16, 3, 2, 1, 0, 11 }

/* ------------------------------------------------------------------------------------------
 * Messages of the acceptance-filter callback and the general-ID send channel (§10.9.2.8/9)
 * ------------------------------------------------------------------------------------------ */

typedef struct XCAN_MESSAGE {
  ULONG ulCanId;     /* identifier */
  USHORT usDataSize; /* valid bytes in aucData, 0..8 (0 for a remote frame received) */
  USHORT usFlags;    /* XCAN_29BIT_ID, XCAN_REMOTE */
  UCHAR aucData[8];
} XCAN_MESSAGE;

/* ------------------------------------------------------------------------------------------
 * Services: data types, control commands, information requests
 * ------------------------------------------------------------------------------------------ */

#define DATA_UCHAR 1
#define DATA_USHORT 2
#define DATA_ULONG 4

#define CMD_START 1 /* max_channel_control */
#define CMD_STOP 2

#define INFO_DEVICE 1         /* max_channel_info: bus state word (bus-control device) */
#define INFO_XCAN_MSG_COUNT 2 /* frames sent (send objects) or received (receive objects) */

/* ------------------------------------------------------------------------------------------
 * Bus state word (error callback argument and INFO_DEVICE, §4): low word OR-ed state flags,
 * high word the last error code.
 * ------------------------------------------------------------------------------------------ */

#define XCAN_BUS_ON 0x0001     /* on the bus */
#define XCAN_BUS_HEAVY 0x0002  /* heavily disturbed: an error counter at the warning limit */
#define XCAN_BUS_OFF 0x0004    /* the controller took itself off the bus */
#define XCAN_LINE_ERROR 0x0008 /* line fault reported by the low-speed transceiver */

#define XCAN_LEC_NONE 0
#define XCAN_LEC_STUFF 1
#define XCAN_LEC_FORM 2
#define XCAN_LEC_ACK 3
#define XCAN_LEC_BIT1 4 /* sent recessive, read dominant */
#define XCAN_LEC_BIT0 5 /* sent dominant, read recessive */
#define XCAN_LEC_CRC 6

#define XCAN_STATUS(flags, lec) ((ULONG)(((ULONG)(lec) << 16) | ((ULONG)(flags)&0xFFFFu)))
#define XCAN_STATUS_FLAGS(status) ((USHORT)((status)&0xFFFFu))
#define XCAN_STATUS_LEC(status) ((USHORT)((status) >> 16))

/* ------------------------------------------------------------------------------------------
 * Error codes of the services. 0x21..0x2C carry the SL-CANi diagnosis code of the same
 * situation; 0x40.. have no SL-CANi counterpart.
 * ------------------------------------------------------------------------------------------ */

#define ERR_OK 0
#define ERR_XCAN_NO_MEMORY 0x21        /* no room for another object (diag 21h) */
#define ERR_XCAN_PARAM 0x24            /* bit-timing parameter out of range (diag 24h) */
#define ERR_XCAN_EXCL_LIMIT 0x27       /* a 14th XCAN_EXCL_BUFFER object or channel (diag 27h) */
#define ERR_XCAN_CPS_MISMATCH 0x28     /* the ID's object exists with another CPS (diag 28h) */
#define ERR_XCAN_MASK_EXCLUDES 0x29    /* the mask would lock configured objects out (diag 29h) */
#define ERR_XCAN_WRONG_TYPE 0x2A       /* service not defined for this channel (diag 2Ah) */
#define ERR_XCAN_FIFO_FULL 0x2B        /* the driver FIFO takes no more send requests (diag 2Bh) */
#define ERR_XCAN_BUFFER15_MIXED 0x2C   /* passive send and receive objects in buffer 15 (2Ch) */
#define ERR_XCAN_INVALID_CPS 0x40      /* device, interface, flags or timeout not allowed */
#define ERR_XCAN_ID_RANGE 0x41         /* identifier out of range for the interface's format */
#define ERR_XCAN_CHANNEL_BUSY 0x42     /* a second general-ID or acceptance-filter channel */
#define ERR_XCAN_TIMEOUT 0x43          /* usTimeout µs passed before the frame went or came */
#define ERR_XCAN_DATA_SIZE 0x44        /* block size not allowed (more than 8 bytes, ...) */
#define ERR_XCAN_INVALID_HANDLE 0x45   /* no such channel */
#define ERR_XCAN_INDEX 0x46            /* usIndexFirst/usIndexLast other than 0 (filter) */
#define ERR_XCAN_AUTO_ID_REQUIRED 0x47 /* filter: ulCanID must be XCAN_AUTO_ID */
#define ERR_XCAN_NOT_READY 0x48        /* bus off or switched off: no frame can go */
#define ERR_DATA_NOT_READY 0x50        /* XCAN_NEW_ONLY: no new data; sticky until cleared */

/* ------------------------------------------------------------------------------------------
 * Layout checks
 * ------------------------------------------------------------------------------------------ */

#if defined(__cplusplus)
static_assert(sizeof(CPS_XCAN) == 16, "CPS_XCAN must be 16 bytes");
static_assert(sizeof(XCAN_BITPARAMS) == 14, "XCAN_BITPARAMS must be 14 bytes");
static_assert(sizeof(XCAN_MESSAGE) == 16, "XCAN_MESSAGE must be 16 bytes");
#elif defined(__STDC_VERSION__) && (__STDC_VERSION__ >= 201112L)
_Static_assert(sizeof(CPS_XCAN) == 16, "CPS_XCAN must be 16 bytes");
_Static_assert(sizeof(XCAN_BITPARAMS) == 14, "XCAN_BITPARAMS must be 14 bytes");
_Static_assert(sizeof(XCAN_MESSAGE) == 16, "XCAN_MESSAGE must be 16 bytes");
#endif

#endif /* CANEMU_SORCUS_XCAN_TYPES_H */
