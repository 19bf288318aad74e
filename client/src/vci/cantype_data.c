/* The objects cantype.h declares for C programs (CAN_EDLC_XLT, CAN_ELEN_XLT, CAN_BITRATE_*),
 * defined once here and exported by every VCI library, so that a C program needs no
 * INIT_CAN_EDLC_XLT / INIT_CAN_BITRATES file of its own (one that has it keeps its own). */
#define INIT_CAN_EDLC_XLT
#define INIT_CAN_BITRATES
#include "cantype.h"
