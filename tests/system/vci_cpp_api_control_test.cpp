// The control unit of the VCI C++ API (ICanControl, ICanControl2) against a real canemud in
// stepped time: line states and their info messages, error states and bus-off, bit timing
// and bit-rate detection, listen-only lines and bus load.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "vci_cpp_test_support.hpp"
#include "vcisdk.h"

namespace canemu::testing {
namespace {

TEST(VciCppApi, TheControlUnitsStatesAndInfoMessages) {
  VciDaemon d;
  Adapter beta("beta");  // holds nothing of alpha
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(1, bal));
  Ref<ICanControl> control;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
  Ref<ICanSocket> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
  Ref<ICanChannel> channel;
  ASSERT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
  CANCHANSTATUS cs{};
  ASSERT_EQ(channel->GetStatus(&cs), VCI_OK);  // before Initialize
  EXPECT_FALSE(cs.fActivated);
  Ref<IFifoReader> early;
  EXPECT_EQ(channel->GetReader(early.out()), VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(channel->Initialize(0, 16), VCI_E_INVALIDARG);
  ASSERT_EQ(channel->Initialize(64, 16), VCI_OK);
  Ref<IFifoReader> reader;
  ASSERT_EQ(channel->GetReader(reader.out()), VCI_OK);
  ASSERT_EQ(channel->Activate(), VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(control->StartLine(), VCI_E_INVALID_STATE);
  CANINITLINE init{CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  step_ns(2'000'000);
  ASSERT_EQ(control->StartLine(), VCI_OK);
  CANMSG m = one_byte(0x5, 5);
  ASSERT_EQ(beta.writer->PutDataEntry(&m), VCI_OK);
  step_ns(1'000'000);
  ASSERT_EQ(control->StopLine(), VCI_OK);
  ASSERT_EQ(control->ResetLine(), VCI_OK);
  const auto got = drain(reader.p, false);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 2000u);
  EXPECT_EQ(got[1].dwMsgId, 0x5u);
  EXPECT_EQ(got[1].dwTime, 2000u + end_of(0x5, {5}));
  EXPECT_EQ(got[2].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(got[2].dwTime, 0u);
  EXPECT_EQ(got[3].abData[0], CAN_INFO_RESET);
  ASSERT_EQ(control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
}

TEST(VciCppApi, ALoneAdapterWarnsGoesPassiveAndAFaultTakesItBusOffUntilRestarted) {
  VciDaemon d;
  Adapter alpha("alpha");
  CANMSG m = one_byte(0x10, 1);
  ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  step_ns(10'000'000);
  std::size_t acks = 0;
  std::vector<CANMSG> statuses;
  for (const CANMSG& x : drain(alpha.reader.p, false)) {
    if (x.uMsgInfo.Bytes.bType == CAN_MSGTYPE_ERROR) {
      acks += x.abData[0] == CAN_ERROR_ACK ? 1 : 0;
    } else if (x.uMsgInfo.Bytes.bType == CAN_MSGTYPE_STATUS) {
      statuses.push_back(x);
    }
  }
  EXPECT_GT(acks, 16u);
  ASSERT_EQ(statuses.size(), 1u);
  EXPECT_EQ(statuses[0].abData[0] & CAN_STATUS_ERRLIM, CAN_STATUS_ERRLIM);
  UINT8 state = 0;
  UINT16 tec = 0;
  ASSERT_EQ(canemuGetControllerState(alpha.control.p, &state, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(state, CANEMU_STATE_PASSIVE);
  EXPECT_EQ(tec, 128);
  // A partner comes; 32 injected bit errors take alpha bus-off.
  Adapter beta("beta");
  testing::load_faults(d.daemon,
                       "[[fault]]\nat = \"0s\"\nbus = \"can0\"\nmatch = { from = \"alpha:0\" }\n"
                       "effect = \"bit_error\"\ncount = 40\n");
  step_ns(20'000'000);
  ASSERT_EQ(canemuGetControllerState(alpha.control.p, &state, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(state, CANEMU_STATE_BUSOFF);
  CANLINESTATUS s{};
  ASSERT_EQ(alpha.control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus & CAN_STATUS_BUSOFF, CAN_STATUS_BUSOFF);
  // Restarted (the remaining 8 errors hit the retries), then it sends.
  ASSERT_EQ(alpha.control->StopLine(), VCI_OK);
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);
  step_ns(20'000'000);
  ASSERT_EQ(alpha.control->StopLine(), VCI_OK);
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);
  drain(beta.reader.p, false);
  m = one_byte(0x11, 2);
  ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  step_ns(20'000'000);
  bool seen = false;
  for (const CANMSG& x : drain(beta.reader.p, true)) {
    seen = seen || x.dwMsgId == 0x11;
  }
  EXPECT_TRUE(seen);
}

TEST(VciCppApi, AV2InitializedLineShowsItsTimingAsBtrAndDetectBaudTimesOutOnASilentBus) {
  VciDaemon d;
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(1, bal));
  Ref<ICanControl2> control;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanControl2, control.pv()), VCI_OK);
  CANINITLINE2 init{};
  init.bOpMode = CAN_OPMODE_STANDARD;
  init.bSFMode = CAN_FILTER_PASS;
  init.bEFMode = CAN_FILTER_PASS;
  init.dwSFIds = 2048;
  init.sBtpSdr = CANBTP{0, 500000, 14, 2, 1, 0};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  Ref<ICanSocket> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(socket->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.bBtReg0, CAN_BT0_500KB);
  EXPECT_EQ(s.bBtReg1, CAN_BT1_500KB);
  ASSERT_EQ(control->ResetLine(), VCI_OK);
  CANBTPTABLE table{};
  table.bCount = 2;
  table.asBTP[0].sSdr = CANBTP{0, 500000, 14, 2, 1, 0};
  table.asBTP[1].sSdr = CANBTP{0, 250000, 14, 2, 1, 0};
  std::atomic<bool> done{false};
  HRESULT hr = VCI_OK;
  std::thread detector([&] {
    hr = control->DetectBaud(0, CAN_EXMODE_DISABLED, 10, &table);
    done = true;
  });
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!done && std::chrono::steady_clock::now() < give_up) {
    step_ns(1'000'000);
  }
  detector.join();
  EXPECT_EQ(hr, VCI_E_TIMEOUT);
}

TEST(VciCppApi, TheChannelsControlIsExclusiveAListenOnlyLineNeverSendsAndBusLoadShows) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  // ICanChannel2::GetControl is the control unit, held by alpha's program already.
  V2Channel ch2(alpha.bal.p);
  Ref<ICanControl2> control2;
  EXPECT_EQ(ch2.channel->GetControl(control2.out()), VCI_E_ACCESSDENIED);
  EXPECT_EQ(control2.p, nullptr);
  Ref<IUnknown> bal_unknown;
  EXPECT_EQ(alpha.device->OpenComponent(CLSID_VCIBAL, IID_IUnknown, bal_unknown.pv()), VCI_OK);
  UINT16 entry = 0;
  ASSERT_EQ(alpha.reader->GetEntrySize(&entry), VCI_OK);
  EXPECT_EQ(entry, sizeof(CANMSG));
  // beta sends a frame every millisecond for a second: the load over the last second shows it.
  Ref<ICanScheduler> list;
  ASSERT_EQ(beta.bal->OpenSocket(0, IID_ICanScheduler, list.pv()), VCI_OK);
  CANCYCLICTXMSG c = cyclic_data(0x100, 1, 8);
  UINT32 index = 0;
  ASSERT_EQ(list->AddMessage(&c, &index), VCI_OK);
  ASSERT_EQ(list->StartMessage(index, 0), VCI_OK);
  ASSERT_EQ(list->Resume(), VCI_OK);
  step_ns(1'000'000'000);
  ASSERT_EQ(list->Suspend(), VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(beta.control->GetLineStatus(&s), VCI_OK);
  // One 8-byte frame (about 111..135 bits, 2 us each, plus 3 bits of intermission) a
  // millisecond: between 22 % and 28 % of the bus.
  EXPECT_GE(s.bBusLoad, 22);
  EXPECT_LE(s.bBusLoad, 28);
  // Listen-only: what alpha posts never reaches the bus.
  ASSERT_EQ(alpha.control->ResetLine(), VCI_OK);
  CANINITLINE init{CAN_OPMODE_STANDARD | CAN_OPMODE_LISTONLY, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(alpha.control->InitLine(&init), VCI_OK);
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);
  CANMSG m = one_byte(0x7, 7);
  ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  drain(beta.reader.p, false);
  step_ns(10'000'000);
  EXPECT_TRUE(drain(beta.reader.p, true).empty());
}

}  // namespace
}  // namespace canemu::testing
