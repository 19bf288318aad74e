// The VCI C++ API (libvciapi: vcisdk.h) against a real canemud in stepped time: the guide's
// walk-through (device manager, BAL, socket, channel, control unit, FIFOs with events), the
// device manager and its enumerator, identifiers and reference counting.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "shell_support.hpp"
#include "vci_cpp_test_support.hpp"
#include "vcisdk.h"

namespace canemu {
namespace {

using testing::Adapter;
using testing::one_byte;
using testing::Ref;
using testing::step_ns;
using testing::VciDaemon;

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
  // The next two messages (the threshold) signal it again, and again after that.
  for (uint8_t round = 0; round < 2; ++round) {
    for (uint8_t k = 0; k < 2; ++k) {
      CANMSG next = one_byte(0x124, static_cast<uint8_t>(round * 2 + k));
      ASSERT_EQ(alpha.writer->PutDataEntry(&next), VCI_OK);
    }
    step_ns(1'000'000);
    EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0) << "round " << int{round};
    int taken = 0;
    while (beta.reader->GetDataEntry(&r) == VCI_OK) {
      EXPECT_EQ(r.dwMsgId, 0x124u);
      ++taken;
    }
    EXPECT_EQ(taken, 2);
  }
  EXPECT_GE(canemuEventFd(event), 0);
  EXPECT_EQ(beta.reader->AssignEvent(nullptr), VCI_OK);
  EXPECT_TRUE(CloseHandle(event));
}

// The guide's walk-through as a program of its own, built only from the public headers, run
// against a canemud in real time.
TEST(VciCppApi, TheWalkThroughProgramRunsUnchanged) {
  testing::ConfigFile config(testing::kTwoAdapters);
  testing::Daemon d("realtime", {"--config=" + config.path()});
  const std::string command = "CANEMU_SOCKET=" + d.socket() + " " + VCI_WALKTHROUGH_PATH + " 2>&1";
  const auto run = testing::run_shell(command);
  EXPECT_EQ(run.status, 0) << run.out;
  EXPECT_EQ(run.out,
            "adapter: USB-to-CAN (canemu alpha)\n"
            "adapter: USB-to-CAN (canemu beta)\n"
            "received: id 100 data 42\n");
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

TEST(VciCppApi, InterfaceIdentifiersHaveTheVendorsValues) {
  auto text = [](const GUID& g) {
    char t[40];
    EXPECT_EQ(VciGuidToChar(g, t, sizeof t), VCI_OK);
    return std::string(t);
  };
  EXPECT_EQ(text(IID_IUnknown), "{00000000-0000-0000-C000-000000000046}");
  EXPECT_EQ(text(CLSID_VCIBAL), "{3CB880F4-2791-40BD-B852-09349D1A7B37}");
  EXPECT_EQ(text(IID_IVciDeviceManager), "{7724B0A9-E6DB-46B0-A5D0-468CC4191732}");
  EXPECT_EQ(text(IID_IBalObject), "{A2B958AA-9188-4CDB-8307-25D9F1F843E9}");
  EXPECT_EQ(text(IID_ICanControl2), "{EFD3A8E2-09E3-4115-869F-93E579167431}");
  EXPECT_EQ(text(IID_ICanChannel), "{66FF396B-22EA-42AA-BC7E-4919F89FB45C}");
  EXPECT_EQ(text(IID_IFifoReader), "{19286603-A9CD-433A-A495-72E5C9D97A97}");
  EXPECT_EQ(text(IID_ILinMonitor), "{29068E57-6B69-4010-911C-7A9128521BE0}");
  // Field by field, as a program that compares with its own copy of the SDK's value does.
  const GUID channel2 = {
      0xF2528F90, 0x3A10, 0x46D0, {0x8F, 0x82, 0x08, 0x71, 0xC1, 0xE7, 0xDB, 0xB9}};
  EXPECT_EQ(std::memcmp(&channel2, &IID_ICanChannel2, sizeof channel2), 0);
  // All distinct.
  const GUID* all[] = {&IID_IVciDeviceManager, &IID_IVciEnumDevice, &IID_IVciDevice,
                       &IID_IBalObject,        &IID_ICanSocket,     &IID_ICanSocket2,
                       &IID_ICanControl,       &IID_ICanControl2,   &IID_ICanChannel,
                       &IID_ICanChannel2,      &IID_ICanScheduler,  &IID_ICanScheduler2,
                       &IID_IFifoReader,       &IID_IFifoWriter,    &IID_IVciFifo,
                       &IID_IVciFifo2,         &IID_ILinSocket,     &IID_ILinControl,
                       &IID_ILinMonitor,       &CLSID_VCIBAL,       &IID_IUnknown};
  std::set<std::string> texts;
  for (const GUID* g : all) {
    texts.insert(text(*g));
  }
  EXPECT_EQ(texts.size(), std::size(all));
}

TEST(VciCppApi, IdentifiersRoundTripThroughText) {
  char garbage[] = "not a luid";
  ASSERT_NO_FATAL_FAILURE(testing::expect_luid_round_trip(VciLuidToChar, VciCharToLuid, garbage));
  char text[40];
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
  VCIDEVICEINFO found{};
  ASSERT_NO_FATAL_FAILURE(testing::query_by_hwid(beta.device.p, &info, &found));
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

}  // namespace
}  // namespace canemu
