/*
 * xcan_talk: one X-CAN-2i interface on a canemu bus, programmed the way the SORCUS manual's
 * code does it (chapter 10.9.2): load the MDD, set the bit timing on the bus-control device,
 * open a send object and a receive object, send, and print what comes.
 *
 *   xcan_talk DEVICE INTERFACE SEND_ID RECEIVE_ID [COUNT]
 *
 * Sends COUNT (default 3) data frames with SEND_ID (each waits until it went, at most 50 ms),
 * printing every frame with RECEIVE_ID that comes meanwhile and the bus state on errors. The
 * bit rate is 500 kbit/s, as on the buses of canemud's default configuration. Built with
 *   cc xcan_talk.c $(pkg-config --cflags --libs canemu-xcan)
 */
#define _POSIX_C_SOURCE 200809L /* flockfile, also with -std=c11 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "xcan.h"

static void on_receive(MAX_HANDLE hChan, ULONG ulSize, const void* pData) {
  const UCHAR* data = (const UCHAR*)pData;
  ULONG i;
  /* The callback runs on the library's thread: the line is written whole (POSIX stream lock),
     never mixed with what the main thread prints meanwhile. */
  flockfile(stdout);
  printf("channel %lu: %lu bytes:", (unsigned long)hChan, (unsigned long)ulSize);
  for (i = 0; i < ulSize; ++i) {
    printf(" %02X", data[i]);
  }
  printf("\n");
  fflush(stdout);
  funlockfile(stdout);
}

static void on_bus_error(MAX_HANDLE hChan, ULONG ulSize, const void* pData) {
  ULONG status = 0;
  (void)hChan;
  if (ulSize == sizeof status) {
    memcpy(&status, pData, sizeof status);
  }
  printf("bus state %04X, last error code %u\n", XCAN_STATUS_FLAGS(status),
         XCAN_STATUS_LEC(status));
  fflush(stdout);
}

static int check(ULONG Error, const char* what) {
  if (Error != ERR_OK) {
    fprintf(stderr, "xcan_talk: %s: error 0x%02lX\n", what, (unsigned long)Error);
    return 0;
  }
  return 1;
}

/* The number `text` (decimal, or hex with 0x) in *value; else a message naming `what`. */
static int number(const char* text, const char* what, unsigned long max, ULONG* value) {
  char* end = NULL;
  const unsigned long v = strtoul(text, &end, 0);
  if (*text == '\0' || *text == '-' || *end != '\0' || v > max) {
    fprintf(stderr, "xcan_talk: %s \"%s\": a number from 0 to %lu\n", what, text, max);
    return 0;
  }
  *value = (ULONG)v;
  return 1;
}

int main(int argc, char** argv) {
  MAX_HANDLE hModul, hMDD, hBus, hSend, hReceive;
  CPS_XCAN cps;
  XCAN_BITPARAMS bits = {125, 12, 3, 1, 1, 0, 11}; /* 16 x 125 ns: 500 kbit/s */
  ULONG Error, ulSize, count = 0, ulInterface, ulSendId, ulReceiveId, ulCount = 3;
  USHORT usChannel;
  ULONG i;

  if (argc < 5) {
    fprintf(stderr, "usage: xcan_talk DEVICE INTERFACE SEND_ID RECEIVE_ID [COUNT]\n");
    return 2;
  }
  if (!number(argv[2], "INTERFACE", 1, &ulInterface) ||
      !number(argv[3], "SEND_ID", 0x1FFFFFFF, &ulSendId) ||
      !number(argv[4], "RECEIVE_ID", 0x1FFFFFFF, &ulReceiveId) ||
      (argc > 5 && !number(argv[5], "COUNT", 1000000, &ulCount)))
    return 2;
  usChannel = (USHORT)ulInterface;

  if (!check(canemu_open_module(argv[1], &hModul), "module"))
    return 1;
  Error = max_load_mdd(hModul, 1, 0, 0, 0x803A, NULL, &hMDD);
  if (!check(Error, "max_load_mdd"))
    return 1;

  /* Bus-control device: bit timing, error callback. */
  memset(&cps, 0, sizeof cps);
  cps.usDevice = DEVICE_CTRL;
  cps.usChannel = usChannel;
  cps.usIndexFirst = cps.usIndexLast = XCAN_BUS_CTRL_INDEX;
  if (!check(max_open_channel(hMDD, &cps, on_bus_error, &hBus), "bus control"))
    return 1;
  ulSize = sizeof bits;
  if (!check(max_write_channel_block(hBus, &ulSize, &bits), "bit timing"))
    return 1;

  /* Active send object: waits in the output service until its frame went. */
  memset(&cps, 0, sizeof cps);
  cps.usDevice = DEVICE_BUS_OUT;
  cps.usChannel = usChannel;
  cps.usFlags = XCAN_NO_INT;
  cps.usTimeout = 50000;
  cps.ulCanID = ulSendId;
  if (!check(max_open_channel(hMDD, &cps, NULL, &hSend), "send object"))
    return 1;

  /* Passive receive object: every frame comes to the callback. */
  memset(&cps, 0, sizeof cps);
  cps.usDevice = DEVICE_BUS_IN;
  cps.usChannel = usChannel;
  cps.ulCanID = ulReceiveId;
  if (!check(max_open_channel(hMDD, &cps, on_receive, &hReceive), "receive object"))
    return 1;

  for (i = 0; i < ulCount; ++i) {
    UCHAR arcData[8] = {0x11, 0x22, 0x33, (UCHAR)i};
    ulSize = 4;
    Error = max_write_channel_block(hSend, &ulSize, arcData);
    if (Error == ERR_XCAN_TIMEOUT) {
      printf("frame %lu: not acknowledged within 50 ms\n", (unsigned long)i);
    } else if (!check(Error, "send")) {
      break;
    }
  }
  if (check(max_channel_info(hSend, INFO_XCAN_MSG_COUNT, &count), "count")) {
    printf("%lu frames sent\n", (unsigned long)count);
  }
  max_close_channel(hReceive);
  max_close_channel(hSend);
  max_close_channel(hBus);
  return 0;
}
