// The message filters of the control unit and of v2 channels as the line applies them
// (VCI C++ guide 5.2.4, docs/vci.md); the filter itself is tested in filter_test.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"

namespace canemu::model {
namespace {

using namespace testing;  // line_rig.hpp, hosted_station.hpp

// ---------------------------------------------------------------- filters

TEST(VciCanLine, TheWorkedExampleFilterOnTheControlUnitPassesIds100To103Only) {
  Rig r;
  Port p;
  r.init();
  ASSERT_EQ(r.line.filter(std::nullopt, acceptance(CAN_FILTER_STD, 0x200, 0xFF9)).hr, VCI_OK);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  for (uint32_t id : {0x100u, 0x101u, 0x102u, 0x103u, 0x104u, 0x0FFu}) {
    r.peer.send(classic(id));
  }
  r.peer.send(remote(0x100));
  r.b.run_until(5 * kMs);
  EXPECT_EQ(p.data_ids(), (std::vector<uint32_t>{0x100, 0x101, 0x102, 0x103}));
  for (const CANMSG2& m : p.data()) {
    EXPECT_EQ(m.uMsgInfo.Bits.afc, static_cast<uint32_t>(CAN_ACCEPT_FILTER_1));
  }
  EXPECT_EQ(r.peer.log.sent.size(), 7u);  // all acknowledged by the controller
}

// The control unit's 11-bit acceptance filter closed: only the IDs its list holds pass.
void close_std_acceptance(Rig& r) {
  ASSERT_EQ(
      r.line.filter(std::nullopt, acceptance(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE))
          .hr,
      VCI_OK);
}

TEST(VciCanLine, WithTheAcceptanceFilterClosedOnlyListedIdsPassWithFilter2) {
  Rig r;
  Port p;
  r.init();
  ASSERT_NO_FATAL_FAILURE(close_std_acceptance(r));
  ASSERT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_STD, 0x123 << 1, kStdMask)).hr, VCI_OK);
  ASSERT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_STD, 0x200, 0xFF9)).hr, VCI_OK);
  ASSERT_EQ(r.line.filter(std::nullopt, remove_ids(CAN_FILTER_STD, 0x204, 0xFFD)).hr,
            VCI_OK);  // 0x102 and 0x103
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  for (uint32_t id : {0x122u, 0x123u, 0x124u, 0x100u, 0x101u, 0x102u, 0x103u}) {
    r.peer.send(classic(id));
  }
  r.peer.send(remote(0x123));
  r.b.run_until(5 * kMs);
  EXPECT_EQ(p.data_ids(), (std::vector<uint32_t>{0x123, 0x100, 0x101}));
  for (const CANMSG2& m : p.data()) {
    EXPECT_EQ(m.uMsgInfo.Bits.afc, static_cast<uint32_t>(CAN_ACCEPT_FILTER_2));
  }
}

TEST(VciCanLine, The29BitFilterSelectsAnIdentifierAndRtrPair) {
  Rig r;
  Port p;
  r.init();
  const uint32_t code = ixxat::filter_value(0x1ABCDEF0, true);
  ASSERT_EQ(r.line.filter(std::nullopt, acceptance(CAN_FILTER_EXT, code, kExtMask)).hr, VCI_OK);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(classic(0x1ABCDEF0, {1}, true));
  r.peer.send(remote(0x1ABCDEF0, true));
  r.peer.send(remote(0x1ABCDEF1, true));
  r.peer.send(classic(0x0F0, {1}));  // 11-bit frames are not affected
  r.b.run_until(5 * kMs);
  const auto d = p.data();
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].dwMsgId, 0x1ABCDEF0u);
  EXPECT_EQ(info(d[0]),
            (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_EXT | CAN_MSGFLAGS_RTR, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d[1].dwMsgId, 0x0F0u);
}

TEST(VciCanLine, FilterChangesAreRefusedWhileOnlineOrActiveButTheModeCanBeRead) {
  Rig r;
  Port p, q;
  r.init();
  r.channel(p);
  const ChannelId v2 = r.channel(q, true, {16, CAN_FILTER_EXCL});
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  for (const FilterOp& op :
       {acceptance(CAN_FILTER_STD, 0, 0), add_ids(CAN_FILTER_EXT, 0, kExtMask),
        remove_ids(CAN_FILTER_STD, 0, kStdMask), set_mode(CAN_FILTER_STD, CAN_FILTER_PASS)}) {
    EXPECT_EQ(r.line.filter(std::nullopt, op).hr, VCI_E_INVALID_STATE);
    EXPECT_EQ(r.line.filter(v2, op).hr, VCI_E_INVALID_STATE);
  }
  const ixxat::FilterResult control = r.line.filter(std::nullopt, get_mode(CAN_FILTER_STD));
  EXPECT_EQ(control.hr, VCI_OK);
  EXPECT_EQ(control.mode, CAN_FILTER_INCL);
  const ixxat::FilterResult channel = r.line.filter(v2, get_mode(CAN_FILTER_EXT));
  EXPECT_EQ(channel.hr, VCI_OK);
  EXPECT_EQ(channel.mode, CAN_FILTER_EXCL);
  // An inactive channel on a running line may change its filter; the control unit not.
  ASSERT_EQ(r.line.deactivate(v2), VCI_OK);
  EXPECT_EQ(r.line.filter(v2, add_ids(CAN_FILTER_EXT, 0, kExtMask)).hr, VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_EXT, 0, kExtMask)).hr,
            VCI_E_INVALID_STATE);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_EXT, 0, kExtMask)).hr, VCI_OK);
}

TEST(VciCanLine, FilterCallsNeedAV2ChannelWithFiltersAndAValidSelection) {
  Rig r;
  Port p;
  const ChannelId v1 = *r.line.open_channel(false, false);
  const ChannelId v2 = *r.line.open_channel(false, true);
  EXPECT_EQ(r.line.filter(v1, get_mode(CAN_FILTER_STD)).hr, VCI_E_NOT_IMPLEMENTED);
  EXPECT_EQ(r.line.filter(v2, get_mode(CAN_FILTER_STD)).hr, VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(r.line.filter(77, get_mode(CAN_FILTER_STD)).hr, VCI_E_INVALID_HANDLE);
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(3)).hr, VCI_E_INVALIDARG);
  ASSERT_EQ(r.line.init_channel(v2, {0, CAN_FILTER_LOCK}, &p), VCI_OK);
  EXPECT_EQ(r.line.filter(v2, get_mode(CAN_FILTER_STD)).mode, CAN_FILTER_LOCK);
  const ixxat::FilterResult bad = r.line.filter(v2, set_mode(CAN_FILTER_STD, CAN_FILTER_VOID));
  EXPECT_EQ(bad.hr, VCI_E_INVALIDARG);
  EXPECT_EQ(r.line.filter(v2, get_mode(CAN_FILTER_STD)).mode, CAN_FILTER_LOCK);
}

TEST(VciCanLine, TheV1ControlUnitFilterIsInclAndAV2InitLineSetsTheModes) {
  Rig r;
  r.init();
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(CAN_FILTER_STD)).mode, CAN_FILTER_INCL);
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(CAN_FILTER_EXT)).mode, CAN_FILTER_INCL);
  ASSERT_EQ(r.line.init_line(v2_init(CAN_FILTER_LOCK, CAN_FILTER_PASS)), VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(CAN_FILTER_STD)).mode, CAN_FILTER_LOCK);
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(CAN_FILTER_EXT)).mode, CAN_FILTER_PASS);
  const ixxat::FilterResult changed =
      r.line.filter(std::nullopt, set_mode(CAN_FILTER_STD, CAN_FILTER_EXCL));
  EXPECT_EQ(changed.hr, VCI_OK);
  EXPECT_EQ(changed.mode, CAN_FILTER_LOCK);  // the previous mode
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(CAN_FILTER_STD)).mode, CAN_FILTER_EXCL);
  // ResetLine and InitLine go back to the modes of the InitLine.
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(CAN_FILTER_STD)).mode, CAN_FILTER_LOCK);
  ASSERT_EQ(r.line.init_line(v2_init(CAN_FILTER_LOCK, CAN_FILTER_PASS)), VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, get_mode(CAN_FILTER_STD)).mode, CAN_FILTER_LOCK);
}

TEST(VciCanLine, TheControlUnitsExtendedListHoldsWhatInitLineGaveAndResetLineEmptiesIt) {
  Rig r;
  r.init();
  // v1: 2048 values, e.g. 1024 identifiers with and without RTR.
  ASSERT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_EXT, 0, kExtMask & ~0x7FFu)).hr, VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_EXT, 0x800, kExtMask)).hr,
            VCI_E_OUTOFMEMORY);
  ASSERT_EQ(r.line.reset_line(), VCI_OK);  // the list is deleted: room again
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_EXT, 0x800, kExtMask)).hr, VCI_OK);
  ixxat::LineInit init = v2_init();
  init.ef_ids = 4;
  ASSERT_EQ(r.line.init_line(init), VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_EXT, 0, kExtMask & ~0x7u)).hr,
            VCI_E_OUTOFMEMORY);  // 8 values
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_EXT, 0, kExtMask & ~0x3u)).hr, VCI_OK);
  // The 11-bit list takes every value whatever dwSFIds says.
  init.sf_ids = 16;
  ASSERT_EQ(r.line.init_line(init), VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_STD, 0, 0)).hr, VCI_OK);
}

TEST(VciCanLine, StopLineKeepsTheFiltersAndInitLineOpensThemAgain) {
  Rig r;
  Port p;
  r.init();
  ASSERT_EQ(r.line
                .filter(std::nullopt,
                        acceptance(CAN_FILTER_STD, ixxat::filter_value(0x123, false), kStdMask))
                .hr,
            VCI_OK);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(classic(0x123));
  r.peer.send(classic(0x124));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.send(classic(0x123));
  r.peer.send(classic(0x124));
  r.b.run_until(2 * kMs);
  EXPECT_EQ(p.data_ids(), (std::vector<uint32_t>{0x123, 0x123}));
  ASSERT_EQ(r.line.init_line(v1_init()), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.send(classic(0x124));
  r.b.run_until(3 * kMs);
  EXPECT_EQ(p.data_ids(), (std::vector<uint32_t>{0x123, 0x123, 0x124}));
}

TEST(VciCanLine, AFrameTheControlUnitBlocksReachesNoChannelButEventMessagesDo) {
  Rig r;
  Port pass, v1;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(v2_init(CAN_FILTER_LOCK, CAN_FILTER_LOCK)), VCI_OK);
  r.channel(pass, true, {0, CAN_FILTER_PASS});
  r.channel(v1);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(k123);
  r.peer.send(classic(0x123, {1}, true));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  for (Port* p : {&pass, &v1}) {
    ASSERT_EQ(p->rx.size(), 2u);
    EXPECT_EQ(p->rx[0].abData[0], CAN_INFO_START);
    EXPECT_EQ(p->rx[1].abData[0], CAN_INFO_STOP);
  }
  EXPECT_EQ(r.peer.log.sent.size(), 2u);  // acknowledged all the same
}

TEST(VciCanLine, ElevenAndTwentyNineBitFiltersOfTheControlUnitAreIndependent) {
  Rig r;
  Port p;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(v2_init(CAN_FILTER_LOCK, CAN_FILTER_INCL)), VCI_OK);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(k123);
  r.peer.send(classic(0x123, {0x11, 0x22}, true));
  r.b.run_until(1 * kMs);
  const auto d = p.data();
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_EXT | 2, CAN_ACCEPT_FILTER_1}));
}

TEST(VciCanLine, AControlUnitWithoutElevenBitIdsPassesEveryElevenBitFrame) {
  Rig r;
  Port p;
  ixxat::LineInit init = v2_init(CAN_FILTER_LOCK, CAN_FILTER_LOCK);
  init.sf_ids = 0;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(init), VCI_OK);
  EXPECT_EQ(r.line.filter(std::nullopt, add_ids(CAN_FILTER_STD, 0x246, kStdMask)).hr,
            VCI_E_OUTOFMEMORY);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(k123);
  r.peer.send(remote(0x7FF));
  r.peer.send(classic(0x123, {0x11}, true));  // the 29-bit filter still locks
  r.b.run_until(1 * kMs);
  const auto d = p.data();
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, 2, CAN_ACCEPT_ALWAYS}));
  EXPECT_EQ(info(d[1]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_RTR, CAN_ACCEPT_ALWAYS}));
}

TEST(VciCanLine, V2ChannelFiltersSetAfcUnlessTheyPass) {
  Rig r;
  Port incl, excl, pass;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(v2_init(CAN_FILTER_PASS, CAN_FILTER_PASS)), VCI_OK);
  const ChannelId ci = *r.line.open_channel(false, true);
  const ChannelId ce = *r.line.open_channel(false, true);
  for (auto [id, port, mode] :
       {std::tuple{ci, &incl, CAN_FILTER_INCL}, std::tuple{ce, &excl, CAN_FILTER_EXCL}}) {
    ASSERT_EQ(r.line.init_channel(id, {16, static_cast<uint8_t>(mode)}, port), VCI_OK);
    ASSERT_EQ(
        r.line.filter(id, acceptance(CAN_FILTER_STD, ixxat::filter_value(0x123, false), kStdMask))
            .hr,
        VCI_OK);
    ASSERT_EQ(
        r.line.filter(id, add_ids(CAN_FILTER_STD, ixxat::filter_value(0x124, false), kStdMask)).hr,
        VCI_OK);
    ASSERT_EQ(r.line.activate(id), VCI_OK);
  }
  r.channel(pass, true, {0, CAN_FILTER_PASS});
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(classic(0x123));
  r.peer.send(classic(0x124));
  r.peer.send(classic(0x125));
  r.b.run_until(2 * kMs);
  auto afc = [](const Port& p) {
    std::vector<std::pair<uint32_t, uint32_t>> out;
    for (const CANMSG2& m : p.data()) {
      out.emplace_back(m.dwMsgId, m.uMsgInfo.Bits.afc);
    }
    return out;
  };
  using V = std::vector<std::pair<uint32_t, uint32_t>>;
  EXPECT_EQ(afc(incl), (V{{0x123, CAN_ACCEPT_FILTER_1}, {0x124, CAN_ACCEPT_FILTER_2}}));
  EXPECT_EQ(afc(excl), (V{{0x125, CAN_ACCEPT_PASSEXCL}}));
  // PASS on the channel and on the control unit: accepted always.
  EXPECT_EQ(
      afc(pass),
      (V{{0x123, CAN_ACCEPT_ALWAYS}, {0x124, CAN_ACCEPT_ALWAYS}, {0x125, CAN_ACCEPT_ALWAYS}}));
}

TEST(VciCanLine, AV2ChannelInPassModeShowsTheControlUnitsAfc) {
  Rig r;
  Port p;
  r.init();
  ASSERT_NO_FATAL_FAILURE(close_std_acceptance(r));
  ASSERT_EQ(r.line
                .filter(std::nullopt,
                        add_ids(CAN_FILTER_STD, ixxat::filter_value(0x123, false), kStdMask))
                .hr,
            VCI_OK);
  r.channel(p, true, {0, CAN_FILTER_PASS});
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(k123);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(p.data().size(), 1u);
  EXPECT_EQ(p.data()[0].uMsgInfo.Bits.afc, static_cast<uint32_t>(CAN_ACCEPT_FILTER_2));
}

TEST(VciCanLine, AV2ChannelWithoutAListRefusesIdCallsButKeepsItsAcceptanceFilter) {
  Rig r;
  Port p;
  r.init();
  const ChannelId ch = *r.line.open_channel(false, true);
  ASSERT_EQ(r.line.init_channel(ch, {0, CAN_FILTER_INCL}, &p), VCI_OK);
  EXPECT_EQ(r.line.filter(ch, add_ids(CAN_FILTER_EXT, 0x2468, kExtMask)).hr, VCI_E_OUTOFMEMORY);
  ASSERT_EQ(r.line.filter(ch, acceptance(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE)).hr,
            VCI_OK);
  EXPECT_EQ(r.line.filter(ch, remove_ids(CAN_FILTER_EXT, 0x2468, kExtMask)).hr, VCI_E_OUTOFMEMORY);
  EXPECT_EQ(r.line.filter(ch, add_ids(CAN_FILTER_STD, 0x246, kStdMask)).hr, VCI_OK);
  EXPECT_EQ(
      r.line.filter(ch, acceptance(CAN_FILTER_EXT, ixxat::filter_value(0x1234, false), kExtMask))
          .hr,
      VCI_OK);
  // A list of 2 refuses a pattern of 4.
  Port q;
  const ChannelId small = *r.line.open_channel(false, true);
  ASSERT_EQ(r.line.init_channel(small, {2, CAN_FILTER_INCL}, &q), VCI_OK);
  EXPECT_EQ(r.line.filter(small, add_ids(CAN_FILTER_EXT, 0, kExtMask & ~0x6u)).hr,
            VCI_E_OUTOFMEMORY);
  EXPECT_EQ(r.line.filter(small, add_ids(CAN_FILTER_EXT, 0, kExtMask & ~0x2u)).hr, VCI_OK);
  ASSERT_EQ(r.line.activate(ch), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(classic(0x1234, {1}, true));
  r.peer.send(classic(0x1235, {1}, true));
  r.peer.send(classic(0x123, {1}));
  r.peer.send(classic(0x124, {1}));
  r.b.run_until(2 * kMs);
  EXPECT_EQ(p.data_ids(), (std::vector<uint32_t>{0x1234, 0x123}));
}

}  // namespace
}  // namespace canemu::model
