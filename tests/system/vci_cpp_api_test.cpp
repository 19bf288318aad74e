// The VCI C++ API (libvciapi: vcisdk.h) against a real canemud in stepped time: the guide's
// walk-through (device manager, BAL, socket, channel, control unit, FIFOs with events), FIFO
// semantics, identifiers and reference counting.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci_test_support.hpp"
#include "vcisdk.h"

namespace canemu {
namespace {

using testing::step_ns;
using testing::VciDaemon;

template <class T>
struct Ref {  // releases what it holds
  T* p = nullptr;
  Ref() = default;
  Ref(const Ref&) = delete;
  Ref& operator=(const Ref&) = delete;
  ~Ref() {
    if (p != nullptr) {
      p->Release();
    }
  }
  T* operator->() const { return p; }
  T** out() { return &p; }
  PVOID* pv() { return reinterpret_cast<PVOID*>(&p); }
};

// Opens the adapter named `name` the way the guide's walk-through does.
struct Adapter {
  Ref<IVciDevice> device;
  Ref<IBalObject> bal;
  Ref<ICanSocket> socket;
  Ref<ICanChannel> channel;
  Ref<IFifoReader> reader;
  Ref<IFifoWriter> writer;
  Ref<ICanControl> control;
  explicit Adapter(const std::string& name) {
    Ref<IVciDeviceManager> manager;
    EXPECT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
    Ref<IVciEnumDevice> e;
    EXPECT_EQ(manager->EnumDevices(e.out()), VCI_OK);
    VCIDEVICEINFO info{};
    while (e->Next(1, &info, nullptr) == VCI_OK) {
      if (std::string(info.Description).find("(canemu " + name + ")") != std::string::npos) {
        EXPECT_EQ(manager->OpenDevice(info.VciObjectId, device.out()), VCI_OK);
      }
    }
    EXPECT_EQ(device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
    EXPECT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
    EXPECT_EQ(channel->Initialize(1024, 128), VCI_OK);
    EXPECT_EQ(channel->GetReader(reader.out()), VCI_OK);
    EXPECT_EQ(channel->GetWriter(writer.out()), VCI_OK);
    EXPECT_EQ(channel->Activate(), VCI_OK);
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
    CANINITLINE init{CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME, 0,
                     CAN_BT0_500KB, CAN_BT1_500KB};
    EXPECT_EQ(control->InitLine(&init), VCI_OK);
    EXPECT_EQ(control->StartLine(), VCI_OK);
  }
};

// The BAL of the adapter whose VciObjectId is `id`, opened through the device manager.
void open_bal(INT64 id, Ref<IBalObject>& bal) {
  Ref<IVciDeviceManager> manager;
  ASSERT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  VCIID vciid{};
  vciid.AsInt64 = id;
  Ref<IVciDevice> device;
  ASSERT_EQ(manager->OpenDevice(vciid, device.out()), VCI_OK);
  ASSERT_EQ(device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
}

CANMSG one_byte(UINT32 id, UINT8 b) {
  CANMSG m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  m.abData[0] = b;
  return m;
}

TEST(VciCppApi, TheWalkThroughSendsAndReceivesWithAnEvent) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  HANDLE event = CreateEvent(nullptr, FALSE, FALSE, nullptr);
  ASSERT_NE(event, nullptr);
  ASSERT_EQ(beta.reader->SetThreshold(2), VCI_OK);  // the INFO START and the frame
  ASSERT_EQ(beta.reader->AssignEvent(event), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(event, 0), WAIT_TIMEOUT);
  CANMSG m = one_byte(0x123, 0x5A);
  ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  step_ns(1'000'000);
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);
  std::vector<CANMSG> got;
  CANMSG r;
  while (beta.reader->GetDataEntry(&r) == VCI_OK) {
    got.push_back(r);
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
  EXPECT_EQ(got[1].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].abData[0], 0x5A);
  // At its end of frame, in 1 us ticks: the frame's bits (stuff bits included) of 2 us each.
  const auto frame = model::Frame::classic(0x123, std::vector<uint8_t>{0x5A});
  EXPECT_EQ(got[1].dwTime, 2u * model::encode(*frame).length);
  EXPECT_EQ(beta.reader->GetDataEntry(&r), VCI_E_RXQUEUE_EMPTY);
  // Reading did not signal it again.
  EXPECT_EQ(WaitForSingleObject(event, 0), WAIT_TIMEOUT);
  EXPECT_GE(canemuEventFd(event), 0);
  EXPECT_EQ(beta.reader->AssignEvent(nullptr), VCI_OK);
  EXPECT_TRUE(CloseHandle(event));
}

TEST(VciCppApi, ObjectsAreExclusiveWhereTheGuideSaysAndReferenceCounted) {
  VciDaemon d;
  Adapter alpha("alpha");
  Ref<ICanControl> second;
  EXPECT_EQ(alpha.bal->OpenSocket(0, IID_ICanControl, second.pv()), VCI_E_ACCESSDENIED);
  EXPECT_EQ(second.p, nullptr);
  Ref<IFifoReader> another;
  EXPECT_EQ(alpha.channel->GetReader(another.out()), VCI_E_ACCESSDENIED);
  Ref<ICanScheduler> list;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler, list.pv()), VCI_OK);
  Ref<ICanScheduler2> list2;
  EXPECT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler2, list2.pv()), VCI_E_ACCESSDENIED);
  Ref<IUnknown> none;
  EXPECT_EQ(alpha.bal->OpenSocket(1, IID_ICanSocket, none.pv()), VCI_E_INVALIDARG);
  EXPECT_EQ(alpha.bal->OpenSocket(0, IID_IFifoReader, none.pv()), VCI_E_NOINTERFACE);
  EXPECT_EQ(alpha.device->OpenComponent(IID_IBalObject, IID_IBalObject, none.pv()),
            VCI_E_INVALIDARG);
  // QueryInterface adds a reference; Release counts down.
  Ref<IUnknown> unknown;
  ASSERT_EQ(alpha.socket->QueryInterface(IID_IUnknown, unknown.pv()), VCI_OK);
  EXPECT_EQ(alpha.socket->AddRef(), 3u);
  EXPECT_EQ(alpha.socket->Release(), 2u);
  Ref<ICanSocket2> other;
  EXPECT_EQ(alpha.socket->QueryInterface(IID_ICanSocket2, other.pv()), VCI_E_NOINTERFACE);
  EXPECT_EQ(other.p, nullptr);
  // The socket's view needs nothing else open.
  BALSOCKETINFO info{};
  ASSERT_EQ(alpha.socket->GetSocketInfo(&info), VCI_OK);
  EXPECT_EQ(info.BusNo, 0);
  EXPECT_EQ(info.Type, (VCI_BUS_CAN << 8) | CAN_CTRL_SJA1000);
  CANCAPABILITIES caps{};
  ASSERT_EQ(alpha.socket->GetCapabilities(&caps), VCI_OK);
  EXPECT_EQ(caps.wCtrlType, CAN_CTRL_SJA1000);
  CANLINESTATUS line{};
  ASSERT_EQ(alpha.socket->GetLineStatus(&line), VCI_OK);
  EXPECT_EQ(line.bBtReg1, CAN_BT1_500KB);
  BALFEATURES features{};
  ASSERT_EQ(alpha.bal->GetFeatures(&features), VCI_OK);
  EXPECT_EQ(features.BusSocketCount, 1);
}

TEST(VciCppApi, AStandAloneFifoKeepsOrderCountsAndSignalsOnWritesOnly) {
  VciDaemon d;
  VCIID id{};
  Ref<IFifoWriter> writer;
  ASSERT_EQ(VciCreateFifo(&id, 32, 16, IID_IFifoWriter, writer.pv()), VCI_OK);
  Ref<IFifoReader> reader;
  ASSERT_EQ(VciAccessFifo(id, IID_IFifoReader, reader.pv()), VCI_OK);
  Ref<IFifoReader> twice;
  EXPECT_EQ(VciAccessFifo(id, IID_IFifoReader, twice.pv()), VCI_E_ACCESSDENIED);
  UINT16 capacity = 0;
  UINT16 size = 0;
  ASSERT_EQ(reader->GetCapacity(&capacity), VCI_OK);
  ASSERT_EQ(reader->GetEntrySize(&size), VCI_OK);
  EXPECT_GE(capacity, 32);
  EXPECT_EQ(size, 16);
  HANDLE event = CreateEvent(nullptr, FALSE, FALSE, nullptr);
  ASSERT_EQ(reader->SetThreshold(3), VCI_OK);
  ASSERT_EQ(reader->AssignEvent(event), VCI_OK);
  uint8_t element[16] = {};
  for (uint8_t k = 1; k <= 5; ++k) {
    element[0] = k;
    ASSERT_EQ(writer->PutDataEntry(element), VCI_OK);
  }
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);  // the third write crossed 3
  UINT16 fill = 0;
  UINT16 free_count = 0;
  ASSERT_EQ(reader->GetFillCount(&fill), VCI_OK);
  ASSERT_EQ(reader->GetFreeCount(&free_count), VCI_OK);
  EXPECT_EQ(fill, 5);
  EXPECT_EQ(fill + free_count, capacity);
  // Acquire five, release two: the next acquire starts at the third.
  PVOID p = nullptr;
  UINT16 count = 0;
  ASSERT_EQ(reader->AcquireRead(&p, &count), VCI_OK);
  EXPECT_EQ(count, 5);
  EXPECT_EQ(static_cast<uint8_t*>(p)[0], 1);
  ASSERT_EQ(reader->ReleaseRead(2), VCI_OK);
  ASSERT_EQ(reader->AcquireRead(&p, &count), VCI_OK);
  EXPECT_EQ(count, 3);
  EXPECT_EQ(static_cast<uint8_t*>(p)[0], 3);
  ASSERT_EQ(reader->ReleaseRead(0), VCI_OK);
  // Acquired without a count pointer, one element may be released.
  ASSERT_EQ(reader->AcquireRead(&p, nullptr), VCI_OK);
  EXPECT_EQ(reader->ReleaseRead(2), VCI_E_INVALIDARG);
  ASSERT_EQ(reader->ReleaseRead(1), VCI_OK);         // the third
  ASSERT_EQ(reader->GetDataEntry(nullptr), VCI_OK);  // drops the fourth
  ASSERT_EQ(reader->GetDataEntry(element), VCI_OK);
  EXPECT_EQ(element[0], 5);
  EXPECT_EQ(WaitForSingleObject(event, 0), WAIT_TIMEOUT);  // reads signal nothing
  // Lock is recursive.
  EXPECT_EQ(reader->Lock(), VCI_OK);
  EXPECT_EQ(reader->Lock(), VCI_OK);
  EXPECT_EQ(reader->Unlock(), VCI_OK);
  EXPECT_EQ(reader->Unlock(), VCI_OK);
  // Reset only with no reader and writer open.
  Ref<IVciFifo2> fifo;
  ASSERT_EQ(VciAccessFifo(id, IID_IVciFifo2, fifo.pv()), VCI_OK);
  EXPECT_EQ(fifo->Reset(), VCI_E_ACCESSDENIED);
  reader->AssignEvent(nullptr);
  reader->Release();
  reader.p = nullptr;
  writer->Release();
  writer.p = nullptr;
  ASSERT_EQ(fifo->Reset(), VCI_OK);
  ASSERT_EQ(fifo->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  CloseHandle(event);
}

TEST(VciCppApi, IdentifiersRoundTripThroughText) {
  VCIID luid{};
  luid.AsInt64 = 0x0123456789ABCDEF;
  char text[40];
  EXPECT_EQ(VciLuidToChar(luid, text, 16), VCI_E_BUFFER_OVERFLOW);
  ASSERT_EQ(VciLuidToChar(luid, text, 17), VCI_OK);
  EXPECT_STREQ(text, "0123456789ABCDEF");
  VCIID back{};
  ASSERT_EQ(VciCharToLuid(text, &back), VCI_OK);
  EXPECT_EQ(back.AsInt64, luid.AsInt64);
  char garbage[] = "not a luid";
  EXPECT_EQ(VciCharToLuid(garbage, &back), VCI_E_FAIL);
  EXPECT_EQ(VciGuidToChar(IID_ICanChannel, text, 38), VCI_E_BUFFER_OVERFLOW);
  ASSERT_EQ(VciGuidToChar(IID_ICanChannel, text, 39), VCI_OK);
  EXPECT_EQ(std::strlen(text), 38u);
  GUID g{};
  ASSERT_EQ(VciCharToGuid(text, &g), VCI_OK);
  EXPECT_EQ(std::memcmp(&g, &IID_ICanChannel, sizeof g), 0);
  EXPECT_EQ(VciCharToGuid(garbage, &g), VCI_E_FAIL);
  char small[4];
  EXPECT_EQ(VciFormatError(VCI_E_TIMEOUT, small, sizeof small), VCI_OK);
  EXPECT_EQ(std::strlen(small), 3u);
  EXPECT_EQ(VciFormatError(VCI_E_TIMEOUT, nullptr, 10), VCI_E_INVALIDARG);
}

TEST(VciCppApi, TheFdChannelSendsAnFdFrameThroughItsWriter) {
  VciDaemon d(
      "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n\n"
      "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n\n"
      "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n");
  struct Fd {
    Ref<IVciDevice> device;
    Ref<IBalObject> bal;
    Ref<ICanSocket2> socket;
    Ref<ICanChannel2> channel;
    Ref<ICanControl2> control;
    Ref<IFifoReader> reader;
    Ref<IFifoWriter> writer;
    explicit Fd(INT64 id) {
      Ref<IVciDeviceManager> manager;
      EXPECT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
      VCIID v{};
      v.AsInt64 = id;
      EXPECT_EQ(manager->OpenDevice(v, device.out()), VCI_OK);
      EXPECT_EQ(device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
      EXPECT_EQ(bal->OpenSocket(0, IID_ICanSocket2, socket.pv()), VCI_OK);
      EXPECT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
      EXPECT_EQ(channel->Initialize(256, 64, 0, CAN_FILTER_PASS), VCI_OK);
      EXPECT_EQ(channel->GetReader(reader.out()), VCI_OK);
      EXPECT_EQ(channel->GetWriter(writer.out()), VCI_OK);
      EXPECT_EQ(channel->Activate(), VCI_OK);
      EXPECT_EQ(channel->GetControl(control.out()), VCI_OK);
      CANINITLINE2 init{};
      init.bOpMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED;
      init.bExMode = CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA;
      init.bSFMode = CAN_FILTER_PASS;
      init.bEFMode = CAN_FILTER_PASS;
      init.sBtpSdr = CANBTP{0, 500000, 14, 2, 1, 0};
      init.sBtpFdr = CANBTP{0, 2000000, 8, 2, 1, 0};
      EXPECT_EQ(control->InitLine(&init), VCI_OK);
      EXPECT_EQ(control->StartLine(), VCI_OK);
    }
  };
  Fd alpha(1);
  Fd beta(2);
  // The guide's own example: fdr without edl, written in place with AcquireWrite.
  PCANMSG2 p = nullptr;
  ASSERT_EQ(alpha.writer->AcquireWrite(reinterpret_cast<PVOID*>(&p), nullptr), VCI_OK);
  std::memset(p, 0, sizeof *p);
  p->dwMsgId = 0x1234;
  p->uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  p->uMsgInfo.Bits.fdr = 1;
  p->uMsgInfo.Bits.ext = 1;
  p->uMsgInfo.Bits.dlc = 1;
  p->abData[0] = 0x77;
  ASSERT_EQ(alpha.writer->ReleaseWrite(1), VCI_OK);
  step_ns(1'000'000);
  std::vector<CANMSG2> got;
  CANMSG2 m;
  while (beta.reader->GetDataEntry(&m) == VCI_OK) {
    if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
      got.push_back(m);
    }
  }
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x1234u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(got[0].abData[0], 0x77);
  CANCHANSTATUS2 s{};
  ASSERT_EQ(beta.channel->GetStatus(&s), VCI_OK);
  EXPECT_TRUE(s.fActivated);
  EXPECT_EQ(s.sLineStatus.bExMode, CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
}

TEST(VciCppApi, AnEnumeratorsEventFiresWhenAnAdapterComes) {
  VciDaemon d;
  Ref<IVciDeviceManager> manager;
  ASSERT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  Ref<IVciEnumDevice> e;
  ASSERT_EQ(manager->EnumDevices(e.out()), VCI_OK);
  VCIDEVICEINFO infos[4] = {};
  UINT32 fetched = 0;
  EXPECT_EQ(e->Next(4, infos, nullptr), VCI_E_INVALIDARG);  // a count is needed for more than 1
  ASSERT_EQ(e->Next(4, infos, &fetched), VCI_OK);
  EXPECT_EQ(fetched, 2u);
  HANDLE event = CreateEvent(nullptr, FALSE, FALSE, nullptr);
  ASSERT_EQ(e->AssignEvent(event), VCI_OK);
  ASSERT_EQ(canemuCreateDevice("can0", "late", nullptr, nullptr, 0), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);
  ASSERT_EQ(e->Reset(), VCI_OK);
  ASSERT_EQ(e->Next(4, infos, &fetched), VCI_OK);
  EXPECT_EQ(fetched, 3u);
  EXPECT_STREQ(infos[2].Description, "USB-to-CAN (canemu late)");
  ASSERT_EQ(e->Reset(), VCI_OK);
  ASSERT_EQ(e->Skip(2), VCI_OK);
  ASSERT_EQ(e->Next(1, infos, nullptr), VCI_OK);
  EXPECT_STREQ(infos[0].Description, "USB-to-CAN (canemu late)");
  EXPECT_EQ(e->Next(1, infos, nullptr), VCI_E_NO_MORE_ITEMS);
  ASSERT_EQ(e->AssignEvent(nullptr), VCI_OK);
  CloseHandle(event);
}

TEST(VciCppApi, DevicesAreFoundByHardwareIdAndByClass) {
  VciDaemon d;
  Adapter beta("beta");
  VCIDEVICEINFO info{};
  ASSERT_EQ(beta.device->GetDeviceInfo(&info), VCI_OK);
  Ref<IVciDevice> by_hwid;
  ASSERT_EQ(VciQueryDeviceByHwid(info.UniqueHardwareId.AsGuid, by_hwid.out()), VCI_OK);
  VCIDEVICEINFO found{};
  ASSERT_EQ(by_hwid->GetDeviceInfo(&found), VCI_OK);
  EXPECT_EQ(found.VciObjectId.AsInt64, info.VciObjectId.AsInt64);
  Ref<IVciDevice> second;
  ASSERT_EQ(VciQueryDeviceByClass(info.DeviceClass, 1, second.out()), VCI_OK);
  ASSERT_EQ(second->GetDeviceInfo(&found), VCI_OK);
  EXPECT_STREQ(found.Description, "USB-to-CAN (canemu beta)");
  Ref<IVciDevice> none;
  EXPECT_EQ(VciQueryDeviceByClass(info.DeviceClass, 2, none.out()), VCI_E_NO_MORE_ITEMS);
  EXPECT_EQ(none.p, nullptr);
  VCIDEVICECAPS caps{};
  ASSERT_EQ(beta.device->GetDeviceCaps(&caps), VCI_OK);
  EXPECT_EQ(caps.BusCtrlCount, 1);
  VCIVERSIONINFO version{};
  ASSERT_EQ(VciGetVersion(&version), VCI_OK);
  EXPECT_EQ(version.VciMajorVersion, 4u);
}

TEST(VciCppApi, AWritersEventFiresWhenTheControllerMakesRoom) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  UINT16 capacity = 0;
  ASSERT_EQ(alpha.writer->GetCapacity(&capacity), VCI_OK);
  for (UINT32 k = 0; k < 10; ++k) {
    CANMSG m = one_byte(0x300 + k, static_cast<UINT8>(k));
    ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  }
  UINT16 free_count = 0;
  ASSERT_EQ(alpha.writer->GetFreeCount(&free_count), VCI_OK);
  // Ten put; the line may have taken the first already (the writer rang its doorbell).
  EXPECT_GE(free_count + 10, capacity);
  EXPECT_LE(free_count + 9, capacity);
  HANDLE event = CreateEvent(nullptr, FALSE, FALSE, nullptr);
  ASSERT_EQ(alpha.writer->SetThreshold(capacity), VCI_OK);  // all free again
  ASSERT_EQ(alpha.writer->AssignEvent(event), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(event, 0), WAIT_TIMEOUT);
  step_ns(10'000'000);  // the line takes all ten
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);
  ASSERT_EQ(alpha.writer->GetFreeCount(&free_count), VCI_OK);
  EXPECT_EQ(free_count, capacity);
  alpha.writer->AssignEvent(nullptr);
  CloseHandle(event);
}

// A FIFO made with VciCreateFifo is reached from another process by its VCIID; there is one
// reader and one writer in all processes together.
TEST(VciCppApi, AFifoIsSharedBetweenProcessesWithOneReaderAndOneWriterInAll) {
  VciDaemon d;
  VCIID id{};
  Ref<IFifoWriter> writer;
  ASSERT_EQ(VciCreateFifo(&id, 16, 8, IID_IFifoWriter, writer.pv()), VCI_OK);
  for (uint8_t k = 1; k <= 3; ++k) {
    uint8_t e[8] = {k};
    ASSERT_EQ(writer->PutDataEntry(e), VCI_OK);
  }
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Another program: a connection of its own, the reader, the three elements in order.
    if (canemuConnect(d.daemon.socket().c_str()) != VCI_OK) {
      ::_exit(10);
    }
    IFifoReader* reader = nullptr;
    if (VciAccessFifo(id, IID_IFifoReader, reinterpret_cast<PVOID*>(&reader)) != VCI_OK) {
      ::_exit(11);
    }
    IFifoWriter* second = nullptr;
    if (VciAccessFifo(id, IID_IFifoWriter, reinterpret_cast<PVOID*>(&second)) !=
        VCI_E_ACCESSDENIED) {
      ::_exit(12);  // the first program has the writer
    }
    for (uint8_t k = 1; k <= 3; ++k) {
      uint8_t e[8] = {};
      if (reader->GetDataEntry(e) != VCI_OK || e[0] != k) {
        ::_exit(13);
      }
    }
    reader->Release();
    ::_exit(0);
  }
  int status = -1;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // The reader is free again, and the FIFO empty.
  Ref<IFifoReader> reader;
  ASSERT_EQ(VciAccessFifo(id, IID_IFifoReader, reader.pv()), VCI_OK);
  UINT16 fill = 1;
  ASSERT_EQ(reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  VCIID unknown{};
  unknown.AsInt64 = 999;
  Ref<IVciFifo> none;
  EXPECT_EQ(VciAccessFifo(unknown, IID_IVciFifo, none.pv()), VCI_E_INVALIDARG);
}

// ---------------------------------------------------------------- the checklist through C++

std::vector<CANMSG> drain(IFifoReader* reader, bool data_only) {
  std::vector<CANMSG> got;
  CANMSG m;
  while (reader->GetDataEntry(&m) == VCI_OK) {
    if (!data_only || m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
      got.push_back(m);
    }
  }
  return got;
}

UINT32 end_of(uint32_t id, std::vector<uint8_t> data, bool ext = false) {
  return 2u * model::encode(*model::Frame::classic(id, data, ext)).length;  // 2 us a bit
}

TEST(VciCppApi, TheControlUnitsStatesAndInfoMessages) {
  VciDaemon d;
  Adapter beta("beta");  // holds nothing of alpha
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(1, bal));
  Ref<ICanControl> control;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
  Ref<ICanSocket> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
  Ref<ICanChannel> channel;
  ASSERT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
  CANCHANSTATUS cs{};
  ASSERT_EQ(channel->GetStatus(&cs), VCI_OK);  // before Initialize
  EXPECT_FALSE(cs.fActivated);
  Ref<IFifoReader> early;
  EXPECT_EQ(channel->GetReader(early.out()), VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(channel->Initialize(0, 16), VCI_E_INVALIDARG);
  ASSERT_EQ(channel->Initialize(64, 16), VCI_OK);
  Ref<IFifoReader> reader;
  ASSERT_EQ(channel->GetReader(reader.out()), VCI_OK);
  ASSERT_EQ(channel->Activate(), VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(control->StartLine(), VCI_E_INVALID_STATE);
  CANINITLINE init{CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  step_ns(2'000'000);
  ASSERT_EQ(control->StartLine(), VCI_OK);
  CANMSG m = one_byte(0x5, 5);
  ASSERT_EQ(beta.writer->PutDataEntry(&m), VCI_OK);
  step_ns(1'000'000);
  ASSERT_EQ(control->StopLine(), VCI_OK);
  ASSERT_EQ(control->ResetLine(), VCI_OK);
  const auto got = drain(reader.p, false);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 2000u);
  EXPECT_EQ(got[1].dwMsgId, 0x5u);
  EXPECT_EQ(got[1].dwTime, 2000u + end_of(0x5, {5}));
  EXPECT_EQ(got[2].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(got[2].dwTime, 0u);
  EXPECT_EQ(got[3].abData[0], CAN_INFO_RESET);
  ASSERT_EQ(control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
}

TEST(VciCppApi, ALoneAdapterWarnsGoesPassiveAndAFaultTakesItBusOffUntilRestarted) {
  VciDaemon d;
  Adapter alpha("alpha");
  CANMSG m = one_byte(0x10, 1);
  ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  step_ns(10'000'000);
  std::size_t acks = 0;
  std::vector<CANMSG> statuses;
  for (const CANMSG& x : drain(alpha.reader.p, false)) {
    if (x.uMsgInfo.Bytes.bType == CAN_MSGTYPE_ERROR) {
      acks += x.abData[0] == CAN_ERROR_ACK ? 1 : 0;
    } else if (x.uMsgInfo.Bytes.bType == CAN_MSGTYPE_STATUS) {
      statuses.push_back(x);
    }
  }
  EXPECT_GT(acks, 16u);
  ASSERT_EQ(statuses.size(), 1u);
  EXPECT_EQ(statuses[0].abData[0] & CAN_STATUS_ERRLIM, CAN_STATUS_ERRLIM);
  UINT8 state = 0;
  UINT16 tec = 0;
  ASSERT_EQ(canemuGetControllerState(alpha.control.p, &state, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(state, CANEMU_STATE_PASSIVE);
  EXPECT_EQ(tec, 128);
  // A partner comes; 32 injected bit errors take alpha bus-off.
  Adapter beta("beta");
  testing::load_faults(d.daemon,
                       "[[fault]]\nat = \"0s\"\nbus = \"can0\"\nmatch = { from = \"alpha:0\" }\n"
                       "effect = \"bit_error\"\ncount = 40\n");
  step_ns(20'000'000);
  ASSERT_EQ(canemuGetControllerState(alpha.control.p, &state, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(state, CANEMU_STATE_BUSOFF);
  CANLINESTATUS s{};
  ASSERT_EQ(alpha.control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus & CAN_STATUS_BUSOFF, CAN_STATUS_BUSOFF);
  // Restarted (the remaining 8 errors hit the retries), then it sends.
  ASSERT_EQ(alpha.control->StopLine(), VCI_OK);
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);
  step_ns(20'000'000);
  ASSERT_EQ(alpha.control->StopLine(), VCI_OK);
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);
  drain(beta.reader.p, false);
  m = one_byte(0x11, 2);
  ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  step_ns(20'000'000);
  bool seen = false;
  for (const CANMSG& x : drain(beta.reader.p, true)) {
    seen = seen || x.dwMsgId == 0x11;
  }
  EXPECT_TRUE(seen);
}

TEST(VciCppApi, V2ChannelFiltersInEveryModeForBothWidthsAndRtr) {
  VciDaemon d;
  Adapter beta("beta");
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(1, bal));
  Ref<ICanSocket2> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket2, socket.pv()), VCI_OK);
  struct Ch {
    Ref<ICanChannel2> ch;
    Ref<IFifoReader> reader;
  };
  auto make = [&](Ch& c, UINT8 mode) {
    ASSERT_EQ(socket->CreateChannel(FALSE, c.ch.out()), VCI_OK);
    ASSERT_EQ(c.ch->Initialize(256, 0, 64, mode), VCI_OK);
    ASSERT_EQ(c.ch->GetReader(c.reader.out()), VCI_OK);
  };
  Ch lock, pass, incl, excl;
  make(lock, CAN_FILTER_LOCK);
  make(pass, CAN_FILTER_PASS);
  make(incl, CAN_FILTER_INCL);
  make(excl, CAN_FILTER_EXCL);
  for (Ch* c : {&incl, &excl}) {
    for (UINT8 w : {UINT8{CAN_FILTER_STD}, UINT8{CAN_FILTER_EXT}}) {
      ASSERT_EQ(c->ch->SetAccFilter(w, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE), VCI_OK);
    }
    ASSERT_EQ(c->ch->AddFilterIds(CAN_FILTER_STD, 0x123 << 1, 0xFFF), VCI_OK);  // data 0x123
    ASSERT_EQ(c->ch->AddFilterIds(CAN_FILTER_EXT, (0x1234 << 1) | 1, 0x3FFFFFFF),
              VCI_OK);  // remote 0x1234 (29 bit)
  }
  for (Ch* c : {&lock, &pass, &incl, &excl}) {
    ASSERT_EQ(c->ch->Activate(), VCI_OK);
  }
  EXPECT_EQ(incl.ch->SetAccFilter(CAN_FILTER_STD, 0, 0), VCI_E_INVALID_STATE);
  Ref<ICanControl2> control;
  ASSERT_EQ(incl.ch->GetControl(control.out()), VCI_OK);
  CANINITLINE2 init{};
  init.bOpMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED;
  init.bSFMode = CAN_FILTER_PASS;
  init.bEFMode = CAN_FILTER_PASS;
  init.dwSFIds = 2048;
  init.dwEFIds = 2048;
  init.sBtpSdr = CANBTP{0, 500000, 14, 2, 1, 0};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  ASSERT_EQ(control->StartLine(), VCI_OK);
  CANMSG a = one_byte(0x123, 1);
  CANMSG b = one_byte(0x124, 2);
  CANMSG r = one_byte(0x123, 0);  // remote 0x123: not on the list
  r.uMsgInfo.Bits.rtr = 1;
  r.uMsgInfo.Bits.dlc = 0;
  CANMSG x = one_byte(0x1234, 0);  // remote 29-bit 0x1234: on the list
  x.uMsgInfo.Bits.ext = 1;
  x.uMsgInfo.Bits.rtr = 1;
  x.uMsgInfo.Bits.dlc = 0;
  for (CANMSG* m : {&a, &b, &r, &x}) {
    ASSERT_EQ(beta.writer->PutDataEntry(m), VCI_OK);
  }
  step_ns(5'000'000);
  auto ids = [](IFifoReader* reader) {
    std::vector<std::pair<uint32_t, unsigned>> v;
    CANMSG2 m;
    while (reader->GetDataEntry(&m) == VCI_OK) {
      if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
        v.emplace_back(m.dwMsgId | (m.uMsgInfo.Bits.rtr != 0 ? 0x80000000U : 0U),
                       static_cast<unsigned>(m.uMsgInfo.Bits.afc));
      }
    }
    return v;
  };
  using V = std::vector<std::pair<uint32_t, unsigned>>;
  const unsigned all = CAN_ACCEPT_ALWAYS;
  EXPECT_EQ(ids(lock.reader.p), V{});
  EXPECT_EQ(ids(pass.reader.p),
            (V{{0x123, all}, {0x124, all}, {0x80000123, all}, {0x80001234, all}}));
  EXPECT_EQ(ids(incl.reader.p),
            (V{{0x123, CAN_ACCEPT_FILTER_2}, {0x80001234, CAN_ACCEPT_FILTER_2}}));
  EXPECT_EQ(ids(excl.reader.p),
            (V{{0x124, CAN_ACCEPT_PASSEXCL}, {0x80000123, CAN_ACCEPT_PASSEXCL}}));
}

TEST(VciCppApi, EchoesOverrunAndDelayThroughTheFifos) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  drain(alpha.reader.p, false);
  CANMSG own = one_byte(0x321, 7);
  own.uMsgInfo.Bits.srr = 1;
  ASSERT_EQ(alpha.writer->PutDataEntry(&own), VCI_OK);
  CANMSG later = one_byte(0x322, 8);
  later.dwTime = 500;  // 500 us after the echo's frame was handed over
  ASSERT_EQ(alpha.writer->PutDataEntry(&later), VCI_OK);
  step_ns(5'000'000);
  const auto echo = drain(alpha.reader.p, true);
  ASSERT_EQ(echo.size(), 1u);
  EXPECT_EQ(echo[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(echo[0].dwTime, end_of(0x321, {7}));
  const auto at_beta = drain(beta.reader.p, true);
  ASSERT_EQ(at_beta.size(), 2u);
  EXPECT_EQ(at_beta[1].dwTime, 500u + end_of(0x322, {8}));
  // beta's receive FIFO holds 1024 or a little more; 1100 frames overflow it.
  UINT16 capacity = 0;
  ASSERT_EQ(beta.reader->GetCapacity(&capacity), VCI_OK);
  for (int k = 0; k <= capacity; k += 64) {
    for (int i = 0; i < 64; ++i) {
      CANMSG m = one_byte(0x400, static_cast<UINT8>(i));
      ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
    }
    step_ns(10'000'000);
  }
  CANCHANSTATUS s{};
  ASSERT_EQ(beta.channel->GetStatus(&s), VCI_OK);
  EXPECT_TRUE(s.fRxOverrun);
  EXPECT_EQ(s.bRxFifoLoad, 100);
  UINT16 fill = 0;
  ASSERT_EQ(beta.reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, capacity);
  drain(beta.reader.p, false);
  CANMSG next = one_byte(0x401, 1);
  ASSERT_EQ(alpha.writer->PutDataEntry(&next), VCI_OK);
  step_ns(1'000'000);
  const auto after = drain(beta.reader.p, true);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].uMsgInfo.Bits.ovr, 1u);
}

TEST(VciCppApi, TheCyclicListThroughICanScheduler2AndTheTimerOverflow) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  Ref<ICanScheduler2> list;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler2, list.pv()), VCI_OK);
  CANCYCLICTXMSG2 m{};
  m.wCycleTime = 3;
  m.bIncrMode = CAN_CTXMSG_INC_8;
  m.bByteIndex = 0;
  m.dwMsgId = 0x55;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  m.abData[0] = 0xFE;
  UINT32 index = 0;
  ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
  ASSERT_EQ(list->StartMessage(index, 3), VCI_OK);
  drain(beta.reader.p, false);
  ASSERT_EQ(list->Resume(), VCI_OK);  // at t = 0
  step_ns(20'000'000);
  const auto got = drain(beta.reader.p, true);
  ASSERT_EQ(got.size(), 3u);
  const std::vector<uint8_t> values{0xFE, 0xFF, 0x00};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(got[k].abData[0], values[k]);
    EXPECT_EQ(got[k].dwTime, 3'000u * (k + 1) + end_of(0x55, {values[k]})) << k;
  }
  CANSCHEDULERSTATUS2 s{};
  ASSERT_EQ(list->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  EXPECT_EQ(s.abMsgStat[index], CAN_CTXMSG_STAT_DONE);
  ASSERT_EQ(list->Reset(), VCI_OK);
  ASSERT_EQ(list->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(s.abMsgStat[index], CAN_CTXMSG_STAT_EMPTY);
  step_ns(4'295'000'000'000 - 20'000'000);  // past 2^32 us
  const auto overflow = drain(beta.reader.p, false);
  ASSERT_EQ(overflow.size(), 1u);
  EXPECT_EQ(overflow[0].uMsgInfo.Bytes.bType, CAN_MSGTYPE_TIMEOVR);
  EXPECT_EQ(overflow[0].dwMsgId, 1u);
}

TEST(VciCppApi, ARemovedAdapterSignalsTheEnumeratorAndLeavesTheList) {
  VciDaemon d;
  ASSERT_EQ(canemuCreateDevice("can0", "brief", nullptr, nullptr, 0), VCI_OK);
  Ref<IVciDeviceManager> manager;
  ASSERT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  Ref<IVciEnumDevice> e;
  ASSERT_EQ(manager->EnumDevices(e.out()), VCI_OK);
  HANDLE event = CreateEvent(nullptr, FALSE, FALSE, nullptr);
  ASSERT_EQ(e->AssignEvent(event), VCI_OK);
  ASSERT_EQ(canemuRemoveDevice("brief"), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);
  ASSERT_EQ(e->Reset(), VCI_OK);
  VCIDEVICEINFO infos[4] = {};
  UINT32 fetched = 0;
  ASSERT_EQ(e->Next(4, infos, &fetched), VCI_OK);
  EXPECT_EQ(fetched, 2u);  // alpha and beta only
  e->AssignEvent(nullptr);
  CloseHandle(event);
}

TEST(VciCppApi, ChannelsAreSharedUnlessOneIsExclusive) {
  VciDaemon d;
  Adapter alpha("alpha");  // holds a shared channel
  Ref<ICanChannel> exclusive;
  EXPECT_EQ(alpha.socket->CreateChannel(TRUE, exclusive.out()), VCI_E_ACCESSDENIED);
  EXPECT_EQ(exclusive.p, nullptr);
  Ref<ICanChannel> shared;
  EXPECT_EQ(alpha.socket->CreateChannel(FALSE, shared.out()), VCI_OK);
  // On beta, an exclusive channel shuts out every other.
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(2, bal));
  Ref<ICanSocket> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
  Ref<ICanChannel> first;
  ASSERT_EQ(socket->CreateChannel(TRUE, first.out()), VCI_OK);
  Ref<ICanChannel> second;
  EXPECT_EQ(socket->CreateChannel(FALSE, second.out()), VCI_E_ACCESSDENIED);
  first->Release();
  first.p = nullptr;
  EXPECT_EQ(socket->CreateChannel(FALSE, second.out()), VCI_OK);  // released: open again
}

TEST(VciCppApi, TheCyclicListRefusesBadEntriesAndASeventeenth) {
  VciDaemon d;
  Adapter alpha("alpha");
  Ref<ICanScheduler> list;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler, list.pv()), VCI_OK);
  CANCYCLICTXMSG m{};
  m.wCycleTime = 10;
  m.dwMsgId = 0x100;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  UINT32 index = 0;
  for (UINT32 k = 0; k < 16; ++k) {
    ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
    EXPECT_EQ(index, k);
  }
  EXPECT_EQ(list->AddMessage(&m, &index), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(index, 0xFFFFFFFFu);
  ASSERT_EQ(list->RemMessage(3), VCI_OK);
  m.wCycleTime = 0;
  EXPECT_EQ(list->AddMessage(&m, &index), VCI_E_INVALIDARG);
  m.wCycleTime = 10;
  ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
  EXPECT_EQ(index, 3u);  // the free slot
  EXPECT_EQ(list->StartMessage(16, 1), VCI_E_INVALID_INDEX);
  CANSCHEDULERSTATUS s{};
  ASSERT_EQ(list->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);  // off after opening
}

TEST(VciCppApi, TwoProcessesOpenTheSameBalAndAFifoRoundsToWholePages) {
  VciDaemon d;
  Adapter alpha("alpha");  // this process holds alpha's BAL, control unit and a channel
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (canemuConnect(d.daemon.socket().c_str()) != VCI_OK) {
      ::_exit(10);
    }
    IVciDeviceManager* manager = nullptr;
    IVciDevice* device = nullptr;
    IBalObject* bal = nullptr;
    ICanSocket* socket = nullptr;
    ICanChannel* channel = nullptr;
    VCIID id{};
    id.AsInt64 = 1;
    if (VciGetDeviceManager(&manager) != VCI_OK || manager->OpenDevice(id, &device) != VCI_OK ||
        device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, reinterpret_cast<PVOID*>(&bal)) !=
            VCI_OK ||
        bal->OpenSocket(0, IID_ICanSocket, reinterpret_cast<PVOID*>(&socket)) != VCI_OK ||
        socket->CreateChannel(FALSE, &channel) != VCI_OK) {
      ::_exit(11);
    }
    ICanControl* control = nullptr;
    if (bal->OpenSocket(0, IID_ICanControl, reinterpret_cast<PVOID*>(&control)) !=
        VCI_E_ACCESSDENIED) {
      ::_exit(12);  // the first process has the control unit
    }
    ::_exit(0);
  }
  int status = -1;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // The guide's 32 elements of 16 bytes: one 4 KiB page holds the 256-byte header and 240.
  VCIID fifo_id{};
  Ref<IVciFifo> fifo;
  ASSERT_EQ(VciCreateFifo(&fifo_id, 32, 16, IID_IVciFifo, fifo.pv()), VCI_OK);
  UINT16 capacity = 0;
  ASSERT_EQ(fifo->GetCapacity(&capacity), VCI_OK);
  EXPECT_EQ(capacity, 240);
}

TEST(VciCppApi, AThreadWaitsForTheFifoLockTheOtherHolds) {
  VciDaemon d;
  VCIID id{};
  Ref<IFifoReader> reader;
  ASSERT_EQ(VciCreateFifo(&id, 16, 8, IID_IFifoReader, reader.pv()), VCI_OK);
  std::vector<int> order;
  std::atomic<bool> trying{false};
  ASSERT_EQ(reader->Lock(), VCI_OK);
  std::thread other([&] {
    trying = true;
    reader->Lock();  // waits for the main thread's Unlock
    order.push_back(2);
    reader->Unlock();
  });
  while (!trying) {
    std::this_thread::yield();
  }
  order.push_back(1);
  ASSERT_EQ(reader->Unlock(), VCI_OK);
  other.join();
  EXPECT_EQ(order, (std::vector<int>{1, 2}));
}

TEST(VciCppApi, AV2InitializedLineShowsItsTimingAsBtrAndDetectBaudTimesOutOnASilentBus) {
  VciDaemon d;
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(1, bal));
  Ref<ICanControl2> control;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanControl2, control.pv()), VCI_OK);
  CANINITLINE2 init{};
  init.bOpMode = CAN_OPMODE_STANDARD;
  init.bSFMode = CAN_FILTER_PASS;
  init.bEFMode = CAN_FILTER_PASS;
  init.dwSFIds = 2048;
  init.sBtpSdr = CANBTP{0, 500000, 14, 2, 1, 0};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  Ref<ICanSocket> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(socket->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.bBtReg0, CAN_BT0_500KB);
  EXPECT_EQ(s.bBtReg1, CAN_BT1_500KB);
  ASSERT_EQ(control->ResetLine(), VCI_OK);
  CANBTPTABLE table{};
  table.bCount = 2;
  table.asBTP[0].sSdr = CANBTP{0, 500000, 14, 2, 1, 0};
  table.asBTP[1].sSdr = CANBTP{0, 250000, 14, 2, 1, 0};
  std::atomic<bool> done{false};
  HRESULT hr = VCI_OK;
  std::thread detector([&] {
    hr = control->DetectBaud(0, CAN_EXMODE_DISABLED, 10, &table);
    done = true;
  });
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!done && std::chrono::steady_clock::now() < give_up) {
    step_ns(1'000'000);
  }
  detector.join();
  EXPECT_EQ(hr, VCI_E_TIMEOUT);
}

TEST(VciCppApi, FifoEdgesFullEmptyInPlaceWritesLevelsAndThresholds) {
  VciDaemon d;
  VCIID id{};
  Ref<IFifoWriter> writer;
  ASSERT_EQ(VciCreateFifo(&id, 16, 8, IID_IFifoWriter, writer.pv()), VCI_OK);
  Ref<IFifoReader> reader;
  ASSERT_EQ(VciAccessFifo(id, IID_IFifoReader, reader.pv()), VCI_OK);
  Ref<IVciFifo> info;
  ASSERT_EQ(VciAccessFifo(id, IID_IVciFifo, info.pv()), VCI_OK);
  UINT16 capacity = 0;
  ASSERT_EQ(reader->GetCapacity(&capacity), VCI_OK);
  UINT16 size = 0;
  ASSERT_EQ(reader->GetEntrySize(&size), VCI_OK);
  EXPECT_EQ(size, 8);
  // Thresholds above the capacity are clamped.
  ASSERT_EQ(reader->SetThreshold(0xFFFF), VCI_OK);
  UINT16 threshold = 0;
  ASSERT_EQ(reader->GetThreshold(&threshold), VCI_OK);
  EXPECT_EQ(threshold, capacity);
  // Reading an empty FIFO; acquiring without a place to put the pointer.
  uint8_t e[8] = {};
  EXPECT_EQ(reader->GetDataEntry(e), VCI_E_RXQUEUE_EMPTY);
  PVOID p = nullptr;
  UINT16 n = 0;
  EXPECT_EQ(reader->AcquireRead(&p, &n), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(reader->AcquireRead(nullptr, &n), VCI_E_INVALIDARG);
  // Written in place: invisible until released.
  ASSERT_EQ(writer->AcquireWrite(&p, &n), VCI_OK);
  EXPECT_EQ(n, capacity);
  static_cast<uint8_t*>(p)[0] = 0x42;
  UINT16 fill = 1;
  ASSERT_EQ(reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  ASSERT_EQ(writer->ReleaseWrite(1), VCI_OK);
  ASSERT_EQ(reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 1);
  // Full: the writer is refused, nothing is overwritten; the level says 100 %.
  for (UINT16 k = 1; k < capacity; ++k) {
    e[0] = static_cast<uint8_t>(k);
    ASSERT_EQ(writer->PutDataEntry(e), VCI_OK);
  }
  EXPECT_EQ(writer->PutDataEntry(e), VCI_E_TXQUEUE_FULL);
  EXPECT_EQ(writer->AcquireWrite(&p, &n), VCI_E_TXQUEUE_FULL);
  UINT16 level = 0;
  ASSERT_EQ(info->GetFillLevel(&level), VCI_OK);
  EXPECT_EQ(level, 100);
  ASSERT_EQ(reader->GetDataEntry(e), VCI_OK);
  EXPECT_EQ(e[0], 0x42);
  // A second AssignEvent replaces the first.
  HANDLE first = CreateEvent(nullptr, FALSE, FALSE, nullptr);
  HANDLE second = CreateEvent(nullptr, FALSE, FALSE, nullptr);
  ASSERT_EQ(reader->SetThreshold(1), VCI_OK);
  ASSERT_EQ(reader->AssignEvent(first), VCI_OK);
  ASSERT_EQ(reader->AssignEvent(second), VCI_OK);
  e[0] = 0x99;
  ASSERT_EQ(writer->PutDataEntry(e), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(second, 5000), WAIT_OBJECT_0);
  EXPECT_EQ(WaitForSingleObject(first, 0), WAIT_TIMEOUT);
  reader->AssignEvent(nullptr);
  CloseHandle(first);
  CloseHandle(second);
}

TEST(VciCppApi, TheChannelsControlIsExclusiveAListenOnlyLineNeverSendsAndBusLoadShows) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  // ICanChannel2::GetControl is the control unit, held by alpha's program already.
  Ref<ICanSocket2> socket2;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanSocket2, socket2.pv()), VCI_OK);
  Ref<ICanChannel2> channel2;
  ASSERT_EQ(socket2->CreateChannel(FALSE, channel2.out()), VCI_OK);
  Ref<ICanControl2> control2;
  EXPECT_EQ(channel2->GetControl(control2.out()), VCI_E_ACCESSDENIED);
  EXPECT_EQ(control2.p, nullptr);
  Ref<IUnknown> bal_unknown;
  EXPECT_EQ(alpha.device->OpenComponent(CLSID_VCIBAL, IID_IUnknown, bal_unknown.pv()), VCI_OK);
  UINT16 entry = 0;
  ASSERT_EQ(alpha.reader->GetEntrySize(&entry), VCI_OK);
  EXPECT_EQ(entry, sizeof(CANMSG));
  // beta sends a frame every millisecond for a second: the load over the last second shows it.
  Ref<ICanScheduler> list;
  ASSERT_EQ(beta.bal->OpenSocket(0, IID_ICanScheduler, list.pv()), VCI_OK);
  CANCYCLICTXMSG c{};
  c.wCycleTime = 1;
  c.dwMsgId = 0x100;
  c.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  c.uMsgInfo.Bits.dlc = 8;
  UINT32 index = 0;
  ASSERT_EQ(list->AddMessage(&c, &index), VCI_OK);
  ASSERT_EQ(list->StartMessage(index, 0), VCI_OK);
  ASSERT_EQ(list->Resume(), VCI_OK);
  step_ns(1'000'000'000);
  ASSERT_EQ(list->Suspend(), VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(beta.control->GetLineStatus(&s), VCI_OK);
  // One 8-byte frame (about 111..135 bits, 2 us each, plus 3 bits of intermission) a
  // millisecond: between 22 % and 28 % of the bus.
  EXPECT_GE(s.bBusLoad, 22);
  EXPECT_LE(s.bBusLoad, 28);
  // Listen-only: what alpha posts never reaches the bus.
  ASSERT_EQ(alpha.control->ResetLine(), VCI_OK);
  CANINITLINE init{CAN_OPMODE_STANDARD | CAN_OPMODE_LISTONLY, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(alpha.control->InitLine(&init), VCI_OK);
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);
  CANMSG m = one_byte(0x7, 7);
  ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  drain(beta.reader.p, false);
  step_ns(10'000'000);
  EXPECT_TRUE(drain(beta.reader.p, true).empty());
}

// The guide's walk-through as a program of its own, built only from the public headers, run
// against a canemud in real time.
TEST(VciCppApi, TheWalkThroughProgramRunsUnchanged) {
  testing::ConfigFile config(testing::kTwoAdapters);
  testing::Daemon d("realtime", {"--config=" + config.path()});
  const std::string command = "CANEMU_SOCKET=" + d.socket() + " " + VCI_WALKTHROUGH_PATH + " 2>&1";
  FILE* out = ::popen(command.c_str(), "r");
  ASSERT_NE(out, nullptr);
  std::string text;
  char buf[256];
  while (std::fgets(buf, sizeof buf, out) != nullptr) {
    text += buf;
  }
  EXPECT_EQ(::pclose(out), 0) << text;
  EXPECT_EQ(text,
            "adapter: USB-to-CAN (canemu alpha)\n"
            "adapter: USB-to-CAN (canemu beta)\n"
            "received: id 100 data 42\n");
}

}  // namespace
}  // namespace canemu
