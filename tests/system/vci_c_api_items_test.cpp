// Checklist items of the VCI digest (§7) through the classic VCI C API (libvcinpl) against a
// running canemud in stepped time, with exact time stamps (device ticks of 1 us from canemud's
// start); and the functions of vcinpl.h that no other test calls: vciInitialize,
// vciFindDeviceByClass, canControlGetCaps, the Wait/Mult and legacy *MultipleMessages calls,
// canSchedulerStopMessage and canSchedulerReset.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "vci_c_lin_support.hpp"
#include "vci_c_test_support.hpp"
#include "vcinpl.h"

namespace canemu::testing {
namespace {

// Three adapters on can0: a third one acknowledges while the one under test does not.
const char* const kThreeAdapters =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n";

// The end of a classic frame started at `start_us`, in ticks of 1 us at 500 kbit/s.
UINT32 end_of(uint32_t start_us, uint32_t id, std::vector<uint8_t> bytes, bool ext = false) {
  return static_cast<UINT32>(start_us + bits_of(id, std::move(bytes), ext) * kBitUs2);
}

std::vector<UINT32> times_of(const std::vector<CANMSG>& msgs) {
  std::vector<UINT32> t;
  for (const CANMSG& m : msgs) {
    t.push_back(m.dwTime);
  }
  return t;
}

// ---------------------------------------------------------------- functions

TEST(VciCFunctions, VciInitializeSucceedsWithAndWithoutCanemud) {
  EXPECT_EQ(vciInitialize(), VCI_OK);  // nothing to reach yet
  VciDaemon d;
  EXPECT_EQ(vciInitialize(), VCI_OK);
  EXPECT_EQ(vciInitialize(), VCI_OK);  // idempotent
  EXPECT_EQ(id_of("beta").AsInt64, 2);
}

TEST(VciCFunctions, FindDeviceByClassCountsTheInstancesOfAClass) {
  VciDaemon d;
  HANDLE e = nullptr;
  ASSERT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
  VCIDEVICEINFO alpha{};
  ASSERT_EQ(vciEnumDeviceNext(e, &alpha), VCI_OK);
  vciEnumDeviceClose(e);
  VCIID id{};
  ASSERT_EQ(vciFindDeviceByClass(alpha.DeviceClass, 0, &id), VCI_OK);
  EXPECT_EQ(id.AsInt64, 1);  // alpha
  ASSERT_EQ(vciFindDeviceByClass(alpha.DeviceClass, 1, &id), VCI_OK);
  EXPECT_EQ(id.AsInt64, 2);  // beta, the same model
  id.AsInt64 = 77;
  EXPECT_EQ(vciFindDeviceByClass(alpha.DeviceClass, 2, &id), VCI_E_NO_MORE_ITEMS);
  EXPECT_EQ(id.AsInt64, 77);
  const GUID other = {0x12345678, 0x9ABC, 0xDEF0, {1, 2, 3, 4, 5, 6, 7, 8}};
  EXPECT_EQ(vciFindDeviceByClass(other, 0, &id), VCI_E_NO_MORE_ITEMS);
  EXPECT_EQ(vciFindDeviceByClass(alpha.DeviceClass, 0, nullptr), VCI_E_INVALIDARG);
}

// The receive event follows its threshold (2 messages here), signalled by canemud's writes; the
// transmit event means room, at least its threshold free (2 here): a new FIFO has it at once, a
// FIFO filled beyond it waits until the line takes frames.
TEST(VciCFunctions, WaitRxEventAndWaitTxEventFollowTheThresholds) {
  VciDaemon d;
  Adapter beta("beta");
  Parts alpha("alpha", 16, 4, 2, 2);
  ASSERT_NO_FATAL_FAILURE(alpha.activate_and_init_line());
  EXPECT_EQ(canChannelWaitRxEvent(alpha.control, 0), VCI_E_INVHANDLE);
  EXPECT_EQ(canChannelWaitTxEvent(alpha.control, 0), VCI_E_INVHANDLE);
  EXPECT_EQ(canChannelWaitRxEvent(alpha.channel, 0), VCI_E_TIMEOUT);
  EXPECT_EQ(canChannelWaitTxEvent(alpha.channel, 0), VCI_OK);       // an empty FIFO has room
  EXPECT_EQ(canChannelWaitTxEvent(alpha.channel, 60'000), VCI_OK);  // at once, not in a minute
  SimClock clock;
  // Offline: the posted frames stay in the FIFO, which still has room.
  std::vector<CANMSG> three(3, data(0x201, {1}));
  UINT32 done = 0;
  ASSERT_EQ(canChannelPostMsgMult(alpha.channel, three.data(), 3, &done), VCI_OK);
  EXPECT_EQ(done, 3u);
  EXPECT_EQ(canChannelWaitTxEvent(alpha.channel, 0), VCI_OK);
  clock.to(1'000'000);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);  // the INFO START: 1 of 2
  clock.to(2'000'000);
  EXPECT_EQ(beta.frames().size(), 3u);
  EXPECT_EQ(canChannelWaitRxEvent(alpha.channel, 0), VCI_E_TIMEOUT);
  beta.post(data(0x123, {0x11, 0x22}));
  clock.to(3'000'000);
  EXPECT_EQ(canChannelWaitRxEvent(alpha.channel, 0), VCI_OK);         // START and the frame
  EXPECT_EQ(canChannelWaitRxEvent(alpha.channel, 0), VCI_E_TIMEOUT);  // taken by the wait
  const auto got = alpha.drain();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 1000u);
  EXPECT_EQ(got[1].dwTime, end_of(2000, 0x123, {0x11, 0x22}));
}

// A full transmit FIFO has no room: canChannelWaitTxEvent waits until the line has taken as many
// frames as the threshold asks to be free (simulated time), in another thread.
TEST(VciCFunctions, WaitTxEventWaitsForRoomInAFullFifo) {
  VciDaemon d;
  Adapter beta("beta");
  Parts alpha("alpha", 16, 4, 1, 2);
  ASSERT_NO_FATAL_FAILURE(alpha.activate_and_init_line());
  CANMSG one = data(0x201, {1});
  std::size_t posted = 0;
  while (canChannelPostMessage(alpha.channel, &one) == VCI_OK) {  // capacity: at least 4
    ++posted;
  }
  ASSERT_GE(posted, 4u);
  EXPECT_EQ(canChannelWaitTxEvent(alpha.channel, 0), VCI_E_TIMEOUT);
  SimClock clock;
  std::atomic<bool> woke{false};
  std::atomic<HRESULT> tx{VCI_E_UNEXPECTED};
  std::thread waiter([&] {
    tx = canChannelWaitTxEvent(alpha.channel, 60'000);
    woke = true;
  });
  clock.to(1'000'000);
  EXPECT_FALSE(woke);  // offline: nothing leaves
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  clock.to(2'000'000);
  waiter.join();
  EXPECT_EQ(tx.load(), VCI_OK);
  EXPECT_GE(beta.frames().size(), 2u);
}

// The several-message calls: the *MsgMult forms take the count after the array, the legacy
// *MultipleMessages forms before it, in and out.
TEST(VciCFunctions, TheMultiMessageCallsMoveSeveralMessagesAtOnce) {
  VciDaemon d;
  Adapter alpha("alpha", false);
  Adapter beta("beta");
  SimClock clock;
  std::vector<CANMSG> out{data(0x101, {1}), data(0x102, {2}), data(0x103, {3})};
  UINT32 done = 99;
  // The transmit FIFO holds 64; the line is stopped, so they wait there.
  ASSERT_EQ(canChannelPostMsgMult(alpha.channel, out.data(), 3, &done), VCI_OK);
  EXPECT_EQ(done, 3u);
  UINT32 count = 2;
  ASSERT_EQ(canChannelPostMultipleMessages(alpha.channel, &count, out.data()), VCI_OK);
  EXPECT_EQ(count, 2u);
  count = 1;
  ASSERT_EQ(canChannelSendMultipleMessages(alpha.channel, 100, &count, &out[2]), VCI_OK);
  EXPECT_EQ(count, 1u);
  EXPECT_EQ(canChannelPostMsgMult(alpha.channel, nullptr, 1, &done), VCI_E_INVALIDARG);
  EXPECT_EQ(canChannelPostMsgMult(alpha.channel, out.data(), 1, nullptr), VCI_E_INVALIDARG);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  clock.to(5'000'000);
  // Six frames back to back from t = 0, each after the 3-bit intermission.
  const std::vector<uint32_t> order{0x101, 0x102, 0x103, 0x101, 0x102, 0x103};
  std::vector<UINT32> ends;
  uint32_t start = 0;
  for (uint32_t id : order) {
    const UINT32 e = end_of(start, id, {static_cast<uint8_t>(id & 0xF)});
    ends.push_back(e);
    start = e + 3 * kBitUs2;
  }
  // beta: INFO START, then the six; read them in pieces.
  CANMSG in[8] = {};
  ASSERT_EQ(canChannelPeekMsgMult(beta.channel, in, 1, &done), VCI_OK);
  EXPECT_EQ(done, 1u);
  EXPECT_EQ(in[0].uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
  ASSERT_EQ(canChannelReadMsgMult(beta.channel, 100, in, 2, &done), VCI_OK);
  ASSERT_EQ(done, 2u);
  count = 2;
  ASSERT_EQ(canChannelPeekMultipleMessages(beta.channel, &count, in + 2), VCI_OK);
  ASSERT_EQ(count, 2u);
  count = 8;
  ASSERT_EQ(canChannelReadMultipleMessages(beta.channel, 100, &count, in + 4), VCI_OK);
  ASSERT_EQ(count, 2u);  // what was there
  std::vector<CANMSG> got(in, in + 6);
  EXPECT_EQ(ids_of(got), order);
  EXPECT_EQ(times_of(got), ends);
  // Nothing left.
  EXPECT_EQ(canChannelPeekMsgMult(beta.channel, in, 8, &done), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(done, 0u);
  count = 8;
  EXPECT_EQ(canChannelPeekMultipleMessages(beta.channel, &count, in), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(count, 0u);
  // A read with a timeout on an empty FIFO ends after its time, in simulated time.
  HRESULT read = VCI_E_UNEXPECTED;
  UINT32 read_count = 99;
  testing::step_while([&] {
    read_count = 8;
    CANMSG buf[8];
    read = canChannelReadMultipleMessages(beta.channel, 3, &read_count, buf);
  });
  EXPECT_EQ(read, VCI_E_TIMEOUT);
  EXPECT_EQ(read_count, 0u);
  UINT32 n = 8;
  EXPECT_EQ(canChannelReadMsgMult(beta.channel, 0, in, 8, &n), VCI_E_RXQUEUE_EMPTY);
}

// FIFO capacities are rounded up to whole 4 KiB pages after a 256-byte header (docs/vci.md):
// a transmit FIFO of 2 CANMSGs holds (4096 - 256) / 20 = 192.
constexpr UINT32 kPageOfCanmsg = (4096 - 256) / sizeof(CANMSG);

// A transmit FIFO with room for part of the messages takes that part.
TEST(VciCFunctions, PostMsgMultQueuesWhatFitsAndReportsAFullFifoOnlyWhenNothingFits) {
  VciDaemon d;
  Parts alpha("alpha");  // not started: nothing leaves the FIFO
  ASSERT_EQ(canChannelInitialize(alpha.channel, 16, 1, 2, 1), VCI_OK);
  std::vector<CANMSG> many(kPageOfCanmsg, data(0x100, {}));
  UINT32 done = 0;
  ASSERT_EQ(canChannelPostMsgMult(alpha.channel, many.data(), kPageOfCanmsg - 2, &done), VCI_OK);
  EXPECT_EQ(done, kPageOfCanmsg - 2);
  EXPECT_EQ(canChannelPostMsgMult(alpha.channel, many.data(), 3, &done), VCI_OK);
  EXPECT_EQ(done, 2u);
  EXPECT_EQ(canChannelPostMsgMult(alpha.channel, many.data(), 3, &done), VCI_E_TXQUEUE_FULL);
  EXPECT_EQ(done, 0u);
  UINT32 count = 3;
  EXPECT_EQ(canChannelPostMultipleMessages(alpha.channel, &count, many.data()), VCI_E_TXQUEUE_FULL);
  EXPECT_EQ(count, 0u);
  EXPECT_EQ(alpha.status().bTxFifoLoad, 100);
}

TEST(VciCFunctions, StopMessageKeepsTheEntryAndResetEmptiesTheList) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  SimClock clock;
  const CyclicList list(alpha.device);
  CANCYCLICTXMSG m = cyclic_data(0x100, 2);
  UINT32 index = 99;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  ASSERT_EQ(index, 0u);
  ASSERT_EQ(canSchedulerStartMessage(list, 0, 0), VCI_OK);
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  clock.to(5'000'000);  // sent at 2 and 4 ms
  ASSERT_EQ(canSchedulerStopMessage(list, 0), VCI_OK);
  EXPECT_EQ(canSchedulerStopMessage(list, 5), VCI_E_INVALID_INDEX);  // empty entry
  CANSCHEDULERSTATUS s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_DONE);  // kept, stopped
  clock.to(10'000'000);
  ASSERT_EQ(canSchedulerStartMessage(list, 0, 1), VCI_OK);  // at 10 ms: once, at 12 ms
  clock.to(15'000'000);
  ASSERT_EQ(canSchedulerStartMessage(list, 0, 0), VCI_OK);  // at 15 ms: 17, 19, ...
  clock.to(18'000'000);
  list.expect_reset_empties_it();
  EXPECT_EQ(canSchedulerReset(alpha.channel), VCI_E_INVHANDLE);
  clock.to(30'000'000);
  const auto got = beta.frames();
  std::vector<UINT32> want;
  for (uint32_t ms : {2, 4, 12, 17}) {
    want.push_back(end_of(ms * 1000, 0x100, {}));
  }
  EXPECT_EQ(times_of(got), want);
}

// The LIN monitor's reads that no other test of libvcinpl calls: a master's header answered by
// a slave, read as one message, several at once, and waited for.
TEST(VciCFunctions, LinMonitorReadsOneOrSeveralMessagesAndSignalsItsEvent) {
  using namespace testing;
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta");
  ASSERT_EQ(slave.write(false, lin_data(0x2A, {0xDE, 0xAD}, true)), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x2A, {}, true, true)), VCI_OK);
  step_to(10'000'000);
  EXPECT_EQ(linMonitorWaitRxEvent(master.monitor, 0), VCI_OK);  // the writes signalled it
  EXPECT_EQ(linMonitorWaitRxEvent(master.monitor, 0), VCI_E_TIMEOUT);
  LINMSG one{};
  ASSERT_EQ(linMonitorReadMessage(master.monitor, 100, &one), VCI_OK);
  EXPECT_EQ(text_of(one), event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_START));
  ASSERT_EQ(linMonitorReadMessage(master.monitor, 100, &one), VCI_OK);
  EXPECT_EQ(text_of(one), frame_text(stamp(frame_end(t0, 2)), 0x2A, {0xDE, 0xAD}, true, false));
  EXPECT_EQ(linMonitorReadMessage(master.monitor, 0, &one), VCI_E_TIMEOUT);
  LINMSG got[4] = {};
  UINT32 done = 0;
  ASSERT_EQ(linMonitorPeekMsgMult(slave.monitor, got, 1, &done), VCI_OK);
  ASSERT_EQ(done, 1u);
  EXPECT_EQ(text_of(got[0]), event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_START));
  ASSERT_EQ(linMonitorReadMsgMult(slave.monitor, 100, got, 4, &done), VCI_OK);
  ASSERT_EQ(done, 1u);
  EXPECT_EQ(text_of(got[0]), frame_text(stamp(frame_end(t0, 2)), 0x2A, {0xDE, 0xAD}, true, true));
  EXPECT_EQ(linMonitorPeekMsgMult(slave.monitor, got, 4, &done), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(done, 0u);
}

// ---------------------------------------------------------------- checklist items

TEST(VciCItems, Item56_NewChannelIsInactiveUntilActivate) {
  VciDaemon d;
  Adapter beta("beta");
  Parts alpha("alpha");
  ASSERT_EQ(canControlInitialize(alpha.control, kMode, CAN_BT0_500KB, CAN_BT1_500KB), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  SimClock clock;
  beta.post(data(0x123, {0x11, 0x22}));
  clock.to(1'000'000);
  CANCHANSTATUS s = alpha.status();
  EXPECT_FALSE(s.fActivated);
  EXPECT_EQ(s.sLineStatus.dwStatus, 0u);  // the line is online
  CANMSG m{};
  EXPECT_EQ(canChannelPeekMessage(alpha.channel, &m), VCI_E_RXQUEUE_EMPTY);
  ASSERT_EQ(canChannelActivate(alpha.channel, TRUE), VCI_OK);
  s = alpha.status();
  EXPECT_TRUE(s.fActivated);
  beta.post(data(0x124, {0x33}));
  clock.to(2'000'000);
  const auto got = alpha.drain();  // no INFO START: the line started before the activation
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x124u);
  EXPECT_EQ(got[0].dwTime, end_of(1000, 0x124, {0x33}));
}

TEST(VciCItems, Item57_ActiveChannelGetsNothingWhileTheLineIsNotOnlineNorAfterDeactivate) {
  VciDaemon d(kThreeAdapters);
  Adapter beta("beta");
  Adapter gamma("gamma");
  Parts alpha("alpha");
  ASSERT_EQ(canChannelActivate(alpha.channel, TRUE), VCI_OK);
  SimClock clock;
  beta.post(data(0x101, {}));  // the controller is not initialized
  clock.to(1'000'000);
  EXPECT_TRUE(alpha.drain().empty());
  ASSERT_EQ(canControlInitialize(alpha.control, kMode, CAN_BT0_500KB, CAN_BT1_500KB), VCI_OK);
  beta.post(data(0x102, {}));  // initialized, offline
  clock.to(2'000'000);
  EXPECT_TRUE(alpha.drain().empty());
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  beta.post(data(0x103, {}));
  clock.to(3'000'000);
  auto got = alpha.drain();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 2000u);
  EXPECT_EQ(got[1].dwMsgId, 0x103u);
  EXPECT_EQ(got[1].dwTime, end_of(2000, 0x103, {}));
  // Deactivated: neither reception nor transmission; the posted frame waits in the FIFO.
  ASSERT_EQ(canChannelActivate(alpha.channel, FALSE), VCI_OK);
  beta.post(data(0x104, {}));
  CANMSG mine = data(0x201, {0x55});
  ASSERT_EQ(canChannelPostMessage(alpha.channel, &mine), VCI_OK);
  clock.to(4'000'000);
  EXPECT_TRUE(alpha.drain().empty());
  CANCHANSTATUS s = alpha.status();
  EXPECT_FALSE(s.fActivated);
  EXPECT_EQ(ids_of(gamma.frames()), (std::vector<uint32_t>{0x101, 0x102, 0x103, 0x104}));
  // Active again: the waiting frame goes at once.
  ASSERT_EQ(canChannelActivate(alpha.channel, TRUE), VCI_OK);
  clock.to(5'000'000);
  got = gamma.frames();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x201u);
  EXPECT_EQ(got[0].dwTime, end_of(4000, 0x201, {0x55}));
}

TEST(VciCItems, Item66_StopLineAndResetLineLeaveTheChannelFifosAlone) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  SimClock clock;
  beta.post(data(0x123, {0x11, 0x22}));
  clock.to(1'000'000);
  ASSERT_EQ(canControlStart(alpha.control, FALSE), VCI_OK);
  alpha.post(data(0x201, {1}));
  alpha.post(data(0x202, {2}));
  clock.to(2'000'000);
  ASSERT_EQ(canControlReset(alpha.control), VCI_OK);
  clock.to(3'000'000);
  CANCHANSTATUS s = alpha.status();
  EXPECT_EQ(s.bTxFifoLoad, 2 * 100 / kPageOfCanmsg);  // 2 of the 64 rounded up to 192
  const auto got = alpha.drain();
  ASSERT_EQ(got.size(), 4u);  // START, the frame, STOP, RESET
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[1].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].dwTime, 124u);
  EXPECT_EQ(got[2].uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
  EXPECT_EQ(got[2].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(got[2].dwTime, 0u);
  EXPECT_EQ(got[3].abData[0], CAN_INFO_RESET);
  EXPECT_EQ(got[3].dwTime, 0u);
  EXPECT_TRUE(beta.frames().empty());
  // Running again, the queued frames go out in order.
  ASSERT_EQ(canControlInitialize(alpha.control, kMode, CAN_BT0_500KB, CAN_BT1_500KB), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  clock.to(4'000'000);
  const auto sent = beta.frames();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(ids_of(sent), (std::vector<uint32_t>{0x201, 0x202}));
  const UINT32 first = end_of(3000, 0x201, {1});
  EXPECT_EQ(times_of(sent), (std::vector<UINT32>{first, end_of(first + 6, 0x202, {2})}));
}

TEST(VciCItems, Item67_InitLineWhileOnlineLeavesTheControllerOffline) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  SimClock clock;
  clock.to(1'000'000);
  ASSERT_EQ(canControlInitialize(alpha.control, CAN_OPMODE_STANDARD, CAN_BT0_500KB, CAN_BT1_500KB),
            VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(s.bOpMode, CAN_OPMODE_STANDARD);
  UINT8 line = 0xFF;
  ASSERT_EQ(canemuGetControllerState(alpha.control, nullptr, nullptr, nullptr, &line), VCI_OK);
  EXPECT_EQ(line, CANEMU_LINE_OFFLINE);
  // Offline it neither receives nor acknowledges: beta, alone, sees an ACK error.
  beta.post(data(0x123, {0x11, 0x22}));
  clock.to(2'000'000);
  const auto got = alpha.drain();
  ASSERT_EQ(got.size(), 1u);  // the INFO START from before: InitLine sends no INFO
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  const std::vector<CANMSG> errors = of_type(beta.drain(), CAN_MSGTYPE_ERROR);
  ASSERT_FALSE(errors.empty());
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_ACK);
  EXPECT_EQ(errors[0].dwTime, 1000u + 54 * kBitUs2);  // the ACK slot of bit 53, at its end
  // Started again, it receives beta's retried frame.
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  clock.to(3'000'000);
  const auto frames = alpha.frames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].dwMsgId, 0x123u);
}

TEST(VciCItems, Item68_ClosingTheControlUnitLeavesTheLineRunning) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  SimClock clock;
  ASSERT_EQ(canControlClose(alpha.control), VCI_OK);
  alpha.control = nullptr;
  CANCHANSTATUS s = alpha.status();
  EXPECT_EQ(s.sLineStatus.dwStatus, 0u);
  EXPECT_EQ(s.sLineStatus.bOpMode, kMode);
  beta.post(data(0x123, {0x11, 0x22}));
  alpha.post(data(0x321, {}));
  clock.to(1'000'000);
  const auto got = alpha.frames();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x123u);
  EXPECT_EQ(got[0].dwTime, 124u);
  const auto at_beta = beta.frames();
  ASSERT_EQ(at_beta.size(), 1u);
  EXPECT_EQ(at_beta[0].dwMsgId, 0x321u);
  // Opened again, the control unit finds the line as it was.
  HANDLE control = nullptr;
  ASSERT_EQ(canControlOpen(alpha.device, 0, &control), VCI_OK);
  CANLINESTATUS line{};
  ASSERT_EQ(canControlGetStatus(control, &line), VCI_OK);
  EXPECT_EQ(line.dwStatus, 0u);
  EXPECT_EQ(line.bBtReg0, CAN_BT0_500KB);
  EXPECT_EQ(line.bBtReg1, CAN_BT1_500KB);
  canControlClose(control);
}

TEST(VciCItems, Item69_InactiveChannelsGetNoInfoMessages) {
  VciDaemon d;
  Parts alpha("alpha");
  HANDLE idle = nullptr;
  ASSERT_EQ(canChannelOpen(alpha.device, 0, FALSE, &idle), VCI_OK);
  ASSERT_EQ(canChannelInitialize(idle, 16, 1, 0, 0), VCI_OK);
  ASSERT_EQ(canChannelActivate(alpha.channel, TRUE), VCI_OK);
  SimClock clock;
  clock.to(1'000'000);
  ASSERT_EQ(canControlInitialize(alpha.control, kMode, CAN_BT0_500KB, CAN_BT1_500KB), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  clock.to(2'000'000);
  ASSERT_EQ(canControlStart(alpha.control, FALSE), VCI_OK);
  ASSERT_EQ(canControlReset(alpha.control), VCI_OK);
  clock.to(3'000'000);
  ASSERT_EQ(canChannelActivate(idle, TRUE), VCI_OK);
  CANMSG m{};
  EXPECT_EQ(canChannelPeekMessage(idle, &m), VCI_E_RXQUEUE_EMPTY);
  const auto got = alpha.drain();
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 1000u);
  EXPECT_EQ(got[1].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(got[2].abData[0], CAN_INFO_RESET);
  canChannelClose(idle);
}

TEST(VciCItems, Item71_TwoChannelsTransmitInTurns) {
  VciDaemon d;
  Adapter alpha("alpha", false);
  Adapter beta("beta");
  const ExtraChannel second(alpha.device, 16, 16);
  for (uint32_t id : {0x101, 0x102, 0x103, 0x104}) {
    alpha.post(data(id, {}));
  }
  for (uint32_t id : {0x201, 0x202}) {
    CANMSG m = data(id, {});
    ASSERT_EQ(canChannelPostMessage(second, &m), VCI_OK);
  }
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  SimClock clock;
  clock.to(5'000'000);
  const std::vector<uint32_t> order{0x101, 0x201, 0x102, 0x202, 0x103, 0x104};
  const auto got = beta.frames();
  EXPECT_EQ(ids_of(got), order);
  std::vector<UINT32> ends;
  uint32_t start = 0;
  for (uint32_t id : order) {
    ends.push_back(end_of(start, id, {}));
    start = ends.back() + 3 * kBitUs2;
  }
  EXPECT_EQ(times_of(got), ends);
}

TEST(VciCItems, Item72_ATransmitMessageThatIsNotDataNeverReachesTheBus) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  CANMSG info = data(0x100, {1});
  info.uMsgInfo.Bytes.bType = CAN_MSGTYPE_INFO;
  CANMSG error = data(0x101, {2});
  error.uMsgInfo.Bytes.bType = CAN_MSGTYPE_ERROR;
  CANMSG status = data(0x102, {3});
  status.uMsgInfo.Bytes.bType = CAN_MSGTYPE_STATUS;
  alpha.post(info);
  alpha.post(error);
  alpha.post(status);
  alpha.post(data(0x123, {0x11, 0x22}));
  SimClock clock;
  clock.to(10'000'000);
  const auto got = beta.drain();
  ASSERT_EQ(got.size(), 2u);  // INFO START, the data frame, sent at once as the first
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[1].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].dwTime, 124u);
  EXPECT_EQ(alpha.status().bTxFifoLoad, 0);
}

// One tick is 1 / (dwClockFreq / dwTscDivisor) s; v1 channel, control unit and cyclic list
// report the same capabilities.
TEST(VciCItems, Item77_TimeStampsCountDwClockFreqOverDwTscDivisorTicksPerSecond) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  CANCAPABILITIES caps{};
  ASSERT_EQ(canControlGetCaps(alpha.control, &caps), VCI_OK);
  EXPECT_EQ(caps.wCtrlType, CAN_CTRL_SJA1000);
  EXPECT_EQ(caps.wBusCoupling, CAN_BUSC_HIGHSPEED);
  EXPECT_EQ(caps.dwClockFreq, 1'000'000u);
  EXPECT_EQ(caps.dwTscDivisor, 1u);
  EXPECT_EQ(caps.dwDtxDivisor, 1u);
  EXPECT_EQ(caps.dwDtxMaxTicks, 65535u);
  EXPECT_EQ(canControlGetCaps(alpha.channel, &caps), VCI_E_INVHANDLE);
  CANCAPABILITIES of_channel{};
  ASSERT_EQ(canChannelGetCaps(alpha.channel, &of_channel), VCI_OK);
  ASSERT_EQ(canControlGetCaps(alpha.control, &caps), VCI_OK);
  EXPECT_EQ(std::memcmp(&caps, &of_channel, sizeof caps), 0);
  const uint64_t per_second = caps.dwClockFreq / caps.dwTscDivisor;
  SimClock clock;
  std::vector<uint64_t> sent_ns{0, 1'000'000'000, 2'500'000'000, 3'000'000'000};
  for (uint64_t t : sent_ns) {
    if (t > 0) {
      clock.to(t);
    }
    beta.post(data(0x123, {0x11, 0x22}));
  }
  clock.to(3'001'000'000);
  const auto got = alpha.frames();
  ASSERT_EQ(got.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(got[k].dwTime, sent_ns[k] * per_second / 1'000'000'000 + 124) << k;
  }
  EXPECT_EQ(got[1].dwTime - got[0].dwTime, per_second);
}

// Both start at t = 0; identifier 0 wins. alpha's single-shot srr frame is dropped, not
// echoed; its next srr frame, sent, comes back with srr set at its end of frame.
TEST(VciCItems, Item92_AnSrrEchoOnlyFollowsASuccessfulTransmission) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  alpha.drain();
  beta.drain();
  CANMSG lost = data(0x123, {0x11, 0x22});
  lost.uMsgInfo.Bits.srr = 1;
  lost.uMsgInfo.Bits.ssm = 1;
  alpha.post(lost);
  beta.post(data(0x000, {}));
  SimClock clock;
  clock.to(1'000'000);
  auto got = alpha.frames();
  ASSERT_EQ(got.size(), 1u);  // beta's frame, no echo
  EXPECT_EQ(got[0].dwMsgId, 0u);
  EXPECT_EQ(got[0].dwTime, end_of(0, 0, {}));
  EXPECT_TRUE(beta.frames().empty());
  CANMSG sent = data(0x124, {0x33});
  sent.uMsgInfo.Bits.srr = 1;
  alpha.post(sent);
  clock.to(2'000'000);
  got = alpha.frames();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x124u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(got[0].dwTime, end_of(1000, 0x124, {0x33}));
  const auto at_beta = beta.frames();
  ASSERT_EQ(at_beta.size(), 1u);
  EXPECT_EQ(at_beta[0].dwTime, got[0].dwTime);
}

TEST(VciCItems, Item105_AFrameTheControlUnitFilterBlocksReachesNoChannel) {
  VciDaemon d;
  Adapter beta("beta");
  Parts alpha("alpha");
  const ExtraChannel second(alpha.device, 16, 0);
  ASSERT_NO_FATAL_FAILURE(alpha.activate_and_init_line());
  ASSERT_NO_FATAL_FAILURE(pass_only_0x123_and_start(alpha.control));
  beta.post(data(0x122, {}));
  beta.post(data(0x123, {}));
  SimClock clock;
  clock.to(1'000'000);
  const UINT32 second_end = end_of(end_of(0, 0x122, {}) + 6, 0x123, {});
  for (HANDLE ch : {alpha.channel, static_cast<HANDLE>(second)}) {
    const auto got = testing::drain(ch, true);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].dwMsgId, 0x123u);
    EXPECT_EQ(got[0].dwTime, second_end);
    EXPECT_EQ(got[0].uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_2);
  }
  // The line still acknowledged the blocked frame: beta saw no error.
  for (const CANMSG& m : beta.drain()) {
    EXPECT_NE(m.uMsgInfo.Bytes.bType, CAN_MSGTYPE_ERROR);
  }
}

TEST(VciCItems, Item112_ASingleShotFrameIsNotRetried) {
  VciDaemon d;
  Adapter alpha("alpha");
  Parts beta("beta");  // not started: nobody acknowledges
  CANMSG once = data(0x123, {0x11, 0x22});
  once.uMsgInfo.Bits.ssm = 1;
  alpha.drain();
  alpha.post(once);
  SimClock clock;
  clock.to(1'000'000);
  const std::vector<CANMSG> errors = of_type(alpha.drain(), CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 1u);  // one attempt
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_ACK);
  EXPECT_EQ(errors[0].dwTime, 54u * kBitUs2);
  UINT16 tec = 0;
  ASSERT_EQ(canemuGetControllerState(alpha.control, nullptr, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(tec, 8);
  // A receiver started later gets nothing: the frame was given up.
  ASSERT_EQ(canChannelActivate(beta.channel, TRUE), VCI_OK);
  ASSERT_EQ(canControlInitialize(beta.control, kMode, CAN_BT0_500KB, CAN_BT1_500KB), VCI_OK);
  ASSERT_EQ(canControlStart(beta.control, TRUE), VCI_OK);
  clock.to(20'000'000);
  const auto at_beta = beta.drain();
  ASSERT_EQ(at_beta.size(), 1u);
  EXPECT_EQ(at_beta[0].abData[0], CAN_INFO_START);
  // Losing arbitration: identifier 0 wins at t = 20 ms, the single-shot 0x123 is not sent later.
  CANMSG zero = data(0x000, {});
  ASSERT_EQ(canChannelPostMessage(beta.channel, &zero), VCI_OK);
  alpha.post(once);
  clock.to(40'000'000);
  EXPECT_TRUE(beta.drain().empty());
  const auto got = alpha.frames();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0u);
  EXPECT_EQ(got[0].dwTime, end_of(20'000, 0, {}));
}

// SJA1000 at 16 MHz: the BTR pairs of the table, each at its rate (62 bits of 0x123 with two
// bytes, so the frame ends 62 bit times after it started).
TEST(VciCItems, Item114_TheBtrTableGivesItsBitRates) {
  VciDaemon d;
  Adapter alpha("alpha", false);
  Adapter beta("beta", false);
  ASSERT_EQ(bits_of(0x123, {0x11, 0x22}), 62);
  SimClock clock;
  uint64_t t = 0;
  for (const BtrRate& r : kBtrTable) {
    t += 100'000'000;
    clock.to(t);
    for (const Adapter* a : {&alpha, &beta}) {
      ASSERT_EQ(canControlReset(a->control), VCI_OK);
      ASSERT_EQ(canControlInitialize(a->control, kMode, r.btr0, r.btr1), VCI_OK);
      ASSERT_EQ(canControlStart(a->control, TRUE), VCI_OK);
      a->drain();
    }
    CANLINESTATUS s{};
    ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
    EXPECT_EQ(s.bBtReg0, r.btr0);
    EXPECT_EQ(s.bBtReg1, r.btr1);
    alpha.post(data(0x123, {0x11, 0x22}));
    clock.to(t + 50'000'000);
    const auto got = beta.frames();
    ASSERT_EQ(got.size(), 1u) << r.bps;
    EXPECT_EQ(got[0].dwTime, (t + 62 * uint64_t{1'000'000'000} / r.bps) / 1000) << r.bps;
  }
}

// Cycle 4 for both: the older entry goes in tick 4 after the resume, the other in tick 5 (one
// frame per tick), then each every 4 ticks of 1 ms.
TEST(VciCItems, Item125_ResumeStartsEveryStartedEntryTogether) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  const CyclicList list(alpha.device);
  CANSCHEDULERSTATUS s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  CANCYCLICTXMSG m{};
  m.wCycleTime = 4;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  UINT32 index = 0;
  for (uint32_t id : {0x100, 0x200}) {
    m.dwMsgId = id;
    ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
    ASSERT_EQ(canSchedulerStartMessage(list, index, 0), VCI_OK);
  }
  SimClock clock;
  clock.to(10'000'000);
  EXPECT_TRUE(beta.frames().empty());
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  clock.to(19'500'000);
  const auto got = beta.frames();
  EXPECT_EQ(ids_of(got), (std::vector<uint32_t>{0x100, 0x200, 0x100, 0x200}));
  EXPECT_EQ(times_of(got),
            (std::vector<UINT32>{end_of(14'000, 0x100, {}), end_of(15'000, 0x200, {}),
                                 end_of(18'000, 0x100, {}), end_of(19'000, 0x200, {})}));
}

TEST(VciCItems, Item127_ACyclicFrameComesEveryCycleExactly) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  const CyclicList list(alpha.device);
  CANCAPABILITIES caps{};
  ASSERT_EQ(canSchedulerGetCaps(list, &caps), VCI_OK);
  const uint32_t tick_us = caps.dwCmsDivisor * 1'000'000 / caps.dwClockFreq;
  ASSERT_EQ(tick_us, 1000u);
  CANCYCLICTXMSG m = cyclic_data(0x555, 5, 8);
  UINT32 index = 0;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  ASSERT_EQ(canSchedulerStartMessage(list, index, 0), VCI_OK);
  SimClock clock;
  clock.to(3'000'000);
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  clock.to(3'000'000 + 50'500'000);
  const auto got = beta.frames();
  std::vector<UINT32> want;
  for (uint32_t k = 1; k <= 10; ++k) {
    want.push_back(end_of(3000 + k * 5 * tick_us, 0x555, std::vector<uint8_t>(8, 0)));
  }
  EXPECT_EQ(times_of(got), want);
}

TEST(VciCItems, Item129_IncrementsOfEightAndSixteenBitsWrap) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  const CyclicList list(alpha.device);
  CANCYCLICTXMSG m{};
  m.wCycleTime = 4;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.bByteIndex = 1;
  m.dwMsgId = 0x300;
  m.bIncrMode = CAN_CTXMSG_INC_8;
  m.uMsgInfo.Bits.dlc = 3;
  const uint8_t d8[] = {0xAA, 0xFE, 0x00};
  std::memcpy(m.abData, d8, sizeof d8);
  UINT32 index = 0;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  ASSERT_EQ(canSchedulerStartMessage(list, index, 3), VCI_OK);
  m.dwMsgId = 0x400;
  m.bIncrMode = CAN_CTXMSG_INC_16;
  m.uMsgInfo.Bits.dlc = 4;
  const uint8_t d16[] = {0xAA, 0xFE, 0xFF, 0x07};
  std::memcpy(m.abData, d16, sizeof d16);
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  ASSERT_EQ(canSchedulerStartMessage(list, index, 3), VCI_OK);
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  SimClock clock;
  clock.to(30'000'000);
  using Bytes = std::vector<std::vector<uint8_t>>;
  Bytes data8;
  Bytes data16;
  for (const CANMSG& f : beta.frames()) {
    std::vector<uint8_t> bytes(f.abData, f.abData + f.uMsgInfo.Bits.dlc);
    (f.dwMsgId == 0x300 ? data8 : data16).push_back(bytes);
  }
  EXPECT_EQ(data8, (Bytes{{0xAA, 0xFE, 0x00}, {0xAA, 0xFF, 0x00}, {0xAA, 0x00, 0x00}}));
  // The little-endian word at byte 1: 0xFFFE, 0xFFFF, 0 (byte 3 untouched).
  EXPECT_EQ(data16,
            (Bytes{{0xAA, 0xFE, 0xFF, 0x07}, {0xAA, 0xFF, 0xFF, 0x07}, {0xAA, 0x00, 0x00, 0x07}}));
  CANSCHEDULERSTATUS s = list.status();
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_DONE);
  EXPECT_EQ(s.abMsgStat[1], CAN_CTXMSG_STAT_DONE);
}

TEST(VciCItems, Item130_SuspendStopsResumeContinuesAndResetEmptiesTheList) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  const CyclicList list(alpha.device);
  CANCYCLICTXMSG m = cyclic_data(0x100, 2);
  list.send_without_end(m);
  SimClock clock;
  clock.to(5'000'000);
  ASSERT_EQ(canSchedulerActivate(list, FALSE), VCI_OK);
  CANSCHEDULERSTATUS s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_BUSY);
  clock.to(11'000'000);
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  clock.to(15'500'000);
  list.expect_reset_empties_it();
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);  // nothing left to send
  clock.to(30'000'000);
  std::vector<UINT32> want;
  for (uint32_t ms : {2, 4, 13, 15}) {
    want.push_back(end_of(ms * 1000, 0x100, {}));
  }
  EXPECT_EQ(times_of(beta.frames()), want);
}

}  // namespace
}  // namespace canemu::testing
