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

// One more channel on `device`'s controller (receive FIFO `rx`, transmit FIFO `tx`: none if
// 0), initialized and activated.
inline void open_channel(HANDLE device, UINT16 rx, UINT16 tx, HANDLE* channel) {
  ASSERT_EQ(canChannelOpen(device, 0, FALSE, channel), VCI_OK);
  ASSERT_EQ(canChannelInitialize(*channel, rx, 1, tx, tx == 0 ? 0 : 1), VCI_OK);
  ASSERT_EQ(canChannelActivate(*channel, TRUE), VCI_OK);
}

// open_channel's channel, closed with the object.
struct ExtraChannel : OwnedHandle<canChannelClose> {
  ExtraChannel(HANDLE device, UINT16 rx, UINT16 tx) { open_channel(device, rx, tx, &handle_); }
};

// `control`'s 11-bit filter passes only 0x123 (the acceptance filter shut, the ID list holding
// it), and the line starts.
inline void pass_only_0x123_and_start(HANDLE control) {
  ASSERT_EQ(canControlSetAccFilter(control, FALSE, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE), VCI_OK);
  ASSERT_EQ(canControlAddFilterIds(control, FALSE, 0x123 << 1, 0xFFF), VCI_OK);
  ASSERT_EQ(canControlStart(control, TRUE), VCI_OK);
}

// An adapter's device, its control unit and a channel (receive FIFO `rx`, transmit FIFO `tx`,
// with their event thresholds) initialized but not yet activated.
struct Parts : ControllerHandles {
  explicit Parts(const std::string& name, UINT16 rx = 64, UINT16 tx = 16, UINT16 rx_threshold = 1,
                 UINT16 tx_threshold = 1) {
    EXPECT_EQ(vciDeviceOpen(id_of(name), &device), VCI_OK);
    EXPECT_EQ(canControlOpen(device, 0, &control), VCI_OK);
    EXPECT_EQ(canChannelOpen(device, 0, FALSE, &channel), VCI_OK);
    EXPECT_EQ(canChannelInitialize(channel, rx, rx_threshold, tx, tx_threshold), VCI_OK);
  }
  // Activates the channel and initializes the line at 500 kbit/s, not yet started.
  void activate_and_init_line() const {
    ASSERT_EQ(canChannelActivate(channel, TRUE), VCI_OK);
    ASSERT_EQ(canControlInitialize(control, kMode, CAN_BT0_500KB, CAN_BT1_500KB), VCI_OK);
  }
  // All that arrived.
  std::vector<CANMSG> drain() const { return testing::drain(channel, false); }
  // The data frames among what arrived.
  std::vector<CANMSG> frames() const { return testing::drain(channel, true); }
  // The channel's status.
  CANCHANSTATUS status() const {
    CANCHANSTATUS s{};
    EXPECT_EQ(canChannelGetStatus(channel, &s), VCI_OK);
    return s;
  }
};

// One adapter's controller opened as a VCI program opens it: device, control unit, one
// channel (receive FIFO `rx`, transmit FIFO 64), initialized at 500 kbit/s, started.
struct Adapter : Parts {
  explicit Adapter(const std::string& name, bool start = true, UINT8 mode = kMode, UINT16 rx = 1024,
                   UINT8 btr0 = CAN_BT0_500KB, UINT8 btr1 = CAN_BT1_500KB)
      : Parts(name, rx, 64) {
    EXPECT_EQ(canChannelActivate(channel, TRUE), VCI_OK);
    EXPECT_EQ(canControlInitialize(control, mode, btr0, btr1), VCI_OK);
    if (start) {
      EXPECT_EQ(canControlStart(control, TRUE), VCI_OK);
    }
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
