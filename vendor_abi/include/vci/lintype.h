/*
 * lintype.h - LIN constants and structures of the VCI API (canemu).
 *
 * This project's own declarations, binary-compatible with the LIN layouts of the IXXAT VCI SDK
 * (VCI V4). Valid C11 and C++.
 * Reference: the IXXAT "VCI: C++ Software Design Guide" section 8.4 (LIN data types); numeric
 * values the guide leaves out follow the vendor SDK (docs/vci.md).
 *
 * Packing: every structure is byte-packed (pack 1), as in the SDK.
 */
#ifndef CANEMU_VCI_LINTYPE_H
#define CANEMU_VCI_LINTYPE_H

#include "vcitype.h"

/* ------------------------------------------------------------------------------------------
 * Constants
 * ------------------------------------------------------------------------------------------ */

/* Controller type (VCI_LIN_CTRL(type) in VCIDEVICECAPS.BusCtrlTypes) */
#define LIN_CTRL_UNKNOWN 0  /* unknown (the only one the emulation reports) */
#define LIN_CTRL_MAXVAL 255 /* largest possible value */

/* Controller features (LINCAPABILITIES.dwFeatures) */
#define LIN_FEATURE_MASTER 0x0001   /* master mode */
#define LIN_FEATURE_AUTORATE 0x0002 /* automatic bit-rate detection */
#define LIN_FEATURE_ERRFRAME 0x0004 /* error messages */
#define LIN_FEATURE_BUSLOAD 0x0008  /* bus load measurement */
#define LIN_FEATURE_SLEEP 0x0010    /* go-to-sleep messages (master only) */
#define LIN_FEATURE_WAKEUP 0x0020   /* wake-up messages */

/* Operating modes (LININITLINE.bOpMode) */
#define LIN_OPMODE_SLAVE 0x00  /* slave mode (the default) */
#define LIN_OPMODE_MASTER 0x01 /* master mode */
#define LIN_OPMODE_ERRORS 0x02 /* report errors as error messages */

/* Bit rates (LININITLINE.wBitrate) */
#define LIN_BITRATE_UNDEF 65535 /* undefined */
#define LIN_BITRATE_AUTO 0      /* automatic detection (slave) */
#define LIN_BITRATE_MIN 1000    /* lowest bit rate */
#define LIN_BITRATE_MAX 20000   /* highest bit rate */
#define LIN_BITRATE_1000 1000
#define LIN_BITRATE_1200 1200
#define LIN_BITRATE_2400 2400
#define LIN_BITRATE_4800 4800
#define LIN_BITRATE_9600 9600
#define LIN_BITRATE_10400 10400
#define LIN_BITRATE_19200 19200
#define LIN_BITRATE_20000 20000

/* Line status (LINLINESTATUS.dwStatus). The guide also names LIN_STATUS_TXPEND, _ERRLIM and
 * _BUSOFF, but gives them no values and the SDK headers define none, so neither do we. */
#define LIN_STATUS_OVRRUN 0x01 /* data overrun */
#define LIN_STATUS_ININIT 0x10 /* init mode (stopped) */

/* Message types (LINMSGINFO.Bytes.bType) */
#define LIN_MSGTYPE_DATA 0   /* data message */
#define LIN_MSGTYPE_INFO 1   /* info message */
#define LIN_MSGTYPE_ERROR 2  /* error message */
#define LIN_MSGTYPE_STATUS 3 /* status message */
#define LIN_MSGTYPE_WAKEUP 4 /* wake-up (transmit only) */
#define LIN_MSGTYPE_SLEEP 5  /* go-to-sleep (transmit, master only) */
#define LIN_MSGTYPE_TMOVR 6  /* time stamp counter overflow */

/* Flags of LINMSGINFO.Bytes.bFlags */
#define LIN_MSGFLAGS_ECS 0x01 /* enhanced checksum (LIN 2.0) */
#define LIN_MSGFLAGS_SOR 0x02 /* this controller sent the response */
#define LIN_MSGFLAGS_OVR 0x04 /* receive FIFO overrun */
#define LIN_MSGFLAGS_IDO 0x08 /* ID only: transmit the header alone */

/* abData[0] of an info message */
#define LIN_INFO_START 1 /* controller started */
#define LIN_INFO_STOP 2  /* controller stopped */
#define LIN_INFO_RESET 3 /* controller reset */

/* abData[0] of an error message */
#define LIN_ERROR_BIT 1    /* bit error */
#define LIN_ERROR_CHKSUM 2 /* checksum error */
#define LIN_ERROR_PARITY 3 /* ID parity error */
#define LIN_ERROR_SLNORE 4 /* slave does not respond */
#define LIN_ERROR_SYNC 5   /* invalid sync field */
#define LIN_ERROR_NOBUS 6  /* no bus activity */
#define LIN_ERROR_OTHER 7  /* other error */

/* ------------------------------------------------------------------------------------------
 * Structures
 * ------------------------------------------------------------------------------------------ */

#pragma pack(push, 1)

/* Controller capabilities (12 bytes) */
typedef struct _LINCAPABILITIES {
  UINT32 dwFeatures;   /* LIN_FEATURE_* */
  UINT32 dwClockFreq;  /* clock in Hz */
  UINT32 dwTscDivisor; /* divisor of the time stamp counter */
} LINCAPABILITIES, *PLINCAPABILITIES;

/* Controller initialization (4 bytes) */
typedef struct _LININITLINE {
  UINT8 bOpMode;   /* LIN_OPMODE_* */
  UINT8 bReserved; /* 0 */
  UINT16 wBitrate; /* LIN_BITRATE_MIN .. LIN_BITRATE_MAX, or LIN_BITRATE_AUTO */
} LININITLINE, *PLININITLINE;

/* Line status (8 bytes) */
typedef struct _LINLINESTATUS {
  UINT8 bOpMode;   /* LIN_OPMODE_* */
  UINT8 bReserved; /* 0 */
  UINT16 wBitrate; /* current bit rate */
  UINT32 dwStatus; /* LIN_STATUS_* */
} LINLINESTATUS, *PLINLINESTATUS;

/* Message monitor status (17 bytes) */
typedef struct _LINMONITORSTATUS {
  LINLINESTATUS sLineStatus; /* controller line status */
  BOOL32 fActivated;         /* monitor active */
  BOOL32 fRxOverrun;         /* receive FIFO overrun */
  UINT8 bRxFifoLoad;         /* receive FIFO load in percent */
} LINMONITORSTATUS, *PLINMONITORSTATUS;

/* Message information (4 bytes). Bits are allocated from the least significant bit of the
 * little-endian word: pid 0-7, type 8-15, dlen 16-23, ecs 24, sor 25, ovr 26, ido 27,
 * res 28-31. */
typedef union _LINMSGINFO {
  struct {
    UINT8 bPid;   /* protected identifier */
    UINT8 bType;  /* LIN_MSGTYPE_* */
    UINT8 bDlen;  /* number of data bytes */
    UINT8 bFlags; /* LIN_MSGFLAGS_* */
  } Bytes;
  struct {
    UINT32 pid : 8;  /* protected identifier */
    UINT32 type : 8; /* LIN_MSGTYPE_* */
    UINT32 dlen : 8; /* number of data bytes */
    UINT32 ecs : 1;  /* enhanced checksum */
    UINT32 sor : 1;  /* sender of response (receive only) */
    UINT32 ovr : 1;  /* receive FIFO overrun (receive only) */
    UINT32 ido : 1;  /* ID only (transmit only) */
    UINT32 res : 4;  /* reserved, 0 */
  } Bits;
} LINMSGINFO, *PLINMSGINFO;

/* LIN message (16 bytes) */
typedef struct _LINMSG {
  UINT32 dwTime;       /* time stamp in ticks */
  LINMSGINFO uMsgInfo; /* identifier, type, length and flags */
  UINT8 abData[8];     /* data bytes */
} LINMSG, *PLINMSG;

#pragma pack(pop)

/* ------------------------------------------------------------------------------------------
 * Layout checks
 * ------------------------------------------------------------------------------------------ */

VCI_ASSERT_SIZE(LINCAPABILITIES, 12);
VCI_ASSERT_SIZE(LININITLINE, 4);
VCI_ASSERT_SIZE(LINLINESTATUS, 8);
VCI_ASSERT_SIZE(LINMONITORSTATUS, 17);
VCI_ASSERT_SIZE(LINMSGINFO, 4);
VCI_ASSERT_SIZE(LINMSG, 16);

#endif /* CANEMU_VCI_LINTYPE_H */
