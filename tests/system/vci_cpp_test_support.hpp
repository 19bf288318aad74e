// What the tests of the VCI C++ API (libvciapi: vcisdk.h) share: references that release what
// they hold, an adapter opened the way the guide's walk-through opens it, and messages and
// their time on the wire.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci_test_support.hpp"
#include "vcisdk.h"

namespace canemu::testing {

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

// The VciObjectId of the adapter named `name` (0 if there is none), from the device manager.
inline INT64 vci_id_named(const std::string& name) {
  Ref<IVciDeviceManager> manager;
  EXPECT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  Ref<IVciEnumDevice> e;
  EXPECT_EQ(manager->EnumDevices(e.out()), VCI_OK);
  VCIDEVICEINFO info{};
  while (e->Next(1, &info, nullptr) == VCI_OK) {
    if (std::string(info.Description).find("(canemu " + name + ")") != std::string::npos) {
      return info.VciObjectId.AsInt64;
    }
  }
  return 0;
}

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
    VCIID id{};
    id.AsInt64 = vci_id_named(name);
    EXPECT_EQ(manager->OpenDevice(id, device.out()), VCI_OK);
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
inline void open_bal(INT64 id, Ref<IBalObject>& bal) {
  Ref<IVciDeviceManager> manager;
  ASSERT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  VCIID vciid{};
  vciid.AsInt64 = id;
  Ref<IVciDevice> device;
  ASSERT_EQ(manager->OpenDevice(vciid, device.out()), VCI_OK);
  ASSERT_EQ(device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
}

// `device`'s info, and the info of the device VciQueryDeviceByHwid opens by its hardware ID.
inline void query_by_hwid(IVciDevice* device, VCIDEVICEINFO* info, VCIDEVICEINFO* found) {
  ASSERT_EQ(device->GetDeviceInfo(info), VCI_OK);
  Ref<IVciDevice> same;
  ASSERT_EQ(VciQueryDeviceByHwid(info->UniqueHardwareId.AsGuid, same.out()), VCI_OK);
  ASSERT_EQ(same->GetDeviceInfo(found), VCI_OK);
}

inline CANMSG one_byte(UINT32 id, UINT8 b) {
  CANMSG m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  m.abData[0] = b;
  return m;
}

// What `reader` holds, taken out as `Msg` (CANMSG or CANMSG2; `data_only`: only the data
// frames).
template <class Msg = CANMSG>
inline std::vector<Msg> drain(IFifoReader* reader, bool data_only) {
  std::vector<Msg> got;
  Msg m;
  while (reader->GetDataEntry(&m) == VCI_OK) {
    if (!data_only || m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
      got.push_back(m);
    }
  }
  return got;
}

inline constexpr UINT8 kMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME;
inline constexpr CANBTP kNominal{0, 500000, 14, 2, 1, 0};  // 16 quanta
inline constexpr CANBTP kData{0, 2000000, 8, 2, 1, 0};     // 10 quanta

// An adapter's controller through the v2 interfaces: a PASS channel with its reader and writer,
// the control unit initialized with `op_mode` and `ex_mode` (500 kbit/s, and 2 Mbit/s with
// FASTDATA) and started.
struct V2Adapter {
  Ref<IBalObject> bal;
  Ref<ICanSocket2> socket;
  Ref<ICanChannel2> channel;
  Ref<IFifoReader> reader;
  Ref<IFifoWriter> writer;
  Ref<ICanControl2> control;
  UINT8 op_mode;
  V2Adapter(const std::string& name, UINT8 ex_mode, UINT8 mode = kMode) : op_mode(mode) {
    open_bal(vci_id_named(name), bal);
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanSocket2, socket.pv()), VCI_OK);
    EXPECT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
    EXPECT_EQ(channel->Initialize(256, 64, 0, CAN_FILTER_PASS), VCI_OK);
    EXPECT_EQ(channel->GetReader(reader.out()), VCI_OK);
    EXPECT_EQ(channel->GetWriter(writer.out()), VCI_OK);
    EXPECT_EQ(channel->Activate(), VCI_OK);
    EXPECT_EQ(channel->GetControl(control.out()), VCI_OK);
    init(ex_mode);
    EXPECT_EQ(control->StartLine(), VCI_OK);
  }
  void init(UINT8 ex_mode) {
    CANINITLINE2 init{};
    init.bOpMode = op_mode;
    init.bExMode = ex_mode;
    init.bSFMode = CAN_FILTER_PASS;
    init.bEFMode = CAN_FILTER_PASS;
    init.sBtpSdr = kNominal;
    if ((ex_mode & CAN_EXMODE_FASTDATA) != 0) {
      init.sBtpFdr = kData;
    }
    EXPECT_EQ(control->InitLine(&init), VCI_OK);
  }
  void post(CANMSG2 m) const { ASSERT_EQ(writer->PutDataEntry(&m), VCI_OK); }
};

// The end of a classic frame sent at t = 0, in device ticks (us) at 500 kbit/s.
inline UINT32 end_of(uint32_t id, std::vector<uint8_t> data, bool ext = false) {
  return 2u * model::encode(*model::Frame::classic(id, data, ext)).length;  // 2 us a bit
}

}  // namespace canemu::testing
