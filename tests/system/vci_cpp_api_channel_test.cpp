// The channels of the VCI C++ API (ICanChannel, ICanChannel2) against a real canemud in
// stepped time: FD frames, filters in every mode, shared and exclusive channels.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "vci_cpp_test_support.hpp"
#include "vcisdk.h"

namespace canemu {
namespace {

using testing::Adapter;
using testing::one_byte;
using testing::open_bal;
using testing::Ref;
using testing::step_ns;
using testing::VciDaemon;

TEST(VciCppApi, TheFdChannelSendsAnFdFrameThroughItsWriter) {
  VciDaemon d(
      "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n\n"
      "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n\n"
      "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n");
  const UINT8 ex_mode = CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA;
  testing::V2Adapter alpha("alpha", ex_mode, CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED);
  testing::V2Adapter beta("beta", ex_mode, CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED);
  // The guide's own example: fdr without edl, written in place with AcquireWrite.
  PCANMSG2 p = nullptr;
  ASSERT_EQ(alpha.writer->AcquireWrite(reinterpret_cast<PVOID*>(&p), nullptr), VCI_OK);
  std::memset(p, 0, sizeof *p);
  p->dwMsgId = 0x1234;
  p->uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  p->uMsgInfo.Bits.fdr = 1;
  p->uMsgInfo.Bits.ext = 1;
  p->uMsgInfo.Bits.dlc = 1;
  p->abData[0] = 0x77;
  ASSERT_EQ(alpha.writer->ReleaseWrite(1), VCI_OK);
  step_ns(1'000'000);
  const auto got = testing::drain<CANMSG2>(beta.reader.p, true);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x1234u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(got[0].abData[0], 0x77);
  CANCHANSTATUS2 s{};
  ASSERT_EQ(beta.channel->GetStatus(&s), VCI_OK);
  EXPECT_TRUE(s.fActivated);
  EXPECT_EQ(s.sLineStatus.bExMode, CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
}

TEST(VciCppApi, V2ChannelFiltersInEveryModeForBothWidthsAndRtr) {
  VciDaemon d;
  Adapter beta("beta");
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(1, bal));
  Ref<ICanSocket2> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket2, socket.pv()), VCI_OK);
  struct Ch {
    Ref<ICanChannel2> ch;
    Ref<IFifoReader> reader;
  };
  auto make = [&](Ch& c, UINT8 mode) {
    ASSERT_EQ(socket->CreateChannel(FALSE, c.ch.out()), VCI_OK);
    ASSERT_EQ(c.ch->Initialize(256, 0, 64, mode), VCI_OK);
    ASSERT_EQ(c.ch->GetReader(c.reader.out()), VCI_OK);
  };
  Ch lock, pass, incl, excl;
  make(lock, CAN_FILTER_LOCK);
  make(pass, CAN_FILTER_PASS);
  make(incl, CAN_FILTER_INCL);
  make(excl, CAN_FILTER_EXCL);
  for (Ch* c : {&incl, &excl}) {
    for (UINT8 w : {UINT8{CAN_FILTER_STD}, UINT8{CAN_FILTER_EXT}}) {
      ASSERT_EQ(c->ch->SetAccFilter(w, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE), VCI_OK);
    }
    ASSERT_EQ(c->ch->AddFilterIds(CAN_FILTER_STD, 0x123 << 1, 0xFFF), VCI_OK);  // data 0x123
    ASSERT_EQ(c->ch->AddFilterIds(CAN_FILTER_EXT, (0x1234 << 1) | 1, 0x3FFFFFFF),
              VCI_OK);  // remote 0x1234 (29 bit)
  }
  for (Ch* c : {&lock, &pass, &incl, &excl}) {
    ASSERT_EQ(c->ch->Activate(), VCI_OK);
  }
  EXPECT_EQ(incl.ch->SetAccFilter(CAN_FILTER_STD, 0, 0), VCI_E_INVALID_STATE);
  Ref<ICanControl2> control;
  ASSERT_EQ(incl.ch->GetControl(control.out()), VCI_OK);
  CANINITLINE2 init{};
  init.bOpMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED;
  init.bSFMode = CAN_FILTER_PASS;
  init.bEFMode = CAN_FILTER_PASS;
  init.dwSFIds = 2048;
  init.dwEFIds = 2048;
  init.sBtpSdr = CANBTP{0, 500000, 14, 2, 1, 0};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  ASSERT_EQ(control->StartLine(), VCI_OK);
  CANMSG a = one_byte(0x123, 1);
  CANMSG b = one_byte(0x124, 2);
  CANMSG r = one_byte(0x123, 0);  // remote 0x123: not on the list
  r.uMsgInfo.Bits.rtr = 1;
  r.uMsgInfo.Bits.dlc = 0;
  CANMSG x = one_byte(0x1234, 0);  // remote 29-bit 0x1234: on the list
  x.uMsgInfo.Bits.ext = 1;
  x.uMsgInfo.Bits.rtr = 1;
  x.uMsgInfo.Bits.dlc = 0;
  for (CANMSG* m : {&a, &b, &r, &x}) {
    ASSERT_EQ(beta.writer->PutDataEntry(m), VCI_OK);
  }
  step_ns(5'000'000);
  auto ids = [](IFifoReader* reader) {
    std::vector<std::pair<uint32_t, unsigned>> v;
    CANMSG2 m;
    while (reader->GetDataEntry(&m) == VCI_OK) {
      if (m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
        v.emplace_back(m.dwMsgId | (m.uMsgInfo.Bits.rtr != 0 ? 0x80000000U : 0U),
                       static_cast<unsigned>(m.uMsgInfo.Bits.afc));
      }
    }
    return v;
  };
  using V = std::vector<std::pair<uint32_t, unsigned>>;
  const unsigned all = CAN_ACCEPT_ALWAYS;
  EXPECT_EQ(ids(lock.reader.p), V{});
  EXPECT_EQ(ids(pass.reader.p),
            (V{{0x123, all}, {0x124, all}, {0x80000123, all}, {0x80001234, all}}));
  EXPECT_EQ(ids(incl.reader.p),
            (V{{0x123, CAN_ACCEPT_FILTER_2}, {0x80001234, CAN_ACCEPT_FILTER_2}}));
  EXPECT_EQ(ids(excl.reader.p),
            (V{{0x124, CAN_ACCEPT_PASSEXCL}, {0x80000123, CAN_ACCEPT_PASSEXCL}}));
}

TEST(VciCppApi, ChannelsAreSharedUnlessOneIsExclusive) {
  VciDaemon d;
  Adapter alpha("alpha");  // holds a shared channel
  Ref<ICanChannel> exclusive;
  EXPECT_EQ(alpha.socket->CreateChannel(TRUE, exclusive.out()), VCI_E_ACCESSDENIED);
  EXPECT_EQ(exclusive.p, nullptr);
  Ref<ICanChannel> shared;
  EXPECT_EQ(alpha.socket->CreateChannel(FALSE, shared.out()), VCI_OK);
  // On beta, an exclusive channel shuts out every other.
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(2, bal));
  Ref<ICanSocket> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
  Ref<ICanChannel> first;
  ASSERT_EQ(socket->CreateChannel(TRUE, first.out()), VCI_OK);
  Ref<ICanChannel> second;
  EXPECT_EQ(socket->CreateChannel(FALSE, second.out()), VCI_E_ACCESSDENIED);
  first->Release();
  first.p = nullptr;
  EXPECT_EQ(socket->CreateChannel(FALSE, second.out()), VCI_OK);  // released: open again
}

}  // namespace
}  // namespace canemu
