/*
 * The vendor names of cantype.h, vcierr.h, vcitype.h and lintype.h as a VCI program uses them,
 * in C (this file) and C++ (vci_types_test.cpp includes it). The expected values are derived
 * here independently where that is possible: DLC lengths from ISO 11898-1 (CAN FD), bit rates
 * from the SJA1000's BTR0/BTR1 layout at 16 MHz, result codes from the HRESULT layout.
 * Compile-time checks where the value is a constant expression, run-time checks otherwise;
 * the program prints what fails and exits 1.
 */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "cantype.h"
#include "lintype.h"
#include "vcierr.h"
#include "vcitype.h"

static int failures = 0;

#define CHECK(cond)                                             \
  do {                                                          \
    if (!(cond)) {                                              \
      printf("%s:%d: failed: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                               \
    }                                                           \
  } while (0)

/* ---- constants -------------------------------------------------------------------------- */

VCI_STATIC_ASSERT(CAN_MSGID_INVALID == 0xE0000000u, "no valid ID has bits 29..31");
VCI_STATIC_ASSERT((CAN_MSGID_INVALID & CAN_MSGID_MASK29) == 0, "INVALID is outside every ID");
VCI_STATIC_ASSERT(CAN_MAKE_MSGFLAGS(8, 0, 1, 0, 1) == 0xA8, "dlc 8, srr, ext");
VCI_STATIC_ASSERT(CAN_MAKE_MSGFLAGS(15, 1, 1, 1, 1) == 0xFF, "all flags");
VCI_STATIC_ASSERT(CAN_MAKE_MSGFLAGS(3, 0, 0, 1, 0) == (3 | CAN_MSGFLAGS_RTR),
                  "rtr is CAN_MSGFLAGS_RTR");
VCI_STATIC_ASSERT(CAN_MAKE_MSGFLAGS2(0, 0, 1, 1, 0) == (CAN_MSGFLAGS2_EDL | CAN_MSGFLAGS2_FDR),
                  "edl and fdr");
VCI_STATIC_ASSERT(CAN_MAKE_MSGFLAGS2(1, 1, 1, 1, 1) == 0x1F, "all flags2");
VCI_STATIC_ASSERT(CAN_SDLC_MAX == 8 && CAN_SLEN_MAX == 8, "classic CAN: 8 bytes");
VCI_STATIC_ASSERT(CAN_EDLC_MAX == 15 && CAN_ELEN_MAX == 64, "CAN FD: DLC 15, 64 bytes");
VCI_STATIC_ASSERT(CAN_SDLC_TO_LEN(5) == 5 && CAN_SDLC_TO_LEN(12) == 8, "classic DLC > 8: 8");
VCI_STATIC_ASSERT(CAN_LEN_TO_SDLC(7) == 7 && CAN_LEN_TO_SDLC(9) == 8, "classic length > 8");
VCI_STATIC_ASSERT(CAN_SDLC_TO_LEN(-1) == 8 && CAN_LEN_TO_SDLC(-3) == 8, "negative: the maximum");
VCI_STATIC_ASSERT(CAN_BTR_TABEL_SIZE == 64 && CAN_BTP_TABEL_SIZE == 64, "table sizes");
VCI_STATIC_ASSERT(sizeof(CANRTINFO) == 16, "CANRTINFO: 16 bytes");
VCI_STATIC_ASSERT(offsetof(CANRTINFO, dwLockStatus) == 8, "dwLockStatus at 8");
VCI_STATIC_ASSERT(offsetof(CANRTINFO, wTxFifoLoad) == 14, "wTxFifoLoad at 14");
VCI_STATIC_ASSERT(CAN_RTI_LOCKSTAT_CTL == 1 && CAN_RTI_LOCKSTAT_SHD == 2 &&
                      CAN_RTI_LOCKSTAT_CHN == 0x80000000u,
                  "lock status bits");
VCI_STATIC_ASSERT(LIN_CTRL_MAXVAL == 255 && CAN_CTRL_MAXVAL == 255, "controller type limits");

/* Result codes: severity error (3 << 30) | customer flag | facility 1 | code. */
VCI_STATIC_ASSERT(VCI_SUCCESS == 0 && VCI_OK == 0, "success");
VCI_STATIC_ASSERT((UINT32)VCI_E_TIMEOUT == ((3u << 30) | (1u << 29) | (1u << 16) | 0x0Bu),
                  "VCI_E_TIMEOUT");
VCI_STATIC_ASSERT(_VCI_ERROR(0x000B) == VCI_E_TIMEOUT, "_VCI_ERROR builds the codes");
VCI_STATIC_ASSERT((UINT32)SEV_VCI_ERROR == 0xE0010000u, "error severity of the VCI");
VCI_STATIC_ASSERT((UINT32)SEV_VCI_WARN == 0xA0010000u, "warning severity of the VCI");
VCI_STATIC_ASSERT((UINT32)SEV_VCI_INFO == 0x60010000u, "info severity of the VCI");
VCI_STATIC_ASSERT(GETSCODE(VCI_E_TIMEOUT) == 0x0B, "code part");
VCI_STATIC_ASSERT(GETFACILITY(VCI_E_TIMEOUT) == FACILITY_VCI && FACILITY_VCI == 1, "facility");
VCI_STATIC_ASSERT(GETSEVERITY(VCI_E_TIMEOUT) == SEV_ERROR && SEV_ERROR == 3, "severity");
VCI_STATIC_ASSERT(_IS_VCI_SCODE(VCI_E_TIMEOUT) && !_IS_VCI_SCODE(0x80004005u), "VCI codes");
VCI_STATIC_ASSERT(VCI_E_INVALID_FIRMWARE == VCI_E_WRONG_FLASHFWVERSION, "one code, two names");
VCI_STATIC_ASSERT((UINT32)VCI_E_INVALID_LICENSE == 0xE001001Bu, "0x1B");
VCI_STATIC_ASSERT((UINT32)VCI_E_INVALID_TIMING == 0xE001001Fu, "0x1F");
VCI_STATIC_ASSERT((UINT32)VCI_E_NOT_SUPPORTED == 0xE0010025u, "0x25");
VCI_STATIC_ASSERT((UINT32)VCI_E_LUIDS_EXHAUSTED == 0xE001002Au, "0x2A, the last one");
VCI_STATIC_ASSERT(VCI_FAILED(VCI_E_LUIDS_EXHAUSTED) && VCI_SUCCEEDED(VCI_SUCCESS), "signs");

/* Type words: bus type in the high byte, controller in the low byte. */
VCI_STATIC_ASSERT(VCI_CAN_SJA1000 == 0x0105, "CAN, SJA1000");
VCI_STATIC_ASSERT(VCI_CAN_IFICFD == 0x010D && VCI_CAN_BMCAN == 0x010E, "CAN FD controllers");
VCI_STATIC_ASSERT(VCI_CAN_82C90 == VCI_CAN_81C90 && VCI_CAN_IFI == VCI_CAN_IFICAN, "old names");
VCI_STATIC_ASSERT(VCI_LIN_UNKNOWN == 0x0200 && VCI_KLN_UNKNOWN == 0x0400, "LIN, K-Line");
VCI_STATIC_ASSERT(offsetof(VCIVERSIONINFO, VciRevNumber) == 8 &&
                      offsetof(VCIVERSIONINFO, VciReleaseNumber) == 8 &&
                      sizeof(VCIVERSIONINFO) == 32,
                  "the revision field under both names");

/* ---- tables and bit-rate objects -------------------------------------------------------- */

/* Data bytes of a CAN FD DLC (ISO 11898-1): 0..8 as is, then 12, 16, 20, 24, 32, 48, 64. */
static unsigned fd_length(unsigned dlc) {
  static const unsigned above8[7] = {12, 16, 20, 24, 32, 48, 64};
  return dlc <= 8 ? dlc : above8[dlc - 9];
}

static void check_dlc_tables(void) {
  unsigned dlc;
  unsigned len;
  for (dlc = 0; dlc <= 15; ++dlc) {
    CHECK(CAN_EDLC_XLT[dlc] == fd_length(dlc));
    CHECK(CAN_EDLC_TO_LEN(dlc) == fd_length(dlc));
  }
  for (len = 0; len <= 64; ++len) {
    unsigned smallest = 0; /* the smallest DLC whose data field holds len bytes */
    while (fd_length(smallest) < len) {
      ++smallest;
    }
    CHECK(CAN_ELEN_XLT[len] == smallest);
    CHECK(CAN_LEN_TO_EDLC(len) == smallest);
  }
  CHECK(CAN_EDLC_TO_LEN(9) == 12);
  CHECK(CAN_EDLC_TO_LEN(13) == 32);
  CHECK(CAN_EDLC_TO_LEN(16) == 64); /* out of range: the maximum */
  CHECK(CAN_LEN_TO_EDLC(17) == 11);
  CHECK(CAN_LEN_TO_EDLC(65) == 15);
  CHECK(CAN_LEN_TO_EDLC(-1) == 15);
  CHECK(sizeof CAN_EDLC_XLT == 16 && sizeof CAN_ELEN_XLT == 65);
}

/* The SJA1000 at 16 MHz: tq = 2 * (BRP + 1) / 16 MHz with BRP = BTR0 bits 0-5; a bit is
 * 1 + TSEG1 + TSEG2 quanta with TSEG1 = (BTR1 bits 0-3) + 1, TSEG2 = (BTR1 bits 4-6) + 1. */
static unsigned sja1000_quanta(UINT8 btr1) {
  return 1u + ((btr1 & 0x0Fu) + 1u) + (((btr1 >> 4) & 0x07u) + 1u);
}
static unsigned sja1000_bps(UINT8 btr0, UINT8 btr1) {
  return 8000000u / (((btr0 & 0x3Fu) + 1u) * sja1000_quanta(btr1));
}
static unsigned sja1000_sample_quanta(UINT8 btr1) { /* quanta before the sample point */
  return 1u + (btr1 & 0x0Fu) + 1u;
}

/* Takes a BT01 pair as two arguments, as canControlInitialize does. */
static unsigned bps_of_pair(UINT8 btr0, UINT8 btr1) {
  return sja1000_bps(btr0, btr1);
}

struct rate {
  unsigned bps;
  UINT8 btr[2];
  UINT8 btr0;
  UINT8 btr1;
  const CANBTP* object;
  CANBTP macro;
};

static void check_bit_rates(void) {
  const struct rate rates[] = {
      {5000, {CAN_BT01_5KB}, CAN_BT0_5KB, CAN_BT1_5KB, &CAN_BITRATE_5KB, CAN_BTP_5KB},
      {10000, {CAN_BT01_10KB}, CAN_BT0_10KB, CAN_BT1_10KB, &CAN_BITRATE_10KB, CAN_BTP_10KB},
      {20000, {CAN_BT01_20KB}, CAN_BT0_20KB, CAN_BT1_20KB, &CAN_BITRATE_20KB, CAN_BTP_20KB},
      {50000, {CAN_BT01_50KB}, CAN_BT0_50KB, CAN_BT1_50KB, &CAN_BITRATE_50KB, CAN_BTP_50KB},
      {100000, {CAN_BT01_100KB}, CAN_BT0_100KB, CAN_BT1_100KB, &CAN_BITRATE_100KB, CAN_BTP_100KB},
      {125000, {CAN_BT01_125KB}, CAN_BT0_125KB, CAN_BT1_125KB, &CAN_BITRATE_125KB, CAN_BTP_125KB},
      {250000, {CAN_BT01_250KB}, CAN_BT0_250KB, CAN_BT1_250KB, &CAN_BITRATE_250KB, CAN_BTP_250KB},
      {500000, {CAN_BT01_500KB}, CAN_BT0_500KB, CAN_BT1_500KB, &CAN_BITRATE_500KB, CAN_BTP_500KB},
      {800000, {CAN_BT01_800KB}, CAN_BT0_800KB, CAN_BT1_800KB, &CAN_BITRATE_800KB, CAN_BTP_800KB},
      {1000000,
       {CAN_BT01_1000KB},
       CAN_BT0_1000KB,
       CAN_BT1_1000KB,
       &CAN_BITRATE_1000KB,
       CAN_BTP_1000KB},
  };
  const CANBTP empty = CAN_BTP_EMPTY;
  const CANBTP zero = {0, 0, 0, 0, 0, 0};
  size_t i;
  for (i = 0; i < sizeof rates / sizeof rates[0]; ++i) {
    const struct rate* r = &rates[i];
    CHECK(r->btr[0] == r->btr0 && r->btr[1] == r->btr1);
    CHECK(sja1000_bps(r->btr[0], r->btr[1]) == r->bps);
    /* The CANBTP form describes the same bit: as many quanta, the same sample point. */
    CHECK(r->macro.dwMode == 0 && r->macro.dwBPS == r->bps);
    CHECK(r->macro.wTS1 + r->macro.wTS2 == sja1000_quanta(r->btr1));
    CHECK(r->macro.wTS1 == sja1000_sample_quanta(r->btr1));
    CHECK(r->macro.wSJW == 1 && r->macro.wTDO == 0);
    CHECK(memcmp(r->object, &r->macro, sizeof(CANBTP)) == 0);
  }
  /* The classic rates of the task: 1000, 500, 250, 125 and 100 kbit/s. */
  CHECK(bps_of_pair(CAN_BT01_1000KB) == 1000000);
  CHECK(bps_of_pair(CAN_BT01_500KB) == 500000);
  CHECK(bps_of_pair(CAN_BT01_250KB) == 250000);
  CHECK(bps_of_pair(CAN_BT01_125KB) == 125000);
  CHECK(bps_of_pair(CAN_BT01_100KB) == 100000);
  CHECK(memcmp(&empty, &zero, sizeof zero) == 0);
  CHECK(memcmp(&CAN_BITRATE_NONE, &zero, sizeof zero) == 0);
}

static void check_message_flags(void) {
  CANMSGINFO info;
  memset(&info, 0, sizeof info);
  info.Bytes.bFlags = CAN_MAKE_MSGFLAGS(5, 1, 0, 1, 0);
  info.Bytes.bFlags2 = CAN_MAKE_MSGFLAGS2(1, 0, 1, 0, 1);
  CHECK(info.Bits.dlc == 5 && info.Bits.ovr == 1 && info.Bits.srr == 0);
  CHECK(info.Bits.rtr == 1 && info.Bits.ext == 0);
  CHECK(info.Bits.ssm == 1 && info.Bits.hpm == 0 && info.Bits.edl == 1 && info.Bits.fdr == 0);
  CHECK(info.Bits.esi == 1);
  CHECK(CAN_MAKE_MSGFLAGS(16, 2, 0, 0, 0) == 0); /* each field masked to its width */
}

static int run_checks(void) {
  check_dlc_tables();
  check_bit_rates();
  check_message_flags();
  if (failures == 0) {
    printf("all checks passed\n");
  }
  return failures == 0 ? 0 : 1;
}

#ifndef VCI_TYPES_TEST_NO_MAIN
int main(void) {
  return run_checks();
}
#endif
