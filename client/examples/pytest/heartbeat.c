/*
 * A small ECU-like program under test, through the VCI C API (libvcinpl):
 *   heartbeat ADAPTER COUNT
 * sends a heartbeat frame (ID 100h, one byte counting up) every 10 ms on the adapter's first CAN
 * controller at 500 kbit/s until COUNT have gone out. When the controller goes bus-off it says
 * so, restarts the line (reset, start: the controller comes back after 128 x 11 recessive bits)
 * and says when it is back. Prints one line per event; exits 0 when done, 1 on an API failure.
 * Plain C99; the ADAPTER is the canemu device name, as in "USB-to-CAN (canemu NAME)".
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <vcinpl.h>

static int fail(const char* what, HRESULT hr) {
  char text[256];
  vciFormatError(hr, text, sizeof text);
  fprintf(stderr, "heartbeat: %s: %s\n", what, text);
  return 1;
}

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

static void pause_ms(long ms) {
  struct timespec t = {ms / 1000, (ms % 1000) * 1000000L};
  nanosleep(&t, NULL);
}

int main(int argc, char** argv) {
  HANDLE hDevice = NULL;
  HANDLE hControl = NULL;
  HANDLE hChannel = NULL;
  VCIID id;
  CANMSG msg;
  CANLINESTATUS line;
  HRESULT hr;
  unsigned sent = 0;
  unsigned count;
  int off = 0;
  if (argc != 3) {
    fprintf(stderr, "usage: heartbeat ADAPTER COUNT\n");
    return 2;
  }
  count = (unsigned)strtoul(argv[2], NULL, 10);
  if ((hr = vciInitialize()) != VCI_OK) {
    return fail("canemud", hr);
  }
  if ((hr = find(argv[1], &id)) != VCI_OK) {
    return fail(argv[1], hr);
  }
  if ((hr = vciDeviceOpen(&id, &hDevice)) != VCI_OK ||
      (hr = canChannelOpen(hDevice, 0, FALSE, &hChannel)) != VCI_OK ||
      (hr = canChannelInitialize(hChannel, 16, 1, 16, 1)) != VCI_OK ||
      (hr = canChannelActivate(hChannel, TRUE)) != VCI_OK ||
      (hr = canControlOpen(hDevice, 0, &hControl)) != VCI_OK ||
      (hr = canControlInitialize(hControl, CAN_OPMODE_STANDARD, CAN_BT0_500KB, CAN_BT1_500KB)) !=
          VCI_OK ||
      (hr = canControlStart(hControl, TRUE)) != VCI_OK) {
    return fail("open", hr);
  }
  printf("running\n");
  fflush(stdout);
  while (sent < count) {
    if ((hr = canControlGetStatus(hControl, &line)) != VCI_OK) {
      return fail("status", hr);
    }
    if ((line.dwStatus & CAN_STATUS_BUSOFF) != 0 && !off) {
      off = 1;
      printf("bus-off after %u frames\n", sent);
      fflush(stdout);
      if ((hr = canControlReset(hControl)) != VCI_OK ||
          (hr = canControlInitialize(hControl, CAN_OPMODE_STANDARD, CAN_BT0_500KB,
                                     CAN_BT1_500KB)) != VCI_OK ||
          (hr = canControlStart(hControl, TRUE)) != VCI_OK) {
        return fail("restart", hr);
      }
    } else if ((line.dwStatus & CAN_STATUS_BUSOFF) == 0 && off) {
      off = 0;
      printf("back on the bus\n");
      fflush(stdout);
    }
    if (!off) {
      memset(&msg, 0, sizeof msg);
      msg.dwMsgId = 0x100;
      msg.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
      msg.uMsgInfo.Bits.dlc = 1;
      msg.abData[0] = (UINT8)sent;
      if ((hr = canChannelSendMessage(hChannel, 1000, &msg)) != VCI_OK) {
        return fail("send", hr);
      }
      ++sent;
    }
    pause_ms(10);
  }
  printf("sent %u\n", sent);
  canControlClose(hControl);
  canChannelClose(hChannel);
  vciDeviceClose(hDevice);
  return 0;
}
