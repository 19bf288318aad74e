// Messages through the classic VCI C API (libvcinpl: CANMSG) against a real canemud: what a
// program written for an IXXAT USB-to-CAN sees on its channels, with exact time stamps (device
// ticks of 1 us counted from canemud's start), delayed messages and the cyclic list.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vci_c_test_support.hpp"
#include "vcinpl.h"

namespace canemu::testing {
namespace {

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

TEST(VciCApi, SelfReceptionReachesEveryChannelOfTheController) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  const ExtraChannel second(alpha.device, 64, 0);
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
  const auto at_second = testing::drain(second, true);
  ASSERT_EQ(at_second.size(), 1u);
  EXPECT_EQ(at_second[0].dwMsgId, 0x321u);
  EXPECT_EQ(at_second[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(beta.frames().size(), 2u);
  // A channel without a transmit FIFO cannot send.
  CANMSG x = data(1, {});
  EXPECT_EQ(canChannelPostMessage(second, &x), VCI_E_ACCESSDENIED);
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
  CANCHANSTATUS s = alpha.status();
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
  s = alpha.status();
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
  const ExtraChannel second(alpha.device, 64, 16);
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
}

TEST(VciCApi, TheCyclicListSendsOnItsTicksAndIncrementsTheIdentifier) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  const CyclicList list(alpha.device);
  HANDLE other = nullptr;
  EXPECT_EQ(canSchedulerOpen(beta.device, 0, &other), VCI_OK);  // beta's own list
  HANDLE again = nullptr;
  EXPECT_EQ(canSchedulerOpen(alpha.device, 0, &again), VCI_E_ACCESSDENIED);
  CANCAPABILITIES caps{};
  ASSERT_EQ(canSchedulerGetCaps(list, &caps), VCI_OK);
  EXPECT_EQ(caps.dwClockFreq, 1'000'000u);
  EXPECT_EQ(caps.dwCmsDivisor, 1000u);  // 1 ms ticks
  CANCYCLICTXMSG m = cyclic_data(0x7FE, 2, 1);
  m.bIncrMode = CAN_CTXMSG_INC_ID;
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
  CANSCHEDULERSTATUS s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_DONE);
  EXPECT_EQ(s.abMsgStat[1], CAN_CTXMSG_STAT_EMPTY);
  ASSERT_EQ(canSchedulerRemMessage(list, index), VCI_OK);
  EXPECT_EQ(canSchedulerStartMessage(list, index, 1), VCI_E_INVALID_INDEX);
  canSchedulerClose(other);
}

// In real time a blocked reader wakes when the frame comes, and a writer's doorbell wakes the
// daemon: no steps anywhere.
// One frame per tick: an entry whose share 1/wCycleTime would take the list's total above 1 is
// refused (VCI_E_OUTOFMEMORY, index 0xFFFFFFFF), whether the entries are started or not.
// Cycles 2, 3 and 6 fill every tick: each sends on its own rhythm, one frame per tick.
TEST(VciCApi, TheCyclicListAdmitsEntriesUpToOneFramePerTick) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  const CyclicList list(alpha.device);
  CANCYCLICTXMSG m{};
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  const UINT16 cycles[] = {2, 3, 6};
  for (UINT32 k = 0; k < 3; ++k) {
    m.wCycleTime = cycles[k];
    m.dwMsgId = 0x100 + k;
    UINT32 index = 99;
    ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
    EXPECT_EQ(index, k);
  }
  m.wCycleTime = 65535;
  m.dwMsgId = 0x1FF;
  UINT32 refused = 0;
  EXPECT_EQ(canSchedulerAddMessage(list, &m, &refused), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(refused, 0xFFFFFFFFu);
  CANSCHEDULERSTATUS s = list.status();
  EXPECT_EQ(s.abMsgStat[3], CAN_CTXMSG_STAT_EMPTY);
  // Removing the cycle-6 entry frees its share: one of cycle 7 fits, leaving 1/42: a further
  // one of cycle 41 does not.
  ASSERT_EQ(canSchedulerRemMessage(list, 2), VCI_OK);
  m.wCycleTime = 7;
  UINT32 index = 0;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  EXPECT_EQ(index, 2u);
  m.wCycleTime = 41;
  EXPECT_EQ(canSchedulerAddMessage(list, &m, &refused), VCI_E_OUTOFMEMORY);
  ASSERT_EQ(canSchedulerRemMessage(list, 2), VCI_OK);
  m.wCycleTime = 6;
  m.dwMsgId = 0x102;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  for (UINT32 k = 0; k < 3; ++k) {
    ASSERT_EQ(canSchedulerStartMessage(list, k, 0), VCI_OK);
  }
  beta.drain();
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);  // at t = 0
  step_ns(12'500'000);
  std::vector<uint32_t> ids;
  for (const CANMSG& f : beta.frames()) {
    ids.push_back(f.dwMsgId);
  }
  // a (cycle 2), b (3), c (6). Ticks 2 a, 3 b, 4 a, 6 a (all three due: the oldest entry),
  // 7 b, 8 c (due since 6, before a's 8), 9 a, 10 b (due 9), 11 a (due 10), 12 a.
  EXPECT_EQ(ids, (std::vector<uint32_t>{0x100, 0x101, 0x100, 0x100, 0x101, 0x102, 0x100, 0x101,
                                        0x100, 0x100}));
}

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

}  // namespace
}  // namespace canemu::testing
