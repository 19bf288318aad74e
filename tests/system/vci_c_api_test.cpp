// The classic VCI C API (libvcinpl: CANMSG, BTR0/BTR1) against a real canemud in stepped time:
// what a program written for an IXXAT USB-to-CAN sees, with exact time stamps (device ticks of
// 1 us counted from canemud's start).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci_test_support.hpp"
#include "vcinpl.h"

namespace canemu {
namespace {

using testing::step_ns;
using testing::VciDaemon;

constexpr UINT8 kMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME;
constexpr int64_t kBitUs2 = 2;  // one bit at 500 kbit/s is 2 us

VCIID id_of(const std::string& name) {
  HANDLE e = nullptr;
  EXPECT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
  VCIDEVICEINFO info{};
  VCIID id{};
  while (vciEnumDeviceNext(e, &info) == VCI_OK) {
    if (std::string(info.Description).find("(canemu " + name + ")") != std::string::npos) {
      id = info.VciObjectId;
    }
  }
  vciEnumDeviceClose(e);
  return id;
}

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

CANMSG data(uint32_t id, std::vector<uint8_t> bytes, bool ext = false, bool rtr = false) {
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
int64_t bits_of(uint32_t id, std::vector<uint8_t> bytes, bool ext = false) {
  auto f = model::Frame::classic(id, bytes, ext);
  return static_cast<int64_t>(model::encode(*f).length);
}

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

TEST(VciCApi, TheControlUnitGoesThroughItsStatesAndAnnouncesThem) {
  VciDaemon d;
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  HANDLE control = nullptr;
  HANDLE second = nullptr;
  ASSERT_EQ(canControlOpen(dev, 0, &control), VCI_OK);
  EXPECT_EQ(canControlOpen(dev, 0, &second), VCI_E_ACCESSDENIED);
  CANLINESTATUS s{};
  ASSERT_EQ(canControlGetStatus(control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(canControlStart(control, TRUE), VCI_E_INVALID_STATE);
  HANDLE ch = nullptr;
  ASSERT_EQ(canChannelOpen(dev, 0, FALSE, &ch), VCI_OK);
  EXPECT_EQ(canChannelActivate(ch, TRUE), VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(canChannelInitialize(ch, 0, 1, 16, 1), VCI_E_INVALIDARG);
  ASSERT_EQ(canChannelInitialize(ch, 64, 1, 16, 1), VCI_OK);
  ASSERT_EQ(canChannelActivate(ch, TRUE), VCI_OK);
  ASSERT_EQ(canControlInitialize(control, kMode, CAN_BT0_250KB, CAN_BT1_250KB), VCI_OK);
  ASSERT_EQ(canControlGetStatus(control, &s), VCI_OK);
  EXPECT_EQ(s.bOpMode, kMode);
  EXPECT_EQ(s.bBtReg0, CAN_BT0_250KB);
  EXPECT_EQ(s.bBtReg1, CAN_BT1_250KB);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  step_ns(1'000'000);
  ASSERT_EQ(canControlStart(control, TRUE), VCI_OK);
  ASSERT_EQ(canControlGetStatus(control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, 0u);
  step_ns(500'000);
  ASSERT_EQ(canControlStart(control, FALSE), VCI_OK);
  ASSERT_EQ(canControlReset(control), VCI_OK);
  ASSERT_EQ(canControlGetStatus(control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  // INFO messages: start at its instant (1000 ticks of 1 us), stop and reset with time 0.
  std::vector<CANMSG> got;
  CANMSG m;
  while (canChannelReadMessage(ch, 0, &m) == VCI_OK) {
    got.push_back(m);
  }
  ASSERT_EQ(got.size(), 3u);
  for (const CANMSG& info : got) {
    EXPECT_EQ(info.uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
    EXPECT_EQ(info.dwMsgId, CAN_MSGID_INFO);
    EXPECT_EQ(info.uMsgInfo.Bits.dlc, 1u);
  }
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 1000u);
  EXPECT_EQ(got[1].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(got[1].dwTime, 0u);
  EXPECT_EQ(got[2].abData[0], CAN_INFO_RESET);
  EXPECT_EQ(canChannelReadMessage(ch, 0, &m), VCI_E_TIMEOUT);
  EXPECT_EQ(canChannelPeekMessage(ch, &m), VCI_E_RXQUEUE_EMPTY);
  // Released, the control unit can be opened again.
  EXPECT_EQ(canControlClose(control), VCI_OK);
  EXPECT_EQ(canControlOpen(dev, 0, &second), VCI_OK);
  canControlClose(second);
  canChannelClose(ch);
  vciDeviceClose(dev);
}

TEST(VciCApi, TwoProgramsOnTwoAdaptersTalkAtExactInstants) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  alpha.post(data(0x123, {0x11, 0x22}));
  step_ns(1'000'000);
  beta.post(data(0x12345678, {0, 0, 0, 0}, true, true));
  step_ns(1'000'000);
  // 0x123 with two bytes: 62 bits from t = 0; the remote frame from t = 1 ms.
  const auto at_beta = beta.frames();
  ASSERT_EQ(at_beta.size(), 1u);
  EXPECT_EQ(at_beta[0].dwMsgId, 0x123u);
  EXPECT_EQ(at_beta[0].dwTime, 124u);
  EXPECT_EQ(at_beta[0].uMsgInfo.Bits.dlc, 2u);
  EXPECT_EQ(at_beta[0].abData[0], 0x11);
  EXPECT_EQ(at_beta[0].abData[1], 0x22);
  EXPECT_EQ(at_beta[0].uMsgInfo.Bits.srr, 0u);
  EXPECT_EQ(at_beta[0].uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_1);  // the open acceptance filter
  const auto at_alpha = alpha.frames();
  ASSERT_EQ(at_alpha.size(), 1u);
  EXPECT_EQ(at_alpha[0].dwMsgId, 0x12345678u);
  EXPECT_EQ(at_alpha[0].uMsgInfo.Bits.ext, 1u);
  EXPECT_EQ(at_alpha[0].uMsgInfo.Bits.rtr, 1u);
  EXPECT_EQ(at_alpha[0].uMsgInfo.Bits.dlc, 4u);
  EXPECT_EQ(at_alpha[0].dwTime, 1000u + 64 * kBitUs2);
}

TEST(VciCApi, ALoneAdapterSeesAckErrorsWarningAndErrorPassive) {
  VciDaemon d;
  Adapter alpha("alpha");
  alpha.post(data(0x10, {1}));
  step_ns(10'000'000);
  std::vector<CANMSG> errors;
  std::vector<CANMSG> statuses;
  for (const CANMSG& m : alpha.drain()) {
    if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_ERROR) {
      errors.push_back(m);
    } else if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_STATUS) {
      statuses.push_back(m);
    }
  }
  // Every attempt misses its ACK. The 12th error takes TEC to 96 (warning), the 16th to 128
  // (error-passive), where an error-passive transmitter's ACK errors stop counting.
  ASSERT_GT(errors.size(), 16u);
  for (std::size_t k = 0; k < errors.size(); ++k) {
    EXPECT_EQ(errors[k].dwMsgId, CAN_MSGID_ERROR);
    EXPECT_EQ(errors[k].abData[0], CAN_ERROR_ACK) << k;
    EXPECT_EQ((errors[k].abData[1] & CAN_STATUS_ERRLIM) != 0, k >= 11) << k;
  }
  ASSERT_EQ(statuses.size(), 1u);
  EXPECT_EQ(statuses[0].abData[0] & CAN_STATUS_ERRLIM, CAN_STATUS_ERRLIM);
  EXPECT_EQ(statuses[0].dwTime, errors[11].dwTime);
  UINT8 state = 0;
  UINT16 tec = 0;
  UINT16 rec = 0;
  UINT8 line = 0;
  ASSERT_EQ(canemuGetControllerState(alpha.channel, &state, &tec, &rec, &line), VCI_OK);
  EXPECT_EQ(state, CANEMU_STATE_PASSIVE);
  EXPECT_EQ(tec, 128);
  EXPECT_EQ(rec, 0);
  EXPECT_EQ(line, CANEMU_LINE_ONLINE);
  CANLINESTATUS s{};
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ERRLIM | CAN_STATUS_TXPEND));
}

TEST(VciCApi, WithoutErrorFramesModeNoErrorMessagesButStatusStillComes) {
  VciDaemon d;
  Adapter alpha("alpha", true, CAN_OPMODE_STANDARD);
  alpha.post(data(0x10, {1}));
  step_ns(10'000'000);
  std::size_t errors = 0;
  std::size_t statuses = 0;
  for (const CANMSG& m : alpha.drain()) {
    errors += m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_ERROR ? 1 : 0;
    statuses += m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_STATUS ? 1 : 0;
  }
  EXPECT_EQ(errors, 0u);
  EXPECT_EQ(statuses, 1u);
}

TEST(VciCApi, ThirtyTwoBitErrorsDriveTheSenderBusOffAndARestartRecovers) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  testing::load_faults(d.daemon,
                       "[[fault]]\nat = \"0s\"\nbus = \"can0\"\nmatch = { from = \"alpha:0\" }\n"
                       "effect = \"bit_error\"\ncount = 32\n");
  alpha.post(data(0x10, {1}));
  step_ns(20'000'000);
  std::vector<CANMSG> errors;
  std::vector<CANMSG> statuses;
  for (const CANMSG& m : alpha.drain()) {
    if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_ERROR) {
      errors.push_back(m);
    } else if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_STATUS) {
      statuses.push_back(m);
    }
  }
  ASSERT_EQ(errors.size(), 32u);
  for (const CANMSG& e : errors) {
    EXPECT_EQ(e.abData[0], CAN_ERROR_BIT);
  }
  EXPECT_EQ(errors.back().abData[1] & CAN_STATUS_BUSOFF, CAN_STATUS_BUSOFF);
  ASSERT_EQ(statuses.size(), 2u);  // warning at the 12th error, bus-off at the 32nd
  EXPECT_EQ(statuses[0].abData[0] & (CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF), CAN_STATUS_ERRLIM);
  EXPECT_EQ(statuses[1].abData[0] & CAN_STATUS_BUSOFF, CAN_STATUS_BUSOFF);
  EXPECT_EQ(statuses[1].dwTime, errors.back().dwTime);
  UINT8 state = 0;
  UINT16 tec = 0;
  ASSERT_EQ(canemuGetControllerState(alpha.control, &state, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(state, CANEMU_STATE_BUSOFF);
  EXPECT_EQ(tec, 256);  // 32 x 8, above 255
  EXPECT_TRUE(beta.frames().empty());
  // Stopped and started again: 128 x 11 recessive bits of recovery, then it sends.
  ASSERT_EQ(canControlStart(alpha.control, FALSE), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  alpha.post(data(0x11, {2}));
  step_ns(10'000'000);
  ASSERT_EQ(canemuGetControllerState(alpha.control, &state, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(state, CANEMU_STATE_ACTIVE);
  const auto got = beta.frames();
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.back().dwMsgId, 0x11u);
  CANLINESTATUS s{};
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus & (CAN_STATUS_BUSOFF | CAN_STATUS_ERRLIM), 0u);
}

TEST(VciCApi, TheControlUnitsFilterPassesOnlyWhatItAccepts) {
  VciDaemon d;
  Adapter alpha("alpha", false);
  Adapter beta("beta");
  // IDs 0x100..0x103 without RTR: code 001 0000 0000 0, mask 111 1111 1100 1.
  ASSERT_EQ(canControlSetAccFilter(alpha.control, FALSE, 0x200, 0xFF9), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  EXPECT_EQ(canControlSetAccFilter(alpha.control, FALSE, 0, 0), VCI_E_INVALID_STATE);
  for (uint32_t id = 0x100; id <= 0x104; ++id) {
    beta.post(data(id, {}));
  }
  beta.post(data(0x100, {}, false, true));
  beta.post(data(0x1ABCDE, {}, true));  // the 29-bit filter is still open
  step_ns(5'000'000);
  std::vector<uint32_t> ids;
  for (const CANMSG& m : alpha.frames()) {
    ids.push_back(m.dwMsgId);
    EXPECT_EQ(m.uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_1);
  }
  EXPECT_EQ(ids, (std::vector<uint32_t>{0x100, 0x101, 0x102, 0x103, 0x1ABCDE}));
  // Offline again: only the ID list decides, with one ID in it.
  ASSERT_EQ(canControlStart(alpha.control, FALSE), VCI_OK);
  ASSERT_EQ(canControlSetAccFilter(alpha.control, FALSE, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE),
            VCI_OK);
  ASSERT_EQ(canControlAddFilterIds(alpha.control, FALSE, 0x123 << 1, 0xFFF), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  beta.post(data(0x122, {}));
  beta.post(data(0x123, {}));
  step_ns(5'000'000);
  const auto listed = alpha.frames();
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].dwMsgId, 0x123u);
  EXPECT_EQ(listed[0].uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_2);
  // Removed again: nothing passes.
  ASSERT_EQ(canControlStart(alpha.control, FALSE), VCI_OK);
  ASSERT_EQ(canControlRemFilterIds(alpha.control, FALSE, 0x123 << 1, 0xFFF), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  beta.post(data(0x123, {}));
  step_ns(5'000'000);
  EXPECT_TRUE(alpha.frames().empty());
}

TEST(VciCApi, SelfReceptionReachesEveryChannelOfTheController) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  HANDLE second = nullptr;
  ASSERT_EQ(canChannelOpen(alpha.device, 0, FALSE, &second), VCI_OK);
  ASSERT_EQ(canChannelInitialize(second, 64, 1, 0, 0), VCI_OK);
  ASSERT_EQ(canChannelActivate(second, TRUE), VCI_OK);
  HANDLE exclusive = nullptr;
  EXPECT_EQ(canChannelOpen(alpha.device, 0, TRUE, &exclusive), VCI_E_ACCESSDENIED);
  EXPECT_EQ(exclusive, nullptr);
  CANMSG own = data(0x321, {7});
  own.uMsgInfo.Bits.srr = 1;
  alpha.post(own);
  alpha.post(data(0x322, {8}));  // without srr: invisible to both
  step_ns(2'000'000);
  const auto first = alpha.frames();
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].dwMsgId, 0x321u);
  EXPECT_EQ(first[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(first[0].dwTime, static_cast<UINT32>(bits_of(0x321, {7}) * kBitUs2));
  std::vector<CANMSG> at_second;
  CANMSG m;
  while (canChannelPeekMessage(second, &m) == VCI_OK) {
    if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
      at_second.push_back(m);
    }
  }
  ASSERT_EQ(at_second.size(), 1u);
  EXPECT_EQ(at_second[0].dwMsgId, 0x321u);
  EXPECT_EQ(at_second[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(beta.frames().size(), 2u);
  // A channel without a transmit FIFO cannot send.
  CANMSG x = data(1, {});
  EXPECT_EQ(canChannelPostMessage(second, &x), VCI_E_ACCESSDENIED);
  canChannelClose(second);
}

TEST(VciCApi, AFullReceiveFifoLosesTheNewestAndMarksTheNextOneThatFits) {
  VciDaemon d;
  Adapter alpha("alpha", true, kMode, 1);
  Adapter beta("beta");
  std::vector<CANMSG> burst(300, data(0x55, {1}));
  UINT32 done = 0;
  ASSERT_EQ(canChannelSendMsgMult(beta.channel, 0, burst.data(), 64, &done), VCI_OK);
  EXPECT_EQ(done, 64u);
  step_ns(20'000'000);
  ASSERT_EQ(canChannelSendMsgMult(beta.channel, 0, burst.data(), 64, &done), VCI_OK);
  step_ns(20'000'000);
  ASSERT_EQ(canChannelSendMsgMult(beta.channel, 0, burst.data(), 64, &done), VCI_OK);
  step_ns(20'000'000);
  ASSERT_EQ(canChannelSendMsgMult(beta.channel, 0, burst.data(), 64, &done), VCI_OK);
  step_ns(20'000'000);
  CANCHANSTATUS s{};
  ASSERT_EQ(canChannelGetStatus(alpha.channel, &s), VCI_OK);
  EXPECT_TRUE(s.fRxOverrun);
  EXPECT_EQ(s.bRxFifoLoad, 100);
  const auto kept = alpha.drain();  // the INFO START and the first frames that fitted
  ASSERT_LT(kept.size(), 257u);
  for (const CANMSG& m : kept) {
    EXPECT_EQ(m.uMsgInfo.Bits.ovr, 0u);
  }
  beta.post(data(0x56, {2}));
  step_ns(1'000'000);
  const auto next = alpha.drain();
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].dwMsgId, 0x56u);
  EXPECT_EQ(next[0].uMsgInfo.Bits.ovr, 1u);
  ASSERT_EQ(canChannelGetStatus(alpha.channel, &s), VCI_OK);
  EXPECT_TRUE(s.fRxOverrun);  // until the channel is initialized again
}

TEST(VciCApi, ADelayedMessageWaitsItsTicksAfterThePreviousOne) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  alpha.post(data(0x123, {0x11, 0x22}));
  CANMSG later = data(0x123, {0x11, 0x22});
  later.dwTime = 1000;  // ticks of 1 us after the previous frame was handed over
  alpha.post(later);
  step_ns(5'000'000);
  const auto got = beta.frames();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].dwTime, 124u);
  EXPECT_EQ(got[1].dwTime, 1000u + 124u);
}

TEST(VciCApi, TheCyclicListSendsOnItsTicksAndIncrementsTheIdentifier) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  HANDLE list = nullptr;
  HANDLE other = nullptr;
  ASSERT_EQ(canSchedulerOpen(alpha.device, 0, &list), VCI_OK);
  EXPECT_EQ(canSchedulerOpen(beta.device, 0, &other), VCI_OK);  // beta's own list
  HANDLE again = nullptr;
  EXPECT_EQ(canSchedulerOpen(alpha.device, 0, &again), VCI_E_ACCESSDENIED);
  CANCAPABILITIES caps{};
  ASSERT_EQ(canSchedulerGetCaps(list, &caps), VCI_OK);
  EXPECT_EQ(caps.dwClockFreq, 1'000'000u);
  EXPECT_EQ(caps.dwCmsDivisor, 1000u);  // 1 ms ticks
  CANCYCLICTXMSG m{};
  m.wCycleTime = 2;
  m.bIncrMode = CAN_CTXMSG_INC_ID;
  m.dwMsgId = 0x7FE;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  m.abData[0] = 0xA5;
  UINT32 index = 0;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  EXPECT_EQ(index, 0u);
  m.wCycleTime = 0;
  UINT32 bad = 0;
  EXPECT_EQ(canSchedulerAddMessage(list, &m, &bad), VCI_E_INVALIDARG);
  EXPECT_EQ(bad, 0xFFFFFFFFu);
  ASSERT_EQ(canSchedulerStartMessage(list, index, 3), VCI_OK);
  step_ns(10'000'000);
  EXPECT_TRUE(beta.frames().empty());                   // the task is off until it is activated
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);  // at t = 10 ms
  step_ns(20'000'000);
  const auto got = beta.frames();
  ASSERT_EQ(got.size(), 3u);
  const std::vector<uint32_t> ids{0x7FE, 0x7FF, 0x000};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(got[k].dwMsgId, ids[k]);
    // Ticks 2, 4, 6 after activation, each frame at its end of frame.
    EXPECT_EQ(got[k].dwTime,
              10'000u + 2'000u * (k + 1) + static_cast<UINT32>(bits_of(ids[k], {0xA5}) * kBitUs2))
        << k;
  }
  CANSCHEDULERSTATUS s{};
  ASSERT_EQ(canSchedulerGetStatus(list, &s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_DONE);
  EXPECT_EQ(s.abMsgStat[1], CAN_CTXMSG_STAT_EMPTY);
  ASSERT_EQ(canSchedulerRemMessage(list, index), VCI_OK);
  EXPECT_EQ(canSchedulerStartMessage(list, index, 1), VCI_E_INVALID_INDEX);
  canSchedulerClose(other);
  canSchedulerClose(list);
}

TEST(VciCApi, TheTimeStampCounterAnnouncesItsOverflow) {
  VciDaemon d;
  Adapter alpha("alpha");
  step_ns(4'295'000'000'000);  // past 2^32 us
  const auto got = alpha.drain();
  ASSERT_EQ(got.size(), 2u);  // INFO START, then TIMEOVR
  EXPECT_EQ(got[1].uMsgInfo.Bytes.bType, CAN_MSGTYPE_TIMEOVR);
  EXPECT_EQ(got[1].dwMsgId, 1u);  // one overflow
  EXPECT_EQ(got[1].dwTime, 0u);   // at 2^32 us the counter shows 0 again
}

// In real time a blocked reader wakes when the frame comes, and a writer's doorbell wakes the
// daemon: no steps anywhere.
TEST(VciCApi, InRealTimeAReaderBlocksUntilTheFrameComes) {
  testing::ConfigFile config(testing::kTwoAdapters);
  testing::Daemon daemon("realtime", {"--config=" + config.path()});
  ASSERT_EQ(canemuConnect(daemon.socket().c_str()), VCI_OK);
  {
    Adapter alpha("alpha");
    Adapter beta("beta");
    CANMSG m;
    ASSERT_EQ(canChannelReadMessage(beta.channel, 5000, &m), VCI_OK);  // INFO START
    EXPECT_EQ(m.uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
    CANMSG sent = data(0x321, {1, 2, 3});
    ASSERT_EQ(canChannelSendMessage(alpha.channel, 1000, &sent), VCI_OK);
    ASSERT_EQ(canChannelReadMessage(beta.channel, 5000, &m), VCI_OK);
    EXPECT_EQ(m.dwMsgId, 0x321u);
    EXPECT_EQ(m.uMsgInfo.Bits.dlc, 3u);
    EXPECT_EQ(canChannelReadMessage(beta.channel, 50, &m), VCI_E_TIMEOUT);
    EXPECT_EQ(canemuStepTime(1000, nullptr), VCI_E_INVALID_STATE);  // not stepped time
  }
  canemuConnect(nullptr);
}

// Two programs of their own (examples/vci_c_talk.c, plain C), each on its adapter.
TEST(VciCApi, TwoProgramsOnTwoAdaptersTalkThroughTheCApi) {
  testing::ConfigFile config(testing::kTwoAdapters);
  testing::Daemon daemon("realtime", {"--config=" + config.path()});
  const std::string env = "CANEMU_SOCKET=" + daemon.socket() + " ";
  FILE* receiver = ::popen((env + VCI_C_TALK_PATH + " receive beta").c_str(), "r");
  ASSERT_NE(receiver, nullptr);
  char line[128] = {};
  ASSERT_NE(std::fgets(line, sizeof line, receiver), nullptr);
  EXPECT_STREQ(line, "ready\n");
  const int sender = std::system((env + VCI_C_TALK_PATH + " send alpha 1A5 7E").c_str());
  EXPECT_EQ(sender, 0);
  ASSERT_NE(std::fgets(line, sizeof line, receiver), nullptr);
  EXPECT_STREQ(line, "1A5#7E\n");
  EXPECT_EQ(::pclose(receiver), 0);
}

// Steps simulated time a millisecond at a time until `done` (set by another thread that waits
// for something in simulated time), for at most 30 s of wall time.
void step_until(const std::atomic<bool>& done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!done && std::chrono::steady_clock::now() < give_up) {
    step_ns(1'000'000);
  }
  ASSERT_TRUE(done) << "the waiting call did not return";
}

// A program that does not know the bus's rate finds it: two adapters talk at 250 kbit/s, a
// third listens with a table of rates. The call blocks while simulated time runs, so another
// thread steps it.
TEST(VciCApi, DetectBitrateFindsTheRateOfTheTrafficOnTheBus) {
  VciDaemon d(std::string(testing::kTwoAdapters) +
              "\n[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\n"
              "controllers = [\"can0\"]\n");
  Adapter beta("beta", true, kMode, 1024, CAN_BT0_250KB, CAN_BT1_250KB);
  Adapter gamma("gamma", true, kMode, 1024, CAN_BT0_250KB, CAN_BT1_250KB);
  HANDLE list = nullptr;
  ASSERT_EQ(canSchedulerOpen(beta.device, 0, &list), VCI_OK);
  CANCYCLICTXMSG m{};
  m.wCycleTime = 1;  // a frame every millisecond
  m.dwMsgId = 0x2A0;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  UINT32 index = 0;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  ASSERT_EQ(canSchedulerStartMessage(list, index, 0), VCI_OK);
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);

  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  HANDLE control = nullptr;
  ASSERT_EQ(canControlOpen(dev, 0, &control), VCI_OK);
  UINT8 btr0[] = {CAN_BT0_500KB, CAN_BT0_250KB, CAN_BT0_125KB};
  UINT8 btr1[] = {CAN_BT1_500KB, CAN_BT1_250KB, CAN_BT1_125KB};
  INT32 found = -2;
  std::atomic<bool> done{false};
  HRESULT hr = VCI_E_UNEXPECTED;
  std::thread detector([&] {
    hr = canControlDetectBitrate(control, 100, 3, btr0, btr1, &found);
    done = true;
  });
  step_until(done);
  detector.join();
  EXPECT_EQ(hr, VCI_OK);
  EXPECT_EQ(found, 1);
  // With what it found, the third adapter receives the traffic.
  ASSERT_EQ(canControlInitialize(control, kMode, btr0[found], btr1[found]), VCI_OK);
  HANDLE ch = nullptr;
  ASSERT_EQ(canChannelOpen(dev, 0, FALSE, &ch), VCI_OK);
  ASSERT_EQ(canChannelInitialize(ch, 64, 1, 0, 0), VCI_OK);
  ASSERT_EQ(canChannelActivate(ch, TRUE), VCI_OK);
  ASSERT_EQ(canControlStart(control, TRUE), VCI_OK);
  step_ns(5'000'000);
  std::size_t frames = 0;
  CANMSG got;
  while (canChannelPeekMessage(ch, &got) == VCI_OK) {
    frames += got.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA && got.dwMsgId == 0x2A0 ? 1 : 0;
  }
  EXPECT_GE(frames, 4u);
  // On a bus nobody talks on, it gives up after each entry's wait.
  ASSERT_EQ(canSchedulerActivate(list, FALSE), VCI_OK);
  ASSERT_EQ(canControlReset(control), VCI_OK);
  step_ns(5'000'000);
  done = false;
  std::thread silent([&] {
    hr = canControlDetectBitrate(control, 10, 2, btr0, btr1, &found);
    done = true;
  });
  step_until(done);
  silent.join();
  EXPECT_EQ(hr, VCI_E_TIMEOUT);
  EXPECT_EQ(found, -1);
  canChannelClose(ch);
  canControlClose(control);
  canSchedulerClose(list);
  vciDeviceClose(dev);
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

TEST(VciCApi, ADelayAboveTheMaximumIsClampedAndHighPriorityGoesFirst) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  CANCAPABILITIES caps{};
  ASSERT_EQ(canChannelGetCaps(alpha.channel, &caps), VCI_OK);
  ASSERT_EQ(caps.dwDtxMaxTicks, 65535u);
  alpha.post(data(0x123, {0x11, 0x22}));
  CANMSG far = data(0x123, {0x11, 0x22});
  far.dwTime = 200'000;  // above the maximum: taken as 65535 ticks
  alpha.post(far);
  step_ns(100'000'000);
  auto got = beta.frames();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].dwTime, 65'535u + 124u);
  // Two channels: a high-priority frame of the second overtakes the first's waiting frame (not
  // the one already in the controller).
  HANDLE second = nullptr;
  ASSERT_EQ(canChannelOpen(alpha.device, 0, FALSE, &second), VCI_OK);
  ASSERT_EQ(canChannelInitialize(second, 64, 1, 16, 1), VCI_OK);
  ASSERT_EQ(canChannelActivate(second, TRUE), VCI_OK);
  alpha.post(data(0x201, {1}));
  alpha.post(data(0x202, {2}));
  step_ns(10'000);  // 0x201 is on the wire
  CANMSG urgent = data(0x300, {3});
  urgent.uMsgInfo.Bits.hpm = 1;
  ASSERT_EQ(canChannelPostMessage(second, &urgent), VCI_OK);
  step_ns(5'000'000);
  std::vector<uint32_t> order;
  for (const CANMSG& m : beta.frames()) {
    order.push_back(m.dwMsgId);
  }
  EXPECT_EQ(order, (std::vector<uint32_t>{0x201, 0x300, 0x202}));
  canChannelClose(second);
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
}  // namespace canemu
