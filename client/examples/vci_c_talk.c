/*
 * Two programs, two adapters, one bus, through the VCI C API (libvcinpl):
 *   vci_c_talk receive ADAPTER        waits up to 5 s for a data frame and prints it
 *   vci_c_talk send ADAPTER ID BYTE   sends one frame with one data byte
 *   vci_c_talk lin ADAPTER ID BYTE    a LIN responder on the adapter's first LIN controller:
 *                                     answers the header ID with BYTE and prints the first
 *                                     three frames or errors it sees (docs/lin.md)
 * ADAPTER is the canemu device name (as in "USB-to-CAN (canemu NAME)"). Plain C99.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <vcinpl.h>

static int fail(const char* what, HRESULT hr) {
  char text[256];
  vciFormatError(hr, text, sizeof text);
  fprintf(stderr, "%s: %s\n", what, text);
  return 1;
}

/* The VCIID of the adapter whose description names `name`. */
static HRESULT find(const char* name, VCIID* id) {
  HANDLE hEnum = NULL;
  VCIDEVICEINFO info;
  char want[64];
  HRESULT hr = vciEnumDeviceOpen(&hEnum);
  if (hr != VCI_OK) {
    return hr;
  }
  snprintf(want, sizeof want, "(canemu %s)", name);
  hr = VCI_E_NO_MORE_ITEMS;
  while (vciEnumDeviceNext(hEnum, &info) == VCI_OK) {
    if (strstr(info.Description, want) != NULL) {
      *id = info.VciObjectId;
      hr = VCI_OK;
    }
  }
  vciEnumDeviceClose(hEnum);
  return hr;
}

/* A LIN responder: the response table holds ID -> BYTE; prints what the bus shows. */
static int lin_responder(HANDLE hDevice, UINT8 id, UINT8 byte) {
  HANDLE hControl = NULL;
  HANDLE hMonitor = NULL;
  VCIDEVICECAPS caps;
  LINMSG msg;
  HRESULT hr;
  UINT32 no = 0;
  int seen = 0;
  if ((hr = vciDeviceGetCaps(hDevice, &caps)) != VCI_OK) {
    return fail("caps", hr);
  }
  while (no < caps.BusCtrlCount && VCI_BUS_TYPE(caps.BusCtrlTypes[no]) != VCI_BUS_LIN) {
    ++no; /* LIN controllers come after the CAN ones */
  }
  memset(&msg, 0, sizeof msg);
  msg.uMsgInfo.Bytes.bPid = id;
  msg.uMsgInfo.Bytes.bType = LIN_MSGTYPE_DATA;
  msg.uMsgInfo.Bytes.bDlen = 1;
  msg.uMsgInfo.Bits.ecs = 1;
  msg.abData[0] = byte;
  if ((hr = linMonitorOpen(hDevice, no, FALSE, &hMonitor)) != VCI_OK ||
      (hr = linMonitorInitialize(hMonitor, 64, 1)) != VCI_OK ||
      (hr = linMonitorActivate(hMonitor, TRUE)) != VCI_OK ||
      (hr = linControlOpen(hDevice, no, &hControl)) != VCI_OK ||
      (hr = linControlInitialize(hControl, LIN_OPMODE_ERRORS, 19200)) != VCI_OK ||
      (hr = linControlWriteMessage(hControl, FALSE, &msg)) != VCI_OK ||
      (hr = linControlStart(hControl, TRUE)) != VCI_OK) {
    return fail("LIN", hr);
  }
  printf("ready\n");
  fflush(stdout);
  while (seen < 3) {
    if ((hr = linMonitorReadMessage(hMonitor, 5000, &msg)) != VCI_OK) {
      return fail("receive", hr);
    }
    if (msg.uMsgInfo.Bytes.bType == LIN_MSGTYPE_DATA) {
      printf("%u us: %02X#%02X%s\n", (unsigned)msg.dwTime, msg.uMsgInfo.Bytes.bPid, msg.abData[0],
             msg.uMsgInfo.Bits.sor ? " (mine)" : "");
      ++seen;
    } else if (msg.uMsgInfo.Bytes.bType == LIN_MSGTYPE_ERROR) {
      printf("%u us: error %u\n", (unsigned)msg.dwTime, msg.abData[0]);
      ++seen;
    }
  }
  linControlClose(hControl);
  linMonitorClose(hMonitor);
  return 0;
}

int main(int argc, char** argv) {
  HANDLE hDevice = NULL;
  HANDLE hControl = NULL;
  HANDLE hChannel = NULL;
  VCIID id;
  CANMSG msg;
  HRESULT hr;
  int sending;
  if (argc < 3 || (strcmp(argv[1], "receive") != 0 && argc != 5)) {
    fprintf(stderr,
            "usage: vci_c_talk receive ADAPTER | send ADAPTER ID BYTE | lin ADAPTER ID BYTE\n");
    return 2;
  }
  sending = strcmp(argv[1], "send") == 0;
  if ((hr = vciInitialize()) != VCI_OK) {
    return fail("canemud", hr);
  }
  if ((hr = find(argv[2], &id)) == VCI_E_NO_MORE_ITEMS) {
    fprintf(stderr,
            "no adapter named %s: canemud's configuration has no [[device]] of that name "
            "(config/examples/two-adapters.toml has alpha and beta)\n",
            argv[2]);
    return 1;
  }
  if (hr != VCI_OK) {
    return fail("adapter", hr);
  }
  if (strcmp(argv[1], "lin") == 0) {
    if ((hr = vciDeviceOpen(&id, &hDevice)) != VCI_OK) {
      return fail("open", hr);
    }
    const int rc = lin_responder(hDevice, (UINT8)strtoul(argv[3], NULL, 16),
                                 (UINT8)strtoul(argv[4], NULL, 16));
    vciDeviceClose(hDevice);
    return rc;
  }
  if ((hr = vciDeviceOpen(&id, &hDevice)) != VCI_OK ||
      (hr = canChannelOpen(hDevice, 0, FALSE, &hChannel)) != VCI_OK ||
      (hr = canChannelInitialize(hChannel, 256, 1, 16, 1)) != VCI_OK ||
      (hr = canChannelActivate(hChannel, TRUE)) != VCI_OK ||
      (hr = canControlOpen(hDevice, 0, &hControl)) != VCI_OK ||
      (hr = canControlInitialize(hControl, CAN_OPMODE_STANDARD, CAN_BT0_500KB, CAN_BT1_500KB)) !=
          VCI_OK ||
      (hr = canControlStart(hControl, TRUE)) != VCI_OK) {
    return fail("open", hr);
  }
  if (sending) {
    memset(&msg, 0, sizeof msg);
    msg.dwMsgId = (UINT32)strtoul(argv[3], NULL, 16);
    msg.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
    msg.uMsgInfo.Bits.dlc = 1;
    msg.abData[0] = (UINT8)strtoul(argv[4], NULL, 16);
    msg.uMsgInfo.Bits.srr = 1; /* its echo says when it has gone out */
    if ((hr = canChannelSendMessage(hChannel, 1000, &msg)) != VCI_OK) {
      return fail("send", hr);
    }
    do {
      if ((hr = canChannelReadMessage(hChannel, 5000, &msg)) != VCI_OK) {
        return fail("echo", hr);
      }
    } while (msg.uMsgInfo.Bytes.bType != CAN_MSGTYPE_DATA);
  } else {
    printf("ready\n");
    fflush(stdout);
    for (;;) {
      if ((hr = canChannelReadMessage(hChannel, 5000, &msg)) != VCI_OK) {
        return fail("receive", hr);
      }
      if (msg.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
        printf("%03X#%02X\n", (unsigned)msg.dwMsgId, msg.abData[0]);
        break;
      }
    }
  }
  canControlClose(hControl);
  canChannelClose(hChannel);
  vciDeviceClose(hDevice);
  return 0;
}
