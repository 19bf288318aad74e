// The VCI C++ walk-through as a program: choose adapters from the device list, open the BAL,
// a CAN socket with a message channel and the control unit, initialize 500 kbit/s, start, send
// a frame through one adapter and receive it with the other, waiting on an event.
//
// Written as for IXXAT's SDK on Windows: only <windows.h> is left out (vcisdk.h brings the
// event functions). Run it against canemud with two adapters on one bus, e.g.
//   CANEMU_SOCKET=$XDG_RUNTIME_DIR/canemu.sock ./vci_walkthrough
#include <stdio.h>
#include <string.h>

#include <vcisdk.h>

static IBalObject* OpenBal(IVciDeviceManager* pDevMgr, IVciEnumDevice* pEnum) {
  VCIDEVICEINFO sInfo;
  IVciDevice* pDevice = NULL;
  IBalObject* pBal = NULL;
  if (pEnum->Next(1, &sInfo, NULL) != VCI_OK) {
    return NULL;
  }
  printf("adapter: %s\n", sInfo.Description);
  if (pDevMgr->OpenDevice(sInfo.VciObjectId, &pDevice) == VCI_OK) {
    pDevice->OpenComponent(CLSID_VCIBAL, IID_IBalObject, (void**)&pBal);
    pDevice->Release();  // the BAL keeps what it needs
  }
  return pBal;
}

struct Line {
  ICanChannel* pChannel;
  ICanControl* pControl;
  IFifoReader* pReader;
  IFifoWriter* pWriter;
};

static HRESULT InitSocket(IBalObject* pBal, Line* pLine) {
  ICanSocket* pSocket = NULL;
  HRESULT hResult = pBal->OpenSocket(0, IID_ICanSocket, (void**)&pSocket);
  if (hResult == VCI_OK) {
    hResult = pSocket->CreateChannel(FALSE, &pLine->pChannel);
    pSocket->Release();
  }
  if (hResult == VCI_OK) {
    hResult = pLine->pChannel->Initialize(1024, 128);
  }
  if (hResult == VCI_OK) {
    hResult = pLine->pChannel->GetReader(&pLine->pReader);
  }
  if (hResult == VCI_OK) {
    pLine->pReader->SetThreshold(1);
    hResult = pLine->pChannel->GetWriter(&pLine->pWriter);
  }
  if (hResult == VCI_OK) {
    hResult = pLine->pChannel->Activate();
  }
  if (hResult == VCI_OK) {
    hResult = pBal->OpenSocket(0, IID_ICanControl, (void**)&pLine->pControl);
  }
  if (hResult == VCI_OK) {
    CANINITLINE sInit;
    sInit.bOpMode = CAN_OPMODE_STANDARD | CAN_OPMODE_ERRFRAME;
    sInit.bReserved = 0;
    sInit.bBtReg0 = CAN_BT0_500KB;
    sInit.bBtReg1 = CAN_BT1_500KB;
    hResult = pLine->pControl->InitLine(&sInit);
  }
  if (hResult == VCI_OK) {
    hResult = pLine->pControl->StartLine();
  }
  return hResult;
}

static BOOL TransmitByte(IFifoWriter* pWriter, UINT32 dwId, UINT8 bData) {
  CANMSG sCanMsg;
  memset(&sCanMsg, 0, sizeof(sCanMsg));
  sCanMsg.dwTime = 0;  // at once
  sCanMsg.dwMsgId = dwId;
  sCanMsg.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  sCanMsg.uMsgInfo.Bits.dlc = 1;
  sCanMsg.abData[0] = bData;
  return pWriter->PutDataEntry(&sCanMsg) == VCI_OK;
}

static void CloseLine(Line* pLine) {
  if (pLine->pControl)
    pLine->pControl->Release();
  if (pLine->pReader)
    pLine->pReader->Release();
  if (pLine->pWriter)
    pLine->pWriter->Release();
  if (pLine->pChannel)
    pLine->pChannel->Release();
}

int main() {
  IVciDeviceManager* pDevMgr = NULL;
  IVciEnumDevice* pEnum = NULL;
  char szError[256];
  HRESULT hResult = VciInitialize();
  if (hResult == VCI_OK) {
    hResult = VciGetDeviceManager(&pDevMgr);
  }
  if (hResult == VCI_OK) {
    hResult = pDevMgr->EnumDevices(&pEnum);
  }
  if (hResult != VCI_OK) {
    VciFormatError(hResult, szError, sizeof(szError));
    printf("error: %s\n", szError);
    return 1;
  }
  IBalObject* pSender = OpenBal(pDevMgr, pEnum);
  IBalObject* pReceiver = OpenBal(pDevMgr, pEnum);
  pEnum->Release();
  pDevMgr->Release();
  if (pSender == NULL || pReceiver == NULL) {
    printf("error: two adapters are needed\n");
    return 1;
  }
  Line tx = {NULL, NULL, NULL, NULL};
  Line rx = {NULL, NULL, NULL, NULL};
  hResult = InitSocket(pSender, &tx);
  if (hResult == VCI_OK) {
    hResult = InitSocket(pReceiver, &rx);
  }
  HANDLE hEvent = CreateEvent(NULL, FALSE, FALSE, NULL);
  int result = 1;
  if (hResult == VCI_OK && rx.pReader->AssignEvent(hEvent) == VCI_OK &&
      TransmitByte(tx.pWriter, 0x100, 0x42)) {
    // Wait for the frame (the INFO message of the start may come first).
    while (result != 0 && WaitForSingleObject(hEvent, 2000) == WAIT_OBJECT_0) {
      CANMSG sCanMsg;
      while (rx.pReader->GetDataEntry(&sCanMsg) == VCI_OK) {
        if (sCanMsg.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
          printf("received: id %03X data %02X\n", (unsigned)sCanMsg.dwMsgId, sCanMsg.abData[0]);
          result = 0;
        }
      }
    }
  } else if (hResult != VCI_OK) {
    VciFormatError(hResult, szError, sizeof(szError));
    printf("error: %s\n", szError);
  }
  if (result != 0) {
    printf("error: nothing received\n");
  }
  CloseHandle(hEvent);
  CloseLine(&tx);
  CloseLine(&rx);
  pSender->Release();
  pReceiver->Release();
  return result;
}
