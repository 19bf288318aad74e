// What the tests of the classic VCI C API (libvcinpl: CANMSG, BTR0/BTR1) share: an adapter's
// controller opened as a VCI program opens it, messages and their bits on the wire.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci_test_support.hpp"
#include "vcinpl.h"
// after vcinpl.h
#include "vci_c_common_support.hpp"

namespace canemu::testing {

inline constexpr UINT8 kMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME;
inline constexpr int64_t kBitUs2 = 2;  // one bit at 500 kbit/s is 2 us

// One adapter's controller opened as a VCI program opens it: device, control unit, one
// channel (receive FIFO `rx`, transmit FIFO 64), initialized at 500 kbit/s, started.
struct Adapter {
  HANDLE device = nullptr;
  HANDLE control = nullptr;
  HANDLE channel = nullptr;
  explicit Adapter(const std::string& name, bool start = true, UINT8 mode = kMode, UINT16 rx = 1024,
                   UINT8 btr0 = CAN_BT0_500KB, UINT8 btr1 = CAN_BT1_500KB) {
    const VCIID id = id_of(name);
    EXPECT_EQ(vciDeviceOpen(id, &device), VCI_OK);
    EXPECT_EQ(canControlOpen(device, 0, &control), VCI_OK);
    EXPECT_EQ(canChannelOpen(device, 0, FALSE, &channel), VCI_OK);
    EXPECT_EQ(canChannelInitialize(channel, rx, 1, 64, 1), VCI_OK);
    EXPECT_EQ(canChannelActivate(channel, TRUE), VCI_OK);
    EXPECT_EQ(canControlInitialize(control, mode, btr0, btr1), VCI_OK);
    if (start) {
      EXPECT_EQ(canControlStart(control, TRUE), VCI_OK);
    }
  }
  ~Adapter() {
    canChannelClose(channel);
    canControlClose(control);
    vciDeviceClose(device);
  }
  std::vector<CANMSG> drain() const {
    std::vector<CANMSG> got;
    CANMSG m;
    while (canChannelPeekMessage(channel, &m) == VCI_OK) {
      got.push_back(m);
    }
    return got;
  }
  // The data frames among what arrived.
  std::vector<CANMSG> frames() const {
    std::vector<CANMSG> got;
    for (const CANMSG& m : drain()) {
      if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
        got.push_back(m);
      }
    }
    return got;
  }
  void post(const CANMSG& m) const {
    CANMSG copy = m;
    ASSERT_EQ(canChannelPostMessage(channel, &copy), VCI_OK);
  }
};

inline CANMSG data(uint32_t id, std::vector<uint8_t> bytes, bool ext = false, bool rtr = false) {
  CANMSG m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = static_cast<UINT8>(bytes.size()) & 0x0FU;
  m.uMsgInfo.Bits.ext = ext ? 1 : 0;
  m.uMsgInfo.Bits.rtr = rtr ? 1 : 0;
  if (!bytes.empty()) {
    std::memcpy(m.abData, bytes.data(), bytes.size());
  }
  return m;
}

// Bits on the wire of a classic frame.
inline int64_t bits_of(uint32_t id, std::vector<uint8_t> bytes, bool ext = false) {
  auto f = model::Frame::classic(id, bytes, ext);
  return static_cast<int64_t>(model::encode(*f).length);
}

}  // namespace canemu::testing
