// The control unit of the classic VCI C API (libvcinpl: BTR0/BTR1) against a real canemud in
// stepped time: line states and their announcements, error states, bus-off and restart, the
// acceptance filter, bit-rate detection and the time stamp counter's overflow.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "cli_process.hpp"
#include "vci_c_test_support.hpp"
#include "vcinpl.h"

namespace canemu {
namespace {

using testing::Adapter;
using testing::by_type;
using testing::ByType;
using testing::cyclic_data;
using testing::CyclicList;
using testing::data;
using testing::id_of;
using testing::kMode;
using testing::open_channel;
using testing::pass_only_0x123_and_start;
using testing::step_ns;
using testing::step_while;
using testing::VciDaemon;

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

TEST(VciCApi, ALoneAdapterSeesAckErrorsWarningAndErrorPassive) {
  VciDaemon d;
  Adapter alpha("alpha");
  alpha.post(data(0x10, {1}));
  step_ns(10'000'000);
  const ByType msgs = by_type(alpha.drain());
  // Every attempt misses its ACK. The 12th error takes TEC to 96 (warning), the 16th to 128
  // (error-passive), where an error-passive transmitter's ACK errors stop counting.
  ASSERT_GT(msgs.errors.size(), 16u);
  for (std::size_t k = 0; k < msgs.errors.size(); ++k) {
    EXPECT_EQ(msgs.errors[k].dwMsgId, CAN_MSGID_ERROR);
    EXPECT_EQ(msgs.errors[k].abData[0], CAN_ERROR_ACK) << k;
    EXPECT_EQ((msgs.errors[k].abData[1] & CAN_STATUS_ERRLIM) != 0, k >= 11) << k;
  }
  ASSERT_EQ(msgs.statuses.size(), 1u);
  EXPECT_EQ(msgs.statuses[0].abData[0] & CAN_STATUS_ERRLIM, CAN_STATUS_ERRLIM);
  EXPECT_EQ(msgs.statuses[0].dwTime, msgs.errors[11].dwTime);
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
  const ByType msgs = by_type(alpha.drain());
  ASSERT_EQ(msgs.errors.size(), 32u);
  for (const CANMSG& e : msgs.errors) {
    EXPECT_EQ(e.abData[0], CAN_ERROR_BIT);
  }
  EXPECT_EQ(msgs.errors.back().abData[1] & CAN_STATUS_BUSOFF, CAN_STATUS_BUSOFF);
  ASSERT_EQ(msgs.statuses.size(), 2u);  // warning at the 12th error, bus-off at the 32nd
  EXPECT_EQ(msgs.statuses[0].abData[0] & (CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF),
            CAN_STATUS_ERRLIM);
  EXPECT_EQ(msgs.statuses[1].abData[0] & CAN_STATUS_BUSOFF, CAN_STATUS_BUSOFF);
  EXPECT_EQ(msgs.statuses[1].dwTime, msgs.errors.back().dwTime);
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

// A long receive fault: the bus held dominant for 100 ms. Every 8 dominant bits after the error
// flag add 8 to the receivers' REC (ISO 11898-1 rule 6), but the SJA1000's RXERR is 8 bits wide:
// REC stops at 255 and stays there, in the controller state, the line status (ERRLIM, not
// BUSOFF), canemu status and the next ERROR message. The next frame received takes it to 127.
TEST(VciCApi, ALongReceiveFaultLeavesRecAt255) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  testing::load_faults(d.daemon,
                       "[[fault]]\nat = \"1ms\"\nbus = \"can0\"\neffect = \"stuck_dominant\"\n"
                       "duration = \"100ms\"\n\n"
                       "[[fault]]\nat = \"700ms\"\nbus = \"can0\"\n"
                       "match = { from = \"alpha:0\" }\neffect = \"stuff_error\"\ncount = 1\n");
  step_ns(600'000'000);
  for (const Adapter* a : {&alpha, &beta}) {
    UINT8 state = 0;
    UINT16 tec = 1;
    UINT16 rec = 0;
    ASSERT_EQ(canemuGetControllerState(a->control, &state, &tec, &rec, nullptr), VCI_OK);
    EXPECT_EQ(state, CANEMU_STATE_PASSIVE);
    EXPECT_EQ(tec, 0);
    EXPECT_EQ(rec, 255);
    CANLINESTATUS s{};
    ASSERT_EQ(canControlGetStatus(a->control, &s), VCI_OK);
    EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ERRLIM));
  }
  Cli status(d.daemon, {"status"});
  const std::string text = Cli::read_all(status.out);
  EXPECT_EQ(status.wait(), 0);
  EXPECT_NE(text.find("beta:0         can0         error-passive     0  255"), std::string::npos)
      << text;
  beta.drain();
  // A receive error while at 255: the ERROR message says 255 (REC as the error was counted).
  step_ns(100'000'000);  // to 700 ms: the fault waits for alpha's frame
  alpha.post(data(0x10, {1}));
  step_ns(10'000'000);
  const ByType msgs = by_type(beta.drain());
  ASSERT_EQ(msgs.errors.size(), 1u);
  EXPECT_EQ(msgs.errors[0].abData[0], CAN_ERROR_STUFF);
  EXPECT_EQ(msgs.errors[0].abData[1], CAN_STATUS_ERRLIM);
  EXPECT_EQ(msgs.errors[0].abData[3], 255);
  ASSERT_EQ(msgs.frames.size(), 1u);  // the repetition
  UINT16 rec = 0;
  ASSERT_EQ(canemuGetControllerState(beta.control, nullptr, nullptr, &rec, nullptr), VCI_OK);
  EXPECT_EQ(rec, 127);
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
  ASSERT_NO_FATAL_FAILURE(pass_only_0x123_and_start(alpha.control));
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

// A program that does not know the bus's rate finds it: two adapters talk at 250 kbit/s, a
// third listens with a table of rates. The call blocks while simulated time runs, so another
// thread steps it.
TEST(VciCApi, DetectBitrateFindsTheRateOfTheTrafficOnTheBus) {
  VciDaemon d(std::string(testing::kTwoAdapters) +
              "\n[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\n"
              "controllers = [\"can0\"]\n");
  Adapter beta("beta", true, kMode, 1024, CAN_BT0_250KB, CAN_BT1_250KB);
  Adapter gamma("gamma", true, kMode, 1024, CAN_BT0_250KB, CAN_BT1_250KB);
  const CyclicList list(beta.device);
  list.send_without_end(cyclic_data(0x2A0, 1, 1));  // a frame every millisecond

  const testing::ControlUnit alpha("alpha");
  UINT8 btr0[] = {CAN_BT0_500KB, CAN_BT0_250KB, CAN_BT0_125KB};
  UINT8 btr1[] = {CAN_BT1_500KB, CAN_BT1_250KB, CAN_BT1_125KB};
  INT32 found = -2;
  HRESULT hr = VCI_E_UNEXPECTED;
  step_while([&] { hr = canControlDetectBitrate(alpha.control, 100, 3, btr0, btr1, &found); });
  EXPECT_EQ(hr, VCI_OK);
  EXPECT_EQ(found, 1);
  // With what it found, the third adapter receives the traffic.
  ASSERT_EQ(canControlInitialize(alpha.control, kMode, btr0[found], btr1[found]), VCI_OK);
  HANDLE ch = nullptr;
  ASSERT_NO_FATAL_FAILURE(open_channel(alpha.device, 64, 0, &ch));
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  step_ns(5'000'000);
  std::size_t frames = 0;
  CANMSG got;
  while (canChannelPeekMessage(ch, &got) == VCI_OK) {
    frames += got.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA && got.dwMsgId == 0x2A0 ? 1 : 0;
  }
  EXPECT_GE(frames, 4u);
  // On a bus nobody talks on, it gives up after each entry's wait.
  ASSERT_EQ(canSchedulerActivate(list, FALSE), VCI_OK);
  ASSERT_EQ(canControlReset(alpha.control), VCI_OK);
  step_ns(5'000'000);
  step_while([&] { hr = canControlDetectBitrate(alpha.control, 10, 2, btr0, btr1, &found); });
  EXPECT_EQ(hr, VCI_E_TIMEOUT);
  EXPECT_EQ(found, -1);
  canChannelClose(ch);
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

}  // namespace
}  // namespace canemu
