// The cyclic list of the VCI C++ API (ICanScheduler, ICanScheduler2) against a real canemud in
// stepped time: messages on their cycles, the timer overflow, and the entries it refuses.
#include <gtest/gtest.h>

#include <vector>

#include "vci_cpp_test_support.hpp"
#include "vcisdk.h"

namespace canemu::testing {
namespace {

TEST(VciCppApi, TheCyclicListThroughICanScheduler2AndTheTimerOverflow) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  Ref<ICanScheduler2> list;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler2, list.pv()), VCI_OK);
  CANCYCLICTXMSG2 m = cyclic_data<CANCYCLICTXMSG2>(0x55, 3, 1);
  m.bIncrMode = CAN_CTXMSG_INC_8;
  m.bByteIndex = 0;
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

TEST(VciCppApi, TheCyclicListRefusesBadEntriesAndASeventeenth) {
  VciDaemon d;
  Adapter alpha("alpha");
  Ref<ICanScheduler> list;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler, list.pv()), VCI_OK);
  CANCYCLICTXMSG m = cyclic_data(0x100, 16, 1);  // 16 entries of cycle 16 fill every tick
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
  m.wCycleTime = 16;
  ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
  EXPECT_EQ(index, 3u);  // the free slot
  EXPECT_EQ(list->StartMessage(16, 1), VCI_E_INVALID_INDEX);
  CANSCHEDULERSTATUS s{};
  ASSERT_EQ(list->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);  // off after opening
}

// Checklist 132: ICanScheduler and ICanScheduler2 are two views of the controller's one list.
// Entries added and started through one are there, with their state, through the other, and
// the admission rule (the shares 1/wCycleTime add up to at most 1) counts them all, refused
// with VCI_E_OUTOFMEMORY and index 0xFFFFFFFF through either.
TEST(VciCppApi, ICanSchedulerAndICanScheduler2ShareOneList) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  {
    Ref<ICanScheduler> v1;
    ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler, v1.pv()), VCI_OK);
    CANCYCLICTXMSG m = cyclic_data(0x100, 2, 1);
    UINT32 index = 99;
    ASSERT_EQ(v1->AddMessage(&m, &index), VCI_OK);
    EXPECT_EQ(index, 0u);
    ASSERT_EQ(v1->StartMessage(index, 0), VCI_OK);
  }
  {
    Ref<ICanScheduler2> v2;
    ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler2, v2.pv()), VCI_OK);
    CANSCHEDULERSTATUS2 s{};
    ASSERT_EQ(v2->GetStatus(&s), VCI_OK);
    EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_BUSY);  // v1's entry, started
    EXPECT_EQ(s.abMsgStat[1], CAN_CTXMSG_STAT_EMPTY);
    CANCYCLICTXMSG2 m = cyclic_data<CANCYCLICTXMSG2>(0x200, 2, 1);
    UINT32 index = 99;
    ASSERT_EQ(v2->AddMessage(&m, &index), VCI_OK);  // 1/2 + 1/2: every tick taken
    EXPECT_EQ(index, 1u);
    m.wCycleTime = 65535;
    UINT32 refused = 0;
    EXPECT_EQ(v2->AddMessage(&m, &refused), VCI_E_OUTOFMEMORY);
    EXPECT_EQ(refused, 0xFFFFFFFFu);
    ASSERT_EQ(v2->StartMessage(index, 0), VCI_OK);
    drain(beta.reader.p, false);
    ASSERT_EQ(v2->Resume(), VCI_OK);  // at t = 0: both entries together
    step_ns(6'500'000);
    std::vector<UINT32> ids;
    for (const CANMSG& f : drain(beta.reader.p, true)) {
      ids.push_back(f.dwMsgId);
    }
    // Both due at tick 2: the older (v1's) first, the other in the next tick, and so on.
    EXPECT_EQ(ids, (std::vector<UINT32>{0x100, 0x200, 0x100, 0x200, 0x100}));
  }
  Ref<ICanScheduler> v1;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanScheduler, v1.pv()), VCI_OK);
  CANSCHEDULERSTATUS s{};
  ASSERT_EQ(v1->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);  // opening the list stops the task
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_BUSY);
  EXPECT_EQ(s.abMsgStat[1], CAN_CTXMSG_STAT_BUSY);  // v2's entry
  CANCYCLICTXMSG m = cyclic_data(0x300, 65535);
  UINT32 refused = 0;
  EXPECT_EQ(v1->AddMessage(&m, &refused), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(refused, 0xFFFFFFFFu);
  ASSERT_EQ(v1->RemMessage(1), VCI_OK);  // v2's entry goes through v1
  UINT32 index = 99;
  ASSERT_EQ(v1->AddMessage(&m, &index), VCI_OK);
  EXPECT_EQ(index, 1u);
}

}  // namespace
}  // namespace canemu::testing
