// The VCI firmware of one CAN controller (VCI C++ guide 5.2, 8.3, docs/vci.md "The
// controller's firmware"): the control unit's states and INFO messages, line status, ERROR,
// STATUS and TIMEOVR messages. The line drives a hosted SJA1000 on a simulated bus with a peer
// station. The other topics: can_line_transmit_test (transmission), can_line_filters_test,
// can_line_fd_test, distributor_test (channels, self reception), cyclic_list_test,
// bitrate_detector_test, line_init_test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "case_name.hpp"

namespace canemu::model {
namespace {

using namespace testing;  // line_rig.hpp, hosted_station.hpp

// ---------------------------------------------------------------- control unit

TEST(VciCanLine, CapabilitiesReportTheEmulatedClocksAndFeatures) {
  Rig r;
  const CANCAPABILITIES c = r.line.capabilities();
  EXPECT_EQ(c.wCtrlType, CAN_CTRL_SJA1000);
  EXPECT_EQ(c.wBusCoupling, CAN_BUSC_HIGHSPEED);
  // STDANDEXT RMTFRAME ERRFRAME BUSLOAD IDFILTER LISTONLY SCHEDULER DELAYEDTX SINGLESHOT
  // HIGHPRIOR AUTOBAUD: 0x2 + 0x4 + 0x8 + 0x10 + 0x20 + 0x40 + 0x80 + 0x200 + 0x400 + 0x800 +
  // 0x1000.
  EXPECT_EQ(c.dwFeatures, 0x1EFEu);
  EXPECT_EQ(c.dwClockFreq, 1'000'000u);
  EXPECT_EQ(c.dwTscDivisor, 1u);
  EXPECT_EQ(c.dwCmsDivisor, 1000u);
  EXPECT_EQ(c.dwCmsMaxTicks, 0xFFFFu);
  EXPECT_EQ(c.dwDtxDivisor, 1u);
  EXPECT_EQ(c.dwDtxMaxTicks, 0xFFFFu);
  const CANCAPABILITIES2 c2 = r.line.capabilities2();
  EXPECT_EQ(c2.dwFeatures, 0x1EFEu);
  EXPECT_EQ(c2.dwCanClkFreq, 8'000'000u);
  EXPECT_EQ(c2.sSdrRangeMax.dwBPS, 64u);
  EXPECT_EQ(c2.sSdrRangeMax.wTS1, 16u);
  EXPECT_EQ(c2.sSdrRangeMax.wTS2, 8u);
  EXPECT_EQ(c2.sFdrRangeMax.dwBPS, 0u);  // no fast data rate
  EXPECT_EQ(c2.dwTscClkFreq, 1'000'000u);
  EXPECT_EQ(c2.dwCmsClkFreq, 1'000'000u);
  EXPECT_EQ(c2.dwDtxClkFreq, 1'000'000u);
}

TEST(VciCanLine, OnALowSpeedBusTheCouplingIsLowSpeedAndItsOpModeAccepted) {
  Rig hs;
  ASSERT_EQ(hs.line.open_control(), VCI_OK);
  EXPECT_EQ(hs.line.init_line(v1_init(kOpAll | CAN_OPMODE_LOWSPEED)), VCI_E_INVALIDARG);
  Rig r;
  r.line.set_low_speed(true);
  EXPECT_EQ(r.line.capabilities().wBusCoupling, CAN_BUSC_LOWSPEED);
  EXPECT_EQ(r.line.capabilities2().wBusCoupling, CAN_BUSC_LOWSPEED);
  r.init(kOpAll | CAN_OPMODE_LOWSPEED);
  EXPECT_EQ(r.line.line_status().bOpMode, kOpAll | CAN_OPMODE_LOWSPEED);
}

// A wire fault the (fault-tolerant) transceiver reports: BUSCERR, one STATUS message when it
// comes and one when it goes, and ResetLine does not clear it.
TEST(VciCanLine, ABusCouplingErrorSetsBuscerrWithStatusMessages) {
  Rig r;
  r.line.set_low_speed(true);
  Port p;
  r.online(p);
  r.b.run_until(1 * kMs);
  r.line.set_bus_coupling_error(true);
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_BUSCERR));
  auto status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].dwTime, 1000u);
  EXPECT_EQ(status[0].abData[0], CAN_STATUS_BUSCERR);
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.line.line_status().dwStatus,
            static_cast<uint32_t>(CAN_STATUS_BUSCERR | CAN_STATUS_ININIT));
  EXPECT_EQ(p.of_type(CAN_MSGTYPE_STATUS).size(), 1u);  // unchanged: no message
  r.b.run_until(2 * kMs);
  r.line.set_bus_coupling_error(false);
  status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 2u);
  EXPECT_EQ(status[1].dwTime, 2000u);
  EXPECT_EQ(status[1].abData[0], CAN_STATUS_ININIT);
}

TEST(VciCanLine, StartLineBeforeInitLineIsAnInvalidState) {
  Rig r;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  EXPECT_EQ(r.line.start_line(), VCI_E_INVALID_STATE);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  const CANLINESTATUS s = r.line.line_status();
  EXPECT_EQ(s.bOpMode, 0);
  EXPECT_EQ(s.bBtReg0, 0);
  EXPECT_EQ(s.bBtReg1, 0);
  EXPECT_EQ(s.dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
  EXPECT_FALSE(r.node.running());
}

TEST(VciCanLine, InitLineReportsModeAndBtrAndStaysOfflineWithoutAnInfoMessage) {
  Rig r;
  Port p;
  r.init();
  r.channel(p);
  EXPECT_EQ(r.line.state(), ixxat::LineState::offline);
  const CANLINESTATUS s = r.line.line_status();
  EXPECT_EQ(s.bOpMode, kOpAll);
  EXPECT_EQ(s.bBtReg0, 0x00);
  EXPECT_EQ(s.bBtReg1, 0x1C);
  EXPECT_EQ(s.dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
  const CANLINESTATUS2 s2 = r.line.line_status2();
  EXPECT_EQ(s2.bOpMode, kOpAll);
  EXPECT_EQ(s2.bExMode, CAN_EXMODE_DISABLED);
  // BTR 0x00/0x1C as a raw CANBTP: prescaler 1, TSEG1 13, TSEG2 2, SJW 1.
  EXPECT_EQ(s2.sBtpSdr.dwMode, static_cast<uint32_t>(CAN_BTMODE_RAW));
  EXPECT_EQ(s2.sBtpSdr.dwBPS, 1u);
  EXPECT_EQ(s2.sBtpSdr.wTS1, 13);
  EXPECT_EQ(s2.sBtpSdr.wTS2, 2);
  EXPECT_EQ(s2.sBtpSdr.wSJW, 1);
  EXPECT_TRUE(p.rx.empty());
  EXPECT_FALSE(r.node.running());
}

TEST(VciCanLine, StartLineSendsOneInfoStartWithTheStartTimeInTicks) {
  Rig r;
  Port p;
  r.init();
  r.channel(p);
  r.b.run_until(1'500 * kUs);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::online);
  EXPECT_TRUE(r.node.running());
  ASSERT_EQ(p.rx.size(), 1u);
  const CANMSG2& m = p.rx[0];
  EXPECT_EQ(m.dwTime, 1500u);
  EXPECT_EQ(m.dwMsgId, CAN_MSGID_INFO);
  EXPECT_EQ(info(m), (Info{CAN_MSGTYPE_INFO, 0, 1, CAN_ACCEPT_ALWAYS}));
  EXPECT_EQ(m.abData[0], CAN_INFO_START);
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
  // Already online: nothing happens.
  EXPECT_EQ(r.line.start_line(), VCI_OK);
  EXPECT_EQ(p.rx.size(), 1u);
}

TEST(VciCanLine, StopAndResetSendInfoMessagesWithTimeZero) {
  Rig r;
  Port p;
  r.online(p);
  r.b.run_until(3 * kMs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::offline);
  EXPECT_FALSE(r.node.running());
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
  EXPECT_EQ(r.line.stop_line(), VCI_OK);  // not online: nothing happens
  r.b.run_until(4 * kMs);
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  EXPECT_EQ(r.line.start_line(), VCI_E_INVALID_STATE);
  const auto infos = p.of_type(CAN_MSGTYPE_INFO);
  ASSERT_EQ(infos.size(), 3u);
  EXPECT_EQ(infos[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(infos[0].dwTime, 0u);
  EXPECT_EQ(infos[1].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(infos[1].dwTime, 0u);
  EXPECT_EQ(info(infos[1]), (Info{CAN_MSGTYPE_INFO, 0, 1, CAN_ACCEPT_ALWAYS}));
  EXPECT_EQ(infos[2].abData[0], CAN_INFO_RESET);
  EXPECT_EQ(infos[2].dwTime, 0u);
  EXPECT_EQ(infos[2].dwMsgId, CAN_MSGID_INFO);
  EXPECT_EQ(p.rx.size(), 3u);  // nothing else
  // A new InitLine makes it startable again.
  ASSERT_EQ(r.line.init_line(v1_init()), VCI_OK);
  EXPECT_EQ(r.line.start_line(), VCI_OK);
}

TEST(VciCanLine, InactiveChannelsReceiveNeitherInfoMessagesNorFrames) {
  Rig r;
  Port active, inactive;
  r.init();
  r.channel(active);
  auto id = r.line.open_channel(false, false);
  ASSERT_TRUE(id);
  ASSERT_EQ(r.line.init_channel(*id, {}, &inactive), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(k123);
  r.b.run_until(1 * kMs);
  EXPECT_EQ(active.rx.size(), 2u);  // INFO START, the frame
  EXPECT_TRUE(inactive.rx.empty());
  const auto status = r.line.channel_status(*id);
  ASSERT_TRUE(status);
  EXPECT_TRUE(status->initialized);
  EXPECT_FALSE(status->activated);
  EXPECT_EQ(status->counters.received, 0u);
}

TEST(VciCanLine, InitLineWhileOnlineResetsTheControllerAndLeavesTheLineOffline) {
  Rig r;
  Port p;
  r.online(p);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.line.init_line(v1_init(CAN_OPMODE_STANDARD)), VCI_OK);
  EXPECT_EQ(r.line.state(), ixxat::LineState::offline);
  EXPECT_FALSE(r.node.running());
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
  EXPECT_EQ(r.line.line_status().bOpMode, CAN_OPMODE_STANDARD);
  EXPECT_EQ(p.rx.size(), 1u);  // INFO START only: InitLine sends no INFO
  // Offline, the controller neither receives nor acknowledges.
  r.peer.send(k123);
  r.b.run_until(2 * kMs);
  EXPECT_TRUE(p.data().empty());
  ASSERT_FALSE(r.peer.log.errors.empty());
  EXPECT_EQ(r.peer.log.errors[0].type, CanErrorType::ack);
}

TEST(VciCanLine, ASecondControlUnitIsDeniedUntilTheFirstIsClosed) {
  Rig r;
  Port p;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  EXPECT_TRUE(r.line.control_open());
  EXPECT_EQ(r.line.open_control(), VCI_E_ACCESSDENIED);
  r.channel(p);  // keeps the line in use
  r.line.close_control();
  EXPECT_FALSE(r.line.control_open());
  EXPECT_EQ(r.line.open_control(), VCI_OK);
}

TEST(VciCanLine, ClosingTheControlUnitLeavesTheLineRunningForItsChannels) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.line.close_control();
  EXPECT_EQ(r.line.state(), ixxat::LineState::online);
  r.peer.send(k123);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(p.data().size(), 1u);
  EXPECT_EQ(p.data()[0].dwTime, 124u);  // 62 bits at 2 us from t = 0
  // The last user goes: the line is released, the controller leaves the bus.
  r.line.close_channel(ch);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  EXPECT_FALSE(r.node.running());
  EXPECT_EQ(r.line.line_status().bOpMode, 0);
  EXPECT_EQ(r.line.line_status().bBtReg1, 0);
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
  EXPECT_FALSE(r.line.channel_status(ch));
  r.peer.send(k123);
  r.b.run_until(2 * kMs);
  ASSERT_FALSE(r.peer.log.errors.empty());
  EXPECT_EQ(r.peer.log.errors[0].type, CanErrorType::ack);
}

TEST(VciCanLine, TheLineIsReleasedOnlyWhenControlChannelsAndCyclicListAreAllClosed) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  ASSERT_EQ(r.line.open_scheduler(), VCI_OK);
  EXPECT_EQ(r.line.scheduler_add(CANCYCLICTXMSG2{}).error(), VCI_E_INVALIDARG);  // cycle 0
  CANCYCLICTXMSG2 c{};
  c.wCycleTime = 10;
  c.dwMsgId = 0x100;
  ASSERT_EQ(r.line.scheduler_add(c).value(), 0u);
  r.line.close_control();
  r.line.close_channel(ch);
  EXPECT_EQ(r.line.state(), ixxat::LineState::online);
  EXPECT_TRUE(r.node.running());
  r.line.close_scheduler();
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  EXPECT_FALSE(r.node.running());
  // The list went with the line.
  ASSERT_EQ(r.line.open_scheduler(), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[0], CAN_CTXMSG_STAT_EMPTY);
}

TEST(VciCanLine, StopLineAndResetLineLeaveTheChannelFifosAlone) {
  Rig r;
  Port p;
  r.online(p);
  r.peer.send(k123);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  p.tx.push_back(msg(0x201));
  p.tx.push_back(msg(0x202));
  r.line.tx_ready();
  r.b.run_until(2 * kMs);
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  r.b.run_until(3 * kMs);
  EXPECT_EQ(p.tx.size(), 2u);
  ASSERT_EQ(p.rx.size(), 4u);  // START, the frame, STOP, RESET
  EXPECT_EQ(p.rx[1].dwMsgId, 0x123u);
  EXPECT_EQ(p.rx[2].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(p.rx[3].abData[0], CAN_INFO_RESET);
  // Once the line runs again the queued frames go out in order.
  ASSERT_EQ(r.line.init_line(v1_init()), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(4 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 2u);
  EXPECT_EQ(r.peer.log.received[0].frame.id(), 0x201u);
  EXPECT_EQ(r.peer.log.received[1].frame.id(), 0x202u);
}

TEST(VciCanLine, AFrameLoadedButNotStartedAtStopLineGoesFirstAfterStartLine) {
  Rig r;
  Port p;
  const ChannelId ch = r.start_with(p, {msg(0x123), msg(0x124)});  // 0x123 is loaded, not started
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_TXPEND));
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  EXPECT_EQ(p.tx.size(), 1u);
  r.b.run_until(1 * kMs);
  EXPECT_TRUE(r.peer.log.received.empty());
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(2 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 2u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.peer.log.received[0].at, 1 * kMs + 62 * kBit);
  EXPECT_EQ(r.peer.log.received[1].frame.id(), 0x124u);
  // After the intermission of 3 bits.
  EXPECT_EQ(r.peer.log.received[1].at, 1 * kMs + (62 + 3 + bits_of(classic(0x124))) * kBit);
  EXPECT_EQ(r.counters(ch).sent, 2u);
  EXPECT_EQ(r.counters(ch).dropped, 0u);
}

TEST(VciCanLine, ResetLineDropsTheLoadedFrameAndCountsIt) {
  Rig r;
  Port p;
  const ChannelId ch = r.start_with(p, {msg(0x123), msg(0x124)});
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
  ASSERT_EQ(r.line.init_line(v1_init()), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame.id(), 0x124u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
}

// STOP and RESET both let a frame already on the wire finish: it is delivered, counted as
// sent, and nothing is dropped; the line is then in init mode.
struct Halt {
  const char* name;
  HRESULT (ixxat::CanLine::*call)();
};

class VciCanLineHalt : public ::testing::TestWithParam<Halt> {};

TEST_P(VciCanLineHalt, AFrameOnTheWireCompletes) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.send(p, msg(0x123));
  r.b.run_until(20 * kBit);  // inside the frame
  ASSERT_EQ((r.line.*GetParam().call)(), VCI_OK);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].at, 62 * kBit);
  EXPECT_EQ(r.peer.log.sent.size(), 0u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.counters(ch).dropped, 0u);
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
}

INSTANTIATE_TEST_SUITE_P(VciCanLine, VciCanLineHalt,
                         ::testing::Values(Halt{"StopLine", &ixxat::CanLine::stop_line},
                                           Halt{"ResetLine", &ixxat::CanLine::reset_line}),
                         test_support::CaseName{});

// ---------------------------------------------------------------- errors and status

TEST(VciCanLine, ALoneTransmitterGetsAckErrorsErrlimAtTec96AndStaysErrorPassiveAt128) {
  Rig r;  // nobody acknowledges
  Port p, locked;
  r.init();
  r.channel(p);
  r.channel(locked, true, {0, CAN_FILTER_LOCK});
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.send(p, msg(0x123));
  r.b.run_until(20 * kMs);
  const auto errors = p.of_type(CAN_MSGTYPE_ERROR);
  ASSERT_GT(errors.size(), 20u);
  for (std::size_t k = 0; k < errors.size(); ++k) {
    const CANMSG2& e = errors[k];
    EXPECT_EQ(e.dwMsgId, CAN_MSGID_ERROR);
    EXPECT_EQ(info(e), (Info{CAN_MSGTYPE_ERROR, 0, 2, CAN_ACCEPT_ALWAYS})) << k;
    EXPECT_EQ(e.abData[0], CAN_ERROR_ACK) << k;
    // TEC 8 (k + 1), at most 128: ERRLIM from the 12th error (TEC 96) on.
    EXPECT_EQ(e.abData[1], k < 11 ? CAN_STATUS_TXPEND : CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM) << k;
    // Beyond the dlc: REC and TEC after the error.
    EXPECT_EQ(e.abData[3], 0) << k;
    EXPECT_EQ(e.abData[4], std::min<std::size_t>(8 * (k + 1), 128)) << k;
  }
  // Error-active: ACK slot at bit 53, then 6 flag + 8 delimiter + 3 intermission bits: one
  // attempt every 54 + 17 = 71 bits.
  for (std::size_t k = 0; k < 12; ++k) {
    EXPECT_EQ(errors[k].dwTime, (71 * k + 54) * 2) << k;
  }
  const auto status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].dwTime, errors[11].dwTime);
  EXPECT_EQ(status[0].dwMsgId, CAN_MSGID_STATUS);
  EXPECT_EQ(info(status[0]), (Info{CAN_MSGTYPE_STATUS, 0, 1, CAN_ACCEPT_ALWAYS}));
  EXPECT_EQ(status[0].abData[0], CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM);
  const ixxat::ControllerState cs = r.line.controller_state();
  EXPECT_EQ(cs.state, ErrorState::passive);
  EXPECT_EQ(cs.tec, 128);
  EXPECT_EQ(r.line.line_status().dwStatus,
            static_cast<uint32_t>(CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM));
  // A filter never holds back ERROR and STATUS messages.
  EXPECT_EQ(locked.of_type(CAN_MSGTYPE_ERROR).size(), errors.size());
  EXPECT_EQ(locked.of_type(CAN_MSGTYPE_STATUS).size(), 1u);
}

TEST(VciCanLine, WithoutErrFrameModeStatusMessagesArriveButNoErrorMessages) {
  Rig r;
  Port p;
  r.init(CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED);
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.send(p, msg(0x123));
  r.b.run_until(20 * kMs);
  EXPECT_TRUE(p.of_type(CAN_MSGTYPE_ERROR).empty());
  const auto status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].dwTime, (71u * 11 + 54) * 2);  // the 12th ACK error, see above
  EXPECT_EQ(status[0].abData[0], CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM);
}

TEST(VciCanLine, InitLineClearsErrlimAndReportsIt) {
  Rig r;
  Port p;
  r.init();
  r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.send(p, msg(0x123));
  r.b.run_until(20 * kMs);
  ASSERT_EQ(r.line.controller_state().state, ErrorState::passive);
  r.peer.start();  // the next attempt succeeds: TEC 127, still ERRLIM
  r.b.run_until(21 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.line.controller_state().tec, 127);
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ERRLIM));
  p.rx.clear();
  ASSERT_EQ(r.line.init_line(v1_init()), VCI_OK);
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
  EXPECT_EQ(r.line.controller_state().tec, 0);
  ASSERT_EQ(p.rx.size(), 1u);
  EXPECT_EQ(p.rx[0].uMsgInfo.Bits.type, static_cast<uint32_t>(CAN_MSGTYPE_STATUS));
  EXPECT_EQ(p.rx[0].dwTime, 21'000u);
  EXPECT_EQ(p.rx[0].abData[0], CAN_STATUS_ININIT);
}

TEST(VciCanLine, ThirtyTwoBitErrorsTakeTheLineBusOffUntilItIsStartedAgain) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.b.plan.add(errors_from(r.node.node(), CanErrorType::bit, 32));
  r.send(p, msg(0x123));
  r.b.run_until(100 * kMs);
  const auto errors = p.of_type(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 32u);
  for (std::size_t k = 0; k < 32; ++k) {
    EXPECT_EQ(errors[k].abData[0], CAN_ERROR_BIT) << k;
  }
  EXPECT_EQ(errors[10].abData[1], CAN_STATUS_TXPEND);                      // TEC 88
  EXPECT_EQ(errors[11].abData[1], CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM);  // 96
  EXPECT_EQ(errors[31].abData[1], CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF);
  auto status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 2u);  // ERRLIM at TEC 96, BUSOFF at 256 (error-passive changes none)
  EXPECT_EQ(status[0].dwTime, errors[11].dwTime);
  EXPECT_EQ(status[0].abData[0], CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM);
  EXPECT_EQ(status[1].dwTime, errors[31].dwTime);
  EXPECT_EQ(status[1].abData[0], CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF);
  EXPECT_EQ(r.line.controller_state().state, ErrorState::bus_off);
  EXPECT_EQ(r.line.line_status().dwStatus,
            static_cast<uint32_t>(CAN_STATUS_TXPEND | CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF));
  EXPECT_TRUE(r.peer.log.received.empty());
  // Still bus-off much later: the firmware does not restart by itself.
  r.b.run_until(200 * kMs);
  EXPECT_EQ(r.line.controller_state().state, ErrorState::bus_off);
  // Stop: reset mode aborts the controller's request; the firmware keeps the frame for the
  // next start, so nothing is pending in the controller while the line is offline.
  p.rx.clear();
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  EXPECT_EQ(r.node.controller().pending_tx(), nullptr);
  EXPECT_EQ(r.line.line_status().dwStatus,
            static_cast<uint32_t>(CAN_STATUS_ININIT | CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF));
  // Start: recovery takes 128 x 11 recessive bits on the idle bus, then the frame goes, once.
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  const int64_t recovered = 200 * kMs + 128 * 11 * kBit;
  r.b.run_until(recovered - 1);
  EXPECT_EQ(r.line.controller_state().state, ErrorState::bus_off);
  r.b.run_until(300 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.peer.log.received[0].at, recovered + 62 * kBit);
  EXPECT_EQ(r.peer.log.sent.size(), 0u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.counters(ch).dropped, 0u);
  status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].dwTime, static_cast<uint32_t>(recovered / kUs));
  EXPECT_EQ(status[0].abData[0], CAN_STATUS_TXPEND);  // the frame waits in the controller
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
  EXPECT_EQ(r.line.controller_state().tec, 0);
}

TEST(VciCanLine, ErrlimClearsWhenTheCountersFallBelow96) {
  Rig r;
  Port p;
  r.init();
  const ChannelId ch = r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.send(p, msg(0x123));
  r.b.run_until(20 * kMs);
  ASSERT_EQ(r.line.controller_state().tec, 128);
  for (uint32_t k = 0; k < 32; ++k) {
    p.tx.push_back(msg(0x200 + k));
  }
  p.rx.clear();
  r.peer.start();  // every success takes 1 from TEC 128: below 96 after the 33rd
  r.b.run_until(40 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 33u);
  EXPECT_EQ(r.counters(ch).sent, 33u);
  EXPECT_EQ(r.line.controller_state().tec, 95);
  EXPECT_EQ(r.line.controller_state().state, ErrorState::active);
  const auto status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].dwTime, static_cast<uint32_t>(r.peer.log.received[32].at / kUs));
  EXPECT_EQ(status[0].abData[0], 0);
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
}

TEST(VciCanLine, ReceiveErrorsGiveErrorMessagesWithTheirType) {
  Rig r;
  Port p;
  r.online(p);
  const NodeId peer = r.peer.node.node();
  for (CanErrorType type : {CanErrorType::stuff, CanErrorType::form, CanErrorType::crc}) {
    const auto bit = type == CanErrorType::stuff ? std::optional<uint16_t>(30) : std::nullopt;
    r.b.plan.add(errors_from(peer, type, 1, bit));
  }
  r.peer.send(k123);
  r.b.run_until(10 * kMs);
  const auto errors = p.of_type(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_STUFF);
  EXPECT_EQ(errors[0].dwTime, 62u);  // the end of bit 30: 31 bits
  EXPECT_EQ(errors[1].abData[0], CAN_ERROR_FORM);
  EXPECT_EQ(errors[2].abData[0], CAN_ERROR_CRC);
  for (const CANMSG2& e : errors) {
    EXPECT_EQ(e.abData[1], 0);  // REC far below 96, nothing to send
    EXPECT_EQ(info(e), (Info{CAN_MSGTYPE_ERROR, 0, 2, CAN_ACCEPT_ALWAYS}));
    EXPECT_EQ(e.abData[4], 0);  // TEC
  }
  // REC as the error is detected: +1 for it. The +8 for the transmitter's flag after the
  // receiver's own (a dominant bit after its flag) comes later, within the error frame.
  EXPECT_EQ(errors[0].abData[3], 1);
  EXPECT_EQ(errors[1].abData[3], 1 + 9);
  EXPECT_EQ(errors[2].abData[3], 1 + 18);
  EXPECT_EQ(p.data_ids(), std::vector<uint32_t>{0x123});  // the fourth attempt
}

// A long receive fault (the bus held dominant for 100 ms): every 8 dominant bits after the error
// flag add 8 to REC (rule 6), but the SJA1000's counter is 8 bits wide and stops at 255. ERRLIM
// is set, BUSOFF is not (only the TEC leads to bus-off).
TEST(VciCanLine, ALongReceiveFaultLeavesRecAt255) {
  Rig r;
  Port p;
  r.online(p);
  r.b.bus.hold_dominant(SimTime::from_ns(kMs), SimDuration(100 * kMs));
  r.b.run_until(200 * kMs);
  const ixxat::ControllerState s = r.line.controller_state();
  EXPECT_EQ(s.rec, 255);
  EXPECT_EQ(s.tec, 0);
  EXPECT_EQ(s.state, ErrorState::passive);
  EXPECT_EQ(r.peer.node.controller().confinement().rec(), 255);
  const auto errors = p.of_type(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_STUFF);  // six dominant bits from 1 ms on
  EXPECT_EQ(errors[0].abData[3], 1);
  EXPECT_EQ(errors[0].dwTime, 1012u);
  const auto status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].abData[0], CAN_STATUS_ERRLIM);
  EXPECT_EQ(status[0].dwTime, 1200u);  // REC past 96 within the dominant hold
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ERRLIM));
  // The next frame received takes it back to 127 (rule 8).
  r.peer.send(k123);
  r.b.run_until(210 * kMs);
  EXPECT_EQ(p.data_ids(), std::vector<uint32_t>{0x123});
  EXPECT_EQ(r.line.controller_state().rec, 127);
}

TEST(VciCanLine, TheTimeStampCounterOverflowsAfter2To32TicksWithATimeovrMessage) {
  Rig r;
  Port p;
  r.online(p);
  const int64_t overflow = (int64_t{1} << 32) * kUs;  // 4294.967296 s
  r.b.run_until(overflow - 1);
  EXPECT_TRUE(p.of_type(CAN_MSGTYPE_TIMEOVR).empty());
  r.b.run_until(overflow);
  const auto t = p.of_type(CAN_MSGTYPE_TIMEOVR);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].dwTime, 0u);
  EXPECT_EQ(t[0].dwMsgId, 1u);
  EXPECT_EQ(info(t[0]), (Info{CAN_MSGTYPE_TIMEOVR, 0, 0, CAN_ACCEPT_ALWAYS}));
  r.peer.send(k123);
  r.b.run_until(overflow + 1 * kMs);
  ASSERT_EQ(p.data().size(), 1u);
  EXPECT_EQ(p.data()[0].dwTime, 124u);  // counted from the overflow
}

}  // namespace
}  // namespace canemu::model
