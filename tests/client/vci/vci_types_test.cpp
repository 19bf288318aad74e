// vci_types_test.c as C++, where the tables and bit-rate objects are constants of each
// translation unit, so their values are checked at compile time too.
#define VCI_TYPES_TEST_NO_MAIN
#include "vci_types_test.c"

static_assert(CAN_EDLC_XLT[8] == 8 && CAN_EDLC_XLT[9] == 12 && CAN_EDLC_XLT[10] == 16 &&
                  CAN_EDLC_XLT[11] == 20 && CAN_EDLC_XLT[12] == 24 && CAN_EDLC_XLT[13] == 32 &&
                  CAN_EDLC_XLT[14] == 48 && CAN_EDLC_XLT[15] == 64,
              "ISO 11898-1 CAN FD lengths");
static_assert(CAN_ELEN_XLT[9] == 9 && CAN_ELEN_XLT[12] == 9 && CAN_ELEN_XLT[13] == 10 &&
                  CAN_ELEN_XLT[33] == 14 && CAN_ELEN_XLT[48] == 14 && CAN_ELEN_XLT[49] == 15,
              "the smallest DLC that holds a length");
static_assert(CAN_EDLC_TO_LEN(14) == 48 && CAN_LEN_TO_EDLC(20) == 11, "the macros are constant");
static_assert(sizeof(CAN_EDLC_XLT) == 16 && sizeof(CAN_ELEN_XLT) == 65, "table sizes");
static_assert(CAN_BITRATE_500KB.dwBPS == 500000 && CAN_BITRATE_500KB.wTS1 == 14 &&
                  CAN_BITRATE_500KB.wTS2 == 2,
              "500 kbit/s: 16 quanta, sampled after 14");
static_assert(CAN_BITRATE_1000KB.wTS1 + CAN_BITRATE_1000KB.wTS2 == 8, "1 Mbit/s: 8 quanta");
static_assert(CAN_BITRATE_NONE.dwBPS == 0 && CAN_BITRATE_NONE.wTS1 == 0, "no timing");

int main() {
  return run_checks();
}
