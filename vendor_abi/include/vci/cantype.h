/*
 * cantype.h - CAN constants and structures of the VCI API (canemu).
 *
 * This project's own declarations, binary-compatible with the CAN layouts of the IXXAT VCI SDK
 * (VCI V4, including the CAN FD "2" structures). Valid C11 and C++.
 * Reference: the IXXAT "VCI: C++ Software Design Guide" section 8.3 (CAN data types) and 5.2 (CAN
 * interface); numeric values the guide leaves out follow the vendor SDK (docs/vci.md).
 *
 * Packing: every structure is byte-packed (pack 1), as in the SDK.
 */
#ifndef CANEMU_VCI_CANTYPE_H
#define CANEMU_VCI_CANTYPE_H

#include "vcitype.h"

/* ------------------------------------------------------------------------------------------
 * Controller types (low byte of a CAN type word, CANCAPABILITIES.wCtrlType)
 * ------------------------------------------------------------------------------------------ */

#define CAN_CTRL_UNKNOWN 0  /* unknown */
#define CAN_CTRL_82527 1    /* Intel 82527 */
#define CAN_CTRL_82C200 2   /* Intel 82C200 */
#define CAN_CTRL_81C90 3    /* Intel 81C90 */
#define CAN_CTRL_81C92 4    /* Intel 81C92 */
#define CAN_CTRL_SJA1000 5  /* Philips SJA1000 */
#define CAN_CTRL_82C900 6   /* Infineon 82C900 (TwinCAN) */
#define CAN_CTRL_TOUCAN 7   /* Motorola TouCAN */
#define CAN_CTRL_MSCAN 8    /* Freescale MSCAN */
#define CAN_CTRL_FLEXCAN 9  /* Freescale FlexCAN */
#define CAN_CTRL_IFICAN 10  /* IFI CAN */
#define CAN_CTRL_BCCAN 11   /* Bosch C_CAN */
#define CAN_CTRL_BXCAN 12   /* ST bxCAN */
#define CAN_CTRL_IFICFD 13  /* IFI CAN FD */
#define CAN_CTRL_BMCAN 14   /* Bosch M_CAN */
#define CAN_CTRL_MAXVAL 255 /* largest possible value */

/* Bus coupling (CANCAPABILITIES.wBusCoupling) */
#define CAN_BUSC_UNDEFINED 0x0000 /* undefined */
#define CAN_BUSC_LOWSPEED 0x0001  /* low-speed coupling */
#define CAN_BUSC_HIGHSPEED 0x0002 /* high-speed coupling */

/* ------------------------------------------------------------------------------------------
 * Controller features (CANCAPABILITIES.dwFeatures, CANCAPABILITIES2.dwFeatures)
 * ------------------------------------------------------------------------------------------ */

#define CAN_FEATURE_STDOREXT 0x00000001   /* 11 or 29 bit IDs, not both at once */
#define CAN_FEATURE_STDANDEXT 0x00000002  /* 11 and 29 bit IDs at the same time */
#define CAN_FEATURE_RMTFRAME 0x00000004   /* remote frames */
#define CAN_FEATURE_ERRFRAME 0x00000008   /* error messages */
#define CAN_FEATURE_BUSLOAD 0x00000010    /* bus load measurement */
#define CAN_FEATURE_IDFILTER 0x00000020   /* exact filtering (ID list) */
#define CAN_FEATURE_LISTONLY 0x00000040   /* listen-only mode */
#define CAN_FEATURE_SCHEDULER 0x00000080  /* cyclic transmit list */
#define CAN_FEATURE_GENERRFRM 0x00000100  /* can generate error frames */
#define CAN_FEATURE_DELAYEDTX 0x00000200  /* delayed transmission */
#define CAN_FEATURE_SINGLESHOT 0x00000400 /* single-shot messages */
#define CAN_FEATURE_HIGHPRIOR 0x00000800  /* high-priority messages */
#define CAN_FEATURE_AUTOBAUD 0x00001000   /* automatic bit-rate detection */
#define CAN_FEATURE_EXTDATA 0x00002000    /* data field longer than 8 bytes (CAN FD) */
#define CAN_FEATURE_FASTDATA 0x00004000   /* fast data bit rate (CAN FD) */
#define CAN_FEATURE_ISOFRAME 0x00008000   /* ISO CAN FD frames */
#define CAN_FEATURE_NONISOFRM 0x00010000  /* non-ISO CAN FD frames */
#define CAN_FEATURE_64BITTSC 0x00020000   /* 64-bit time stamp counter */

/* ------------------------------------------------------------------------------------------
 * Operating modes (CANINITLINE[2].bOpMode, .bExMode)
 * ------------------------------------------------------------------------------------------ */

#define CAN_OPMODE_UNDEFINED 0x00 /* undefined */
#define CAN_OPMODE_STANDARD 0x01  /* 11-bit IDs */
#define CAN_OPMODE_EXTENDED 0x02  /* 29-bit IDs */
#define CAN_OPMODE_ERRFRAME 0x04  /* report bus errors as error messages */
#define CAN_OPMODE_LISTONLY 0x08  /* listen-only */
#define CAN_OPMODE_LOWSPEED 0x10  /* low-speed bus coupling */
#define CAN_OPMODE_AUTOBAUD 0x20  /* automatic bit-rate detection */

#define CAN_EXMODE_DISABLED 0x00 /* no extended mode (mandatory on non-FD controllers) */
#define CAN_EXMODE_EXTDATA 0x01  /* data field up to 64 bytes */
#define CAN_EXMODE_FASTDATA 0x02 /* fast data-phase bit rate */
#define CAN_EXMODE_NONISO 0x04   /* non-ISO CAN FD frames */

/* ------------------------------------------------------------------------------------------
 * Bit timing
 * ------------------------------------------------------------------------------------------ */

/* SJA1000 bus timing registers BTR0/BTR1 at 16 MHz (CANINITLINE, CANLINESTATUS). */
#define CAN_BT0_5KB 0x3F
#define CAN_BT1_5KB 0x7F
#define CAN_BT0_10KB 0x31
#define CAN_BT1_10KB 0x1C
#define CAN_BT0_20KB 0x18
#define CAN_BT1_20KB 0x1C
#define CAN_BT0_50KB 0x09
#define CAN_BT1_50KB 0x1C
#define CAN_BT0_100KB 0x04
#define CAN_BT1_100KB 0x1C
#define CAN_BT0_125KB 0x03
#define CAN_BT1_125KB 0x1C
#define CAN_BT0_250KB 0x01
#define CAN_BT1_250KB 0x1C
#define CAN_BT0_500KB 0x00
#define CAN_BT1_500KB 0x1C
#define CAN_BT0_667KB 0x00 /* VCI V4 addition: 12 quanta, 666.7 kbit/s */
#define CAN_BT1_667KB 0x18
#define CAN_BT0_800KB 0x00
#define CAN_BT1_800KB 0x16
#define CAN_BT0_1000KB 0x00
#define CAN_BT1_1000KB 0x14

/* The same pairs as "BTR0, BTR1", for an argument list or an initializer:
 *   canControlInitialize(hCtl, mode, CAN_BT01_500KB);  UINT8 btr[2] = {CAN_BT01_500KB}; */
#define CAN_BT01_5KB 0x3F, 0x7F
#define CAN_BT01_10KB 0x31, 0x1C
#define CAN_BT01_20KB 0x18, 0x1C
#define CAN_BT01_50KB 0x09, 0x1C
#define CAN_BT01_100KB 0x04, 0x1C
#define CAN_BT01_125KB 0x03, 0x1C
#define CAN_BT01_250KB 0x01, 0x1C
#define CAN_BT01_500KB 0x00, 0x1C
#define CAN_BT01_800KB 0x00, 0x16
#define CAN_BT01_1000KB 0x00, 0x14

/* CANBTP.dwMode */
#define CAN_BTMODE_RAW 0x00000001 /* raw controller values: dwBPS is the prescaler */
#define CAN_BTMODE_TSM 0x00000002 /* triple sampling */

/* CANBTP initializers {dwMode, dwBPS, wTS1, wTS2, wSJW, wTDO}:
 *   CANBTP nominal = CAN_BTP_500KB;
 * In the bit/s form wTS1 counts the synchronization quantum too: a bit is wTS1 + wTS2 quanta,
 * sampled after wTS1. CAN_BTP_EMPTY is all zero (no timing, e.g. no fast data phase). The
 * same values as CANBTP objects: CAN_BITRATE_NONE, CAN_BITRATE_5KB, ... (after the
 * structures). */
#define CAN_BTP_EMPTY \
  { 0, 0, 0, 0, 0, 0 }
#define CAN_BTP_5KB \
  { 0, 5000, 17, 8, 1, 0 }
#define CAN_BTP_10KB \
  { 0, 10000, 14, 2, 1, 0 }
#define CAN_BTP_20KB \
  { 0, 20000, 14, 2, 1, 0 }
#define CAN_BTP_50KB \
  { 0, 50000, 14, 2, 1, 0 }
#define CAN_BTP_100KB \
  { 0, 100000, 14, 2, 1, 0 }
#define CAN_BTP_125KB \
  { 0, 125000, 14, 2, 1, 0 }
#define CAN_BTP_250KB \
  { 0, 250000, 14, 2, 1, 0 }
#define CAN_BTP_500KB \
  { 0, 500000, 14, 2, 1, 0 }
#define CAN_BTP_800KB \
  { 0, 800000, 8, 2, 1, 0 }
#define CAN_BTP_1000KB \
  { 0, 1000000, 6, 2, 1, 0 }

/* Entries of CANBTRTABLE and CANBTPTABLE (the vendor's spelling). */
#define CAN_BTR_TABEL_SIZE 64
#define CAN_BTP_TABEL_SIZE 64

/* ------------------------------------------------------------------------------------------
 * Message filter
 * ------------------------------------------------------------------------------------------ */

/* Filter selection (bSelect) */
#define CAN_FILTER_STD 1 /* 11-bit filter */
#define CAN_FILTER_EXT 2 /* 29-bit filter */

/* Filter modes */
#define CAN_FILTER_VOID 0x00 /* invalid or unknown */
#define CAN_FILTER_LOCK 0x01 /* block all data messages */
#define CAN_FILTER_PASS 0x02 /* pass all data messages */
#define CAN_FILTER_INCL 0x03 /* pass messages that the filter accepts */
#define CAN_FILTER_EXCL 0x04 /* block messages that the filter accepts */
#define CAN_FILTER_SRRA 0x80 /* flag: pass self-reception messages of other channels */

/* Acceptance filter code/mask values; a filter value is (ID << 1) | RTR. */
#define CAN_ACC_MASK_ALL 0x00000000 /* with CODE_ALL: accept every ID */
#define CAN_ACC_CODE_ALL 0x00000000
#define CAN_ACC_MASK_NONE 0xFFFFFFFFu /* with CODE_NONE: accept no ID */
#define CAN_ACC_CODE_NONE 0x80000000u

/* Default size of the ID lists */
#define CAN_FILTER_SIZE_STD 2048
#define CAN_FILTER_SIZE_EXT 2048

/* ------------------------------------------------------------------------------------------
 * Status values
 * ------------------------------------------------------------------------------------------ */

/* CANLINESTATUS[2].dwStatus */
#define CAN_STATUS_TXPEND 0x01  /* transmission pending */
#define CAN_STATUS_OVRRUN 0x02  /* data overrun in the controller */
#define CAN_STATUS_ERRLIM 0x04  /* error warning limit exceeded */
#define CAN_STATUS_BUSOFF 0x08  /* bus-off */
#define CAN_STATUS_ININIT 0x10  /* init mode (stopped) */
#define CAN_STATUS_BUSCERR 0x20 /* bus coupling error */

/* CANSCHEDULERSTATUS[2].bTaskStat */
#define CAN_CTXTSK_STAT_STOPPED 0 /* transmit task stopped */
#define CAN_CTXTSK_STAT_RUNNING 1 /* transmit task running */

/* CANSCHEDULERSTATUS[2].abMsgStat[] */
#define CAN_CTXMSG_STAT_EMPTY 0 /* slot unused */
#define CAN_CTXMSG_STAT_BUSY 1  /* message being processed */
#define CAN_CTXMSG_STAT_DONE 2  /* processing completed */

/* ------------------------------------------------------------------------------------------
 * Cyclic transmit list
 * ------------------------------------------------------------------------------------------ */

#define CAN_MAX_CTX_MSGS 16 /* number of cyclic transmit objects */

/* CANCYCLICTXMSG[2].bIncrMode */
#define CAN_CTXMSG_INC_NO 0 /* no increment */
#define CAN_CTXMSG_INC_ID 1 /* increment dwMsgId */
#define CAN_CTXMSG_INC_8 2  /* increment the 8-bit value at abData[bByteIndex] */
#define CAN_CTXMSG_INC_16 3 /* increment the 16-bit value at abData[bByteIndex] (LSB first) */

/* ------------------------------------------------------------------------------------------
 * Messages
 * ------------------------------------------------------------------------------------------ */

/* Message types (CANMSGINFO.Bytes.bType) */
#define CAN_MSGTYPE_DATA 0    /* data message */
#define CAN_MSGTYPE_INFO 1    /* info message */
#define CAN_MSGTYPE_ERROR 2   /* error message */
#define CAN_MSGTYPE_STATUS 3  /* status message */
#define CAN_MSGTYPE_WAKEUP 4  /* reserved */
#define CAN_MSGTYPE_TIMEOVR 5 /* time stamp counter overflow */
#define CAN_MSGTYPE_TIMERST 6 /* reserved */

/* Flags of CANMSGINFO.Bytes.bFlags */
#define CAN_MSGFLAGS_DLC 0x0F /* data length code */
#define CAN_MSGFLAGS_OVR 0x10 /* receive FIFO overrun */
#define CAN_MSGFLAGS_SRR 0x20 /* self-reception request */
#define CAN_MSGFLAGS_RTR 0x40 /* remote transmission request */
#define CAN_MSGFLAGS_EXT 0x80 /* 29-bit ID */

/* CANMSGINFO.Bytes.bFlags from its fields (each 0 or 1, dlc 0..15). */
#define CAN_MAKE_MSGFLAGS(dlc, ovr, srr, rtr, ext)                                             \
  ((UINT8)((((UINT32)(ext)&1u) << 7) | (((UINT32)(rtr)&1u) << 6) | (((UINT32)(srr)&1u) << 5) | \
           (((UINT32)(ovr)&1u) << 4) | ((UINT32)(dlc)&0x0Fu)))

/* Flags of CANMSGINFO.Bytes.bFlags2 */
#define CAN_MSGFLAGS2_SSM 0x01 /* single-shot */
#define CAN_MSGFLAGS2_HPM 0x02 /* high priority */
#define CAN_MSGFLAGS2_EDL 0x04 /* extended data length (CAN FD frame) */
#define CAN_MSGFLAGS2_FDR 0x08 /* fast data rate (bit-rate switch) */
#define CAN_MSGFLAGS2_ESI 0x10 /* error state indicator (receive only) */
#define CAN_MSGFLAGS2_RES 0xE0 /* reserved, 0 */

/* CANMSGINFO.Bytes.bFlags2 from its fields (each 0 or 1). */
#define CAN_MAKE_MSGFLAGS2(ssm, hpm, edl, fdr, esi)                                            \
  ((UINT8)((((UINT32)(esi)&1u) << 4) | (((UINT32)(fdr)&1u) << 3) | (((UINT32)(edl)&1u) << 2) | \
           (((UINT32)(hpm)&1u) << 1) | ((UINT32)(ssm)&1u)))

/* Acceptance result (CANMSGINFO.Bytes.bAccept) */
#define CAN_ACCEPT_REJECT 0x00   /* rejected */
#define CAN_ACCEPT_ALWAYS 0xFF   /* non-data message: always accepted */
#define CAN_ACCEPT_FILTER_1 0x01 /* accepted by the acceptance filter */
#define CAN_ACCEPT_FILTER_2 0x02 /* accepted by the ID list */
#define CAN_ACCEPT_PASSEXCL 0x03 /* passed the filter in mode CAN_FILTER_EXCL */
/* The guide's spellings of the same values */
#define CAN_ACCEPT_FILTER1 CAN_ACCEPT_FILTER_1
#define CAN_ACCEPT_FILTER2 CAN_ACCEPT_FILTER_2
#define CAN_ACCEPT_EXCL CAN_ACCEPT_PASSEXCL

/* dwMsgId of non-data messages */
#define CAN_MSGID_INFO 0xFFFFFFFFu   /* info message */
#define CAN_MSGID_ERROR 0xFFFFFFFFu  /* error message */
#define CAN_MSGID_STATUS 0xFFFFFFFFu /* status message */
#define CAN_MSGID_WAKEUP 0xFFFFFFFFu /* wake-up message */

#define CAN_MSGID_MASK11 0x000007FF   /* valid bits of an 11-bit ID */
#define CAN_MSGID_MASK29 0x1FFFFFFF   /* valid bits of a 29-bit ID */
#define CAN_MSGID_INVALID 0xE0000000u /* bits no valid ID has */

/* abData[0] of an info message */
#define CAN_INFO_START 1 /* controller started */
#define CAN_INFO_STOP 2  /* controller stopped */
#define CAN_INFO_RESET 3 /* controller reset */

/* abData[0] of an error message */
#define CAN_ERROR_NONE 0  /* no error */
#define CAN_ERROR_STUFF 1 /* stuff error */
#define CAN_ERROR_FORM 2  /* form error */
#define CAN_ERROR_ACK 3   /* acknowledgment error */
#define CAN_ERROR_BIT 4   /* bit error */
#define CAN_ERROR_FDB 5   /* fast data bit error (CAN FD) */
#define CAN_ERROR_CRC 6   /* CRC error */
#define CAN_ERROR_DLC 7   /* data length error */
#define CAN_ERROR_OTHER 8 /* other error */

/* ------------------------------------------------------------------------------------------
 * Structures
 * ------------------------------------------------------------------------------------------ */

#pragma pack(push, 1)

/* Bit timing parameters (16 bytes) */
typedef struct _CANBTP {
  UINT32 dwMode; /* CAN_BTMODE_* */
  UINT32 dwBPS;  /* bit rate in bit/s, or the prescaler with CAN_BTMODE_RAW */
  UINT16 wTS1;   /* time segment 1 in quanta (raw mode: without SYNC) */
  UINT16 wTS2;   /* time segment 2 in quanta */
  UINT16 wSJW;   /* synchronization jump width in quanta */
  UINT16 wTDO;   /* transceiver delay compensation offset (fast data rate only) */
} CANBTP, *PCANBTP;

/* Controller capabilities, v1 (32 bytes) */
typedef struct _CANCAPABILITIES {
  UINT16 wCtrlType;     /* CAN_CTRL_* */
  UINT16 wBusCoupling;  /* CAN_BUSC_* */
  UINT32 dwFeatures;    /* CAN_FEATURE_* */
  UINT32 dwClockFreq;   /* primary clock in Hz */
  UINT32 dwTscDivisor;  /* divisor of the time stamp counter */
  UINT32 dwCmsDivisor;  /* divisor of the scheduler tick, 0 = no scheduler */
  UINT32 dwCmsMaxTicks; /* maximum scheduler cycle in ticks, 0 = no scheduler */
  UINT32 dwDtxDivisor;  /* divisor of the delayed-transmit tick, 0 = unsupported */
  UINT32 dwDtxMaxTicks; /* maximum transmit delay in ticks, 0 = unsupported */
} CANCAPABILITIES, *PCANCAPABILITIES;

/* Controller capabilities, v2 (108 bytes) */
typedef struct _CANCAPABILITIES2 {
  UINT16 wCtrlType;     /* CAN_CTRL_* */
  UINT16 wBusCoupling;  /* CAN_BUSC_* */
  UINT32 dwFeatures;    /* CAN_FEATURE_* */
  UINT32 dwCanClkFreq;  /* CAN clock in Hz */
  CANBTP sSdrRangeMin;  /* minimum raw nominal bit timing */
  CANBTP sSdrRangeMax;  /* maximum raw nominal bit timing */
  CANBTP sFdrRangeMin;  /* minimum raw data bit timing, all 0 without fast data */
  CANBTP sFdrRangeMax;  /* maximum raw data bit timing, all 0 without fast data */
  UINT32 dwTscClkFreq;  /* time stamp counter clock in Hz */
  UINT32 dwTscDivisor;  /* divisor of the time stamp counter */
  UINT32 dwCmsClkFreq;  /* scheduler clock in Hz, 0 = no scheduler */
  UINT32 dwCmsDivisor;  /* divisor of the scheduler tick */
  UINT32 dwCmsMaxTicks; /* maximum scheduler cycle in ticks */
  UINT32 dwDtxClkFreq;  /* delayed-transmit clock in Hz, 0 = unsupported */
  UINT32 dwDtxDivisor;  /* divisor of the delayed-transmit tick */
  UINT32 dwDtxMaxTicks; /* maximum transmit delay in ticks */
} CANCAPABILITIES2, *PCANCAPABILITIES2;

/* Controller initialization, v1 (4 bytes) */
typedef struct _CANINITLINE {
  UINT8 bOpMode;   /* CAN_OPMODE_* */
  UINT8 bReserved; /* 0 */
  UINT8 bBtReg0;   /* SJA1000 BTR0 */
  UINT8 bBtReg1;   /* SJA1000 BTR1 */
} CANINITLINE, *PCANINITLINE;

/* Controller initialization, v2 (44 bytes) */
typedef struct _CANINITLINE2 {
  UINT8 bOpMode;  /* CAN_OPMODE_* */
  UINT8 bExMode;  /* CAN_EXMODE_* */
  UINT8 bSFMode;  /* default mode of the 11-bit filter, CAN_FILTER_* */
  UINT8 bEFMode;  /* default mode of the 29-bit filter, CAN_FILTER_* */
  UINT32 dwSFIds; /* number of IDs of the 11-bit filter, 0 = no filter */
  UINT32 dwEFIds; /* number of IDs of the 29-bit filter, 0 = no filter */
  CANBTP sBtpSdr; /* nominal (arbitration) bit timing */
  CANBTP sBtpFdr; /* data-phase bit timing */
} CANINITLINE2, *PCANINITLINE2;

/* BTR table for bit-rate detection (130 bytes) */
typedef struct _CANBTRTABLE {
  UINT8 bCount;     /* number of valid entries */
  UINT8 bIndex;     /* in: CAN_OPMODE_LOWSPEED or 0; out: index found */
  UINT8 abBtr0[64]; /* BTR0 values */
  UINT8 abBtr1[64]; /* BTR1 values */
} CANBTRTABLE, *PCANBTRTABLE;

/* CANBTP table for bit-rate detection (2050 bytes) */
typedef struct _CANBTPTABLE {
  UINT8 bCount; /* number of valid entries */
  UINT8 bIndex; /* out: index found */
  struct {
    CANBTP sSdr; /* nominal bit timing */
    CANBTP sFdr; /* data bit timing (fast data only) */
  } asBTP[64];
} CANBTPTABLE, *PCANBTPTABLE;

/* Line status, v1 (8 bytes) */
typedef struct _CANLINESTATUS {
  UINT8 bOpMode;   /* CAN_OPMODE_* */
  UINT8 bBtReg0;   /* SJA1000 BTR0 */
  UINT8 bBtReg1;   /* SJA1000 BTR1 */
  UINT8 bBusLoad;  /* bus load in percent */
  UINT32 dwStatus; /* CAN_STATUS_* */
} CANLINESTATUS, *PCANLINESTATUS;

/* Line status, v2 (40 bytes) */
typedef struct _CANLINESTATUS2 {
  UINT8 bOpMode;   /* CAN_OPMODE_* */
  UINT8 bExMode;   /* CAN_EXMODE_* */
  UINT8 bBusLoad;  /* bus load in percent */
  UINT8 bReserved; /* 0 */
  CANBTP sBtpSdr;  /* nominal bit timing */
  CANBTP sBtpFdr;  /* data bit timing */
  UINT32 dwStatus; /* CAN_STATUS_* */
} CANLINESTATUS2, *PCANLINESTATUS2;

/* Message channel status, v1 (18 bytes) */
typedef struct _CANCHANSTATUS {
  CANLINESTATUS sLineStatus; /* controller line status */
  BOOL32 fActivated;         /* channel active */
  BOOL32 fRxOverrun;         /* receive FIFO overrun */
  UINT8 bRxFifoLoad;         /* receive FIFO load in percent */
  UINT8 bTxFifoLoad;         /* transmit FIFO load in percent */
} CANCHANSTATUS, *PCANCHANSTATUS;

/* Message channel status, v2 (44 bytes) */
typedef struct _CANCHANSTATUS2 {
  CANLINESTATUS2 sLineStatus; /* controller line status */
  BOOL8 fActivated;           /* channel active */
  BOOL8 fRxOverrun;           /* receive FIFO overrun */
  UINT8 bRxFifoLoad;          /* receive FIFO load in percent */
  UINT8 bTxFifoLoad;          /* transmit FIFO load in percent */
} CANCHANSTATUS2, *PCANCHANSTATUS2;

/* Run-time information of a controller (16 bytes) */
typedef struct _CANRTINFO {
  UINT32 dwNumChannels; /* channels open on the controller */
  UINT32 dwActChannels; /* of which activated */
  UINT32 dwLockStatus;  /* CAN_RTI_LOCKSTAT_* */
  UINT16 wRxFifoLoad;   /* device receive FIFO load in percent */
  UINT16 wTxFifoLoad;   /* device transmit FIFO load in percent */
} CANRTINFO, *PCANRTINFO;

/* Cyclic transmit list status, v1 (17 bytes) */
typedef struct _CANSCHEDULERSTATUS {
  UINT8 bTaskStat;                   /* CAN_CTXTSK_STAT_* */
  UINT8 abMsgStat[CAN_MAX_CTX_MSGS]; /* CAN_CTXMSG_STAT_* per list index */
} CANSCHEDULERSTATUS, *PCANSCHEDULERSTATUS;

/* Cyclic transmit list status, v2 (57 bytes) */
typedef struct _CANSCHEDULERSTATUS2 {
  CANLINESTATUS2 sLineStatus;        /* controller line status */
  UINT8 bTaskStat;                   /* CAN_CTXTSK_STAT_* */
  UINT8 abMsgStat[CAN_MAX_CTX_MSGS]; /* CAN_CTXMSG_STAT_* per list index */
} CANSCHEDULERSTATUS2, *PCANSCHEDULERSTATUS2;

/* Message information (4 bytes). Bits are allocated from the least significant bit of the
 * little-endian word: type 0-7, ssm 8, hpm 9, edl 10, fdr 11, esi 12, res 13-15, dlc 16-19,
 * ovr 20, srr 21, rtr 22, ext 23, afc 24-31. */
typedef union _CANMSGINFO {
  struct {
    UINT8 bType; /* CAN_MSGTYPE_* */
    union {
      UINT8 bReserved; /* v1 name: 0 */
      UINT8 bFlags2;   /* CAN_MSGFLAGS2_* */
    };
    UINT8 bFlags;  /* CAN_MSGFLAGS_* */
    UINT8 bAccept; /* CAN_ACCEPT_* (receive only) */
  } Bytes;
  struct {
    UINT32 type : 8; /* CAN_MSGTYPE_* */
    UINT32 ssm : 1;  /* single-shot */
    UINT32 hpm : 1;  /* high priority */
    UINT32 edl : 1;  /* extended data length (CAN FD) */
    UINT32 fdr : 1;  /* fast data rate */
    UINT32 esi : 1;  /* error state indicator (receive only) */
    UINT32 res : 3;  /* reserved, 0 */
    UINT32 dlc : 4;  /* data length code */
    UINT32 ovr : 1;  /* receive FIFO overrun (receive only) */
    UINT32 srr : 1;  /* self-reception request */
    UINT32 rtr : 1;  /* remote transmission request */
    UINT32 ext : 1;  /* 29-bit ID */
    UINT32 afc : 8;  /* CAN_ACCEPT_* (receive only) */
  } Bits;
} CANMSGINFO, *PCANMSGINFO;

/* CAN message, v1 (20 bytes) */
typedef struct _CANMSG {
  UINT32 dwTime;       /* receive: time stamp in ticks; transmit: delay in ticks */
  UINT32 dwMsgId;      /* CAN ID, right-aligned, without RTR bit */
  CANMSGINFO uMsgInfo; /* type and flags */
  UINT8 abData[8];     /* data bytes */
} CANMSG, *PCANMSG;

/* CAN message, v2 (80 bytes) */
typedef struct _CANMSG2 {
  UINT32 dwTime;       /* receive: time stamp in ticks; transmit: delay in ticks */
  UINT32 _rsvd_;       /* reserved, 0 */
  UINT32 dwMsgId;      /* CAN ID, right-aligned, without RTR bit */
  CANMSGINFO uMsgInfo; /* type and flags */
  UINT8 abData[64];    /* data bytes */
} CANMSG2, *PCANMSG2;

/* Cyclic transmit message, v1 (20 bytes) */
typedef struct _CANCYCLICTXMSG {
  UINT16 wCycleTime;   /* cycle time in scheduler ticks, 1 .. dwCmsMaxTicks */
  UINT8 bIncrMode;     /* CAN_CTXMSG_INC_* */
  UINT8 bByteIndex;    /* data byte incremented by INC_8 / INC_16 */
  UINT32 dwMsgId;      /* CAN ID */
  CANMSGINFO uMsgInfo; /* type and flags */
  UINT8 abData[8];     /* data bytes */
} CANCYCLICTXMSG, *PCANCYCLICTXMSG;

/* Cyclic transmit message, v2 (76 bytes) */
typedef struct _CANCYCLICTXMSG2 {
  UINT16 wCycleTime;   /* cycle time in scheduler ticks, 1 .. dwCmsMaxTicks */
  UINT8 bIncrMode;     /* CAN_CTXMSG_INC_* */
  UINT8 bByteIndex;    /* data byte incremented by INC_8 / INC_16 */
  UINT32 dwMsgId;      /* CAN ID */
  CANMSGINFO uMsgInfo; /* type and flags */
  UINT8 abData[64];    /* data bytes */
} CANCYCLICTXMSG2, *PCANCYCLICTXMSG2;

#pragma pack(pop)

/* CANRTINFO.dwLockStatus */
#define CAN_RTI_LOCKSTAT_CTL 0x00000001u /* the control unit is held */
#define CAN_RTI_LOCKSTAT_SHD 0x00000002u /* the cyclic transmit list is held */
#define CAN_RTI_LOCKSTAT_CHN 0x80000000u /* an exclusive channel is open */

/* ------------------------------------------------------------------------------------------
 * Tables and bit-rate objects
 *
 * CAN_EDLC_XLT[dlc]: data bytes of a CAN FD DLC (0..15); CAN_ELEN_XLT[len]: the smallest DLC
 * that holds len bytes (0..64). CAN_BITRATE_*: the CAN_BTP_* timings as CANBTP objects.
 * In C++ each translation unit gets its own const (C++11: constexpr) copy. In C they are objects
 * with external linkage: a program may define them in one of its files (#define INIT_CAN_EDLC_XLT
 * and/or INIT_CAN_BITRATES before including this header, as with the vendor's header); otherwise
 * the definitions exported by libvcinpl.so, libvcinpl2.so and libvciapi.so serve.
 * ------------------------------------------------------------------------------------------ */

#define CAN_SDLC_MAX 8  /* largest classic DLC */
#define CAN_SLEN_MAX 8  /* longest classic data field */
#define CAN_EDLC_MAX 15 /* largest CAN FD DLC */
#define CAN_ELEN_MAX 64 /* longest CAN FD data field */

#define CANEMU_CAN_EDLC_XLT_VALUES \
  { 0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64 }
#define CANEMU_CAN_ELEN_XLT_VALUES                                                                 \
  {                                                                                                \
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 9, 10, 10, 10, 10, 11, 11, 11, 11, 12, 12, 12, 12, 13, 13, \
        13, 13, 13, 13, 13, 13, 14, 14, 14, 14, 14, 14, 14, 14, 14, 14, 14, 14, 14, 14, 14, 14,    \
        15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15                             \
  }

/* C++11 and later: constexpr, usable in constant expressions. */
#if defined(__cplusplus) && __cplusplus >= 201103L
#define CANEMU_CAN_CONST constexpr
#else
#define CANEMU_CAN_CONST const
#endif

#if defined(__cplusplus) || defined(INIT_CAN_EDLC_XLT)
CANEMU_CAN_CONST UINT8 CAN_EDLC_XLT[CAN_EDLC_MAX + 1] = CANEMU_CAN_EDLC_XLT_VALUES;
CANEMU_CAN_CONST UINT8 CAN_ELEN_XLT[CAN_ELEN_MAX + 1] = CANEMU_CAN_ELEN_XLT_VALUES;
#else
extern const UINT8 CAN_EDLC_XLT[CAN_EDLC_MAX + 1];
extern const UINT8 CAN_ELEN_XLT[CAN_ELEN_MAX + 1];
#endif

#if defined(__cplusplus) || defined(INIT_CAN_BITRATES)
CANEMU_CAN_CONST CANBTP CAN_BITRATE_NONE = CAN_BTP_EMPTY;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_5KB = CAN_BTP_5KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_10KB = CAN_BTP_10KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_20KB = CAN_BTP_20KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_50KB = CAN_BTP_50KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_100KB = CAN_BTP_100KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_125KB = CAN_BTP_125KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_250KB = CAN_BTP_250KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_500KB = CAN_BTP_500KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_800KB = CAN_BTP_800KB;
CANEMU_CAN_CONST CANBTP CAN_BITRATE_1000KB = CAN_BTP_1000KB;
#else
extern const CANBTP CAN_BITRATE_NONE;
extern const CANBTP CAN_BITRATE_5KB;
extern const CANBTP CAN_BITRATE_10KB;
extern const CANBTP CAN_BITRATE_20KB;
extern const CANBTP CAN_BITRATE_50KB;
extern const CANBTP CAN_BITRATE_100KB;
extern const CANBTP CAN_BITRATE_125KB;
extern const CANBTP CAN_BITRATE_250KB;
extern const CANBTP CAN_BITRATE_500KB;
extern const CANBTP CAN_BITRATE_800KB;
extern const CANBTP CAN_BITRATE_1000KB;
#endif

/* DLC <-> length. Out-of-range arguments (negative ones too) give the largest value. */
#define CAN_SDLC_TO_LEN(dlc) ((UINT32)(dlc) <= CAN_SDLC_MAX ? (UINT8)(dlc) : (UINT8)CAN_SLEN_MAX)
#define CAN_EDLC_TO_LEN(dlc) \
  ((UINT32)(dlc) <= CAN_EDLC_MAX ? CAN_EDLC_XLT[(UINT32)(dlc)] : (UINT8)CAN_ELEN_MAX)
#define CAN_LEN_TO_SDLC(len) ((UINT32)(len) <= CAN_SLEN_MAX ? (UINT8)(len) : (UINT8)CAN_SDLC_MAX)
#define CAN_LEN_TO_EDLC(len) \
  ((UINT32)(len) <= CAN_ELEN_MAX ? CAN_ELEN_XLT[(UINT32)(len)] : (UINT8)CAN_EDLC_MAX)

/* ------------------------------------------------------------------------------------------
 * Layout checks
 * ------------------------------------------------------------------------------------------ */

VCI_ASSERT_SIZE(CANBTP, 16);
VCI_ASSERT_SIZE(CANCAPABILITIES, 32);
VCI_ASSERT_SIZE(CANCAPABILITIES2, 108);
VCI_ASSERT_SIZE(CANINITLINE, 4);
VCI_ASSERT_SIZE(CANINITLINE2, 44);
VCI_ASSERT_SIZE(CANBTRTABLE, 130);
VCI_ASSERT_SIZE(CANBTPTABLE, 2050);
VCI_ASSERT_SIZE(CANLINESTATUS, 8);
VCI_ASSERT_SIZE(CANLINESTATUS2, 40);
VCI_ASSERT_SIZE(CANCHANSTATUS, 18);
VCI_ASSERT_SIZE(CANCHANSTATUS2, 44);
VCI_ASSERT_SIZE(CANRTINFO, 16);
VCI_ASSERT_SIZE(CANSCHEDULERSTATUS, 17);
VCI_ASSERT_SIZE(CANSCHEDULERSTATUS2, 57);
VCI_ASSERT_SIZE(CANMSGINFO, 4);
VCI_ASSERT_SIZE(CANMSG, 20);
VCI_ASSERT_SIZE(CANMSG2, 80);
VCI_ASSERT_SIZE(CANCYCLICTXMSG, 20);
VCI_ASSERT_SIZE(CANCYCLICTXMSG2, 76);

#endif /* CANEMU_VCI_CANTYPE_H */
