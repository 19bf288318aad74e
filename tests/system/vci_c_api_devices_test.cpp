// The classic VCI C API (libvcinpl) against a real canemud: enumeration and the adapters'
// identities, adapters made and removed at run time, and what happens without canemud.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "vci_c_test_support.hpp"
#include "vcinpl.h"

namespace canemu::testing {
namespace {

TEST(VciCApi, EnumerationListsEveryAdapterOnceWithItsIdentity) {
  VciDaemon d;
  HANDLE e = nullptr;
  ASSERT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
  VCIDEVICEINFO a{};
  VCIDEVICEINFO b{};
  VCIDEVICEINFO none{};
  ASSERT_EQ(vciEnumDeviceNext(e, &a), VCI_OK);
  ASSERT_EQ(vciEnumDeviceNext(e, &b), VCI_OK);
  EXPECT_EQ(vciEnumDeviceNext(e, &none), VCI_E_NO_MORE_ITEMS);
  EXPECT_EQ(a.VciObjectId.AsInt64, 1);
  EXPECT_EQ(b.VciObjectId.AsInt64, 2);
  EXPECT_STREQ(a.Description, "USB-to-CAN (canemu alpha)");
  EXPECT_STREQ(a.Manufacturer, "canemu");
  EXPECT_EQ(std::string(a.UniqueHardwareId.AsChar, 2), "HW");
  EXPECT_EQ(std::strlen(a.UniqueHardwareId.AsChar), 8u);
  EXPECT_STRNE(a.UniqueHardwareId.AsChar, b.UniqueHardwareId.AsChar);
  // Reset starts over.
  VCIDEVICEINFO again{};
  ASSERT_EQ(vciEnumDeviceReset(e), VCI_OK);
  ASSERT_EQ(vciEnumDeviceNext(e, &again), VCI_OK);
  EXPECT_EQ(std::memcmp(&again, &a, sizeof a), 0);
  EXPECT_EQ(vciEnumDeviceClose(e), VCI_OK);
  EXPECT_EQ(vciEnumDeviceClose(e), VCI_E_INVHANDLE);

  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(b.VciObjectId, &dev), VCI_OK);
  VCIDEVICEINFO info{};
  ASSERT_EQ(vciDeviceGetInfo(dev, &info), VCI_OK);
  EXPECT_EQ(std::memcmp(&info, &b, sizeof b), 0);
  VCIDEVICECAPS caps{};
  ASSERT_EQ(vciDeviceGetCaps(dev, &caps), VCI_OK);
  EXPECT_EQ(caps.BusCtrlCount, 1);
  EXPECT_EQ(caps.BusCtrlTypes[0], (VCI_BUS_CAN << 8) | CAN_CTRL_SJA1000);
  // The same adapter by hardware ID; an unknown VCIID opens nothing.
  VCIID by_hwid{};
  ASSERT_EQ(vciFindDeviceByHwid(b.UniqueHardwareId.AsGuid, &by_hwid), VCI_OK);
  EXPECT_EQ(by_hwid.AsInt64, b.VciObjectId.AsInt64);
  VCIID unknown{};
  unknown.AsInt64 = 99;
  HANDLE nothing = &info;
  EXPECT_EQ(vciDeviceOpen(unknown, &nothing), VCI_E_INVALIDARG);
  EXPECT_EQ(nothing, nullptr);
  HANDLE control = nullptr;
  EXPECT_EQ(canControlOpen(dev, 1, &control), VCI_E_INVALIDARG);  // one bus only
  EXPECT_EQ(vciDeviceClose(dev), VCI_OK);
}

// An adapter made at run time on a named bus: enumerated and used like a configured one,
// gone when removed or when its creator disconnects.
TEST(VciCApi, AnAdapterCreatedOnANamedBusWorksLikeAConfiguredOne) {
  VciDaemon d;
  VCIID id{};
  char name[32] = {};
  ASSERT_EQ(canemuCreateDevice("can0", nullptr, &id, name, sizeof name), VCI_OK);
  EXPECT_STREQ(name, "vci1");
  EXPECT_EQ(id.AsInt64, 3);  // after the two configured adapters
  EXPECT_EQ(id_of("vci1").AsInt64, 3);
  EXPECT_EQ(canemuCreateDevice("nope", "x", nullptr, nullptr, 0), VCI_E_INVALIDARG);
  EXPECT_EQ(canemuCreateDevice("can0", "alpha", nullptr, nullptr, 0), VCI_E_INVALIDARG);
  {
    Adapter alpha("alpha");
    Adapter made("vci1");
    made.post(data(0x77, {7}));
    step_ns(1'000'000);
    const auto got = alpha.frames();
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].dwMsgId, 0x77u);
    EXPECT_EQ(got[0].dwTime, static_cast<UINT32>(bits_of(0x77, {7}) * kBitUs2));
    // Removed from the list; what is open on it keeps working until closed.
    ASSERT_EQ(canemuRemoveDevice("vci1"), VCI_OK);
    EXPECT_EQ(id_of("vci1").AsInt64, 0);
    made.post(data(0x78, {8}));
    step_ns(1'000'000);
    EXPECT_EQ(alpha.frames().size(), 1u);
  }
  EXPECT_EQ(canemuRemoveDevice("vci1"), VCI_E_INVALIDARG);  // gone already
  // A new connection drops the old one: what it created goes with it.
  ASSERT_EQ(canemuCreateDevice("can0", "mine", nullptr, nullptr, 0), VCI_OK);
  EXPECT_NE(id_of("mine").AsInt64, 0);
  ASSERT_EQ(canemuConnect(d.daemon.socket().c_str()), VCI_OK);
  EXPECT_EQ(id_of("mine").AsInt64, 0);
}

// The enumerator's wait returns when an adapter comes; hardware IDs stay from run to run.
TEST(VciCApi, AnEnumeratorWaitsForAdaptersAndHardwareIdsSurviveARestart) {
  std::string first_hwid;
  {
    VciDaemon d;
    HANDLE e = nullptr;
    ASSERT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
    EXPECT_EQ(vciEnumDeviceWaitEvent(e, 50), VCI_E_TIMEOUT);  // nothing changes
    ASSERT_EQ(canemuCreateDevice("can0", "plugged", nullptr, nullptr, 0), VCI_OK);
    EXPECT_EQ(vciEnumDeviceWaitEvent(e, 5000), VCI_OK);
    VCIDEVICEINFO info{};
    ASSERT_EQ(vciEnumDeviceNext(e, &info), VCI_OK);
    first_hwid = info.UniqueHardwareId.AsChar;
    vciEnumDeviceClose(e);
  }
  VciDaemon again;
  HANDLE e = nullptr;
  ASSERT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
  VCIDEVICEINFO info{};
  ASSERT_EQ(vciEnumDeviceNext(e, &info), VCI_OK);
  EXPECT_EQ(first_hwid, info.UniqueHardwareId.AsChar);
  vciEnumDeviceClose(e);
}

TEST(VciCApi, WithoutCanemudEveryCallFailsAtOnceAndSaysWhere) {
  EXPECT_EQ(canemuConnect("/nonexistent/canemud.sock"), VCI_E_DISCONNECTED);
  HANDLE e = nullptr;
  EXPECT_EQ(vciEnumDeviceOpen(&e), VCI_E_DISCONNECTED);
  EXPECT_EQ(e, nullptr);
  char text[256];
  vciFormatError(VCI_E_DISCONNECTED, text, sizeof text);
  EXPECT_NE(std::string(text).find("/nonexistent/canemud.sock"), std::string::npos) << text;
  canemuConnect(nullptr);
}

}  // namespace
}  // namespace canemu::testing
