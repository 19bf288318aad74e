// The VCI firmware of one CAN controller (spec/vci-cpp-digest.md 3.5-3.19, docs/vci.md "The
// controller's firmware"): the control unit's states and INFO messages, reception with time
// stamps, the distributor between channels, self reception, delayed, single-shot and
// high-priority transmission, ERROR, STATUS and TIMEOVR messages, the filters of the control
// unit and of v2 channels, CAN FD, and the cyclic transmit list. The line drives a hosted
// SJA1000 (or CAN FD controller) on a simulated bus with a peer station.
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <deque>
#include <ostream>
#include <tuple>
#include <vector>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"
#include "hosted_station.hpp"

namespace canemu::model {
namespace {

using ixxat::ChannelId;
using ixxat::FilterOp;
using testing::k123;
using testing::kBit;
using testing::kZero;

constexpr int64_t kUs = 1'000;      // one device tick (time stamps, delays) with default Clocks
constexpr int64_t kMs = 1'000'000;  // one tick of the cyclic list
constexpr uint8_t kOpAll = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME;
constexpr uint32_t kStdMask = 0xFFF;
constexpr uint32_t kExtMask = 0x3FFFFFFF;

// A channel's FIFOs: the transmit FIFO the test fills, a bounded receive FIFO.
struct Port final : ixxat::ChannelPort {
  explicit Port(std::size_t rx_capacity = 1024) : capacity(rx_capacity) {}
  bool put(const CANMSG2& m) override {
    if (rx.size() >= capacity) {
      return false;
    }
    rx.push_back(m);
    return true;
  }
  std::optional<CANMSG2> peek() override {
    if (tx.empty()) {
      return std::nullopt;
    }
    return tx.front();
  }
  void pop() override { tx.pop_front(); }

  std::vector<CANMSG2> of_type(uint8_t type) const {
    std::vector<CANMSG2> out;
    for (const CANMSG2& m : rx) {
      if (m.uMsgInfo.Bits.type == type) {
        out.push_back(m);
      }
    }
    return out;
  }
  std::vector<CANMSG2> data() const { return of_type(CAN_MSGTYPE_DATA); }
  std::vector<uint32_t> data_ids() const {
    std::vector<uint32_t> ids;
    for (const CANMSG2& m : data()) {
      ids.push_back(m.dwMsgId);
    }
    return ids;
  }

  std::size_t capacity;
  std::deque<CANMSG2> tx;
  std::vector<CANMSG2> rx;
};

// The four bytes of CANMSGINFO: type, flags2 (ssm hpm edl fdr esi), flags (dlc ovr srr rtr
// ext), accept.
struct Info {
  unsigned type, flags2, flags, accept;
  friend bool operator==(const Info&, const Info&) = default;
  friend std::ostream& operator<<(std::ostream& os, const Info& i) {
    return os << "{type " << i.type << ", flags2 0x" << std::hex << i.flags2 << ", flags 0x"
              << i.flags << ", accept 0x" << i.accept << std::dec << "}";
  }
};
Info info(const CANMSG2& m) {
  const auto& b = m.uMsgInfo.Bytes;
  return {b.bType, b.bFlags2, b.bFlags, b.bAccept};
}

CANMSG2 msg(uint32_t id, std::vector<uint8_t> data = {0x11, 0x22}, bool ext = false) {
  CANMSG2 m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bits.type = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = data.size() & 0x0FU;
  m.uMsgInfo.Bits.ext = ext ? 1 : 0;
  std::memcpy(m.abData, data.data(), data.size());
  return m;
}
CANMSG2 with_srr(CANMSG2 m) {
  m.uMsgInfo.Bits.srr = 1;
  return m;
}

Frame remote(uint32_t id, bool ext = false) {
  FrameSpec s;
  s.id = id;
  s.extended = ext;
  s.remote = true;
  s.dlc = 0;
  return *Frame::create(s);
}
Frame classic(uint32_t id, std::vector<uint8_t> data = {0x11, 0x22}, bool ext = false) {
  return testing::frame(id, std::move(data), ext);
}
// Bits from SOF to the end of EOF of a classic frame.
int64_t bits_of(const Frame& f) {
  return frame_duration(encode(f), testing::timing_500k()).ns() / kBit;
}

FilterOp acceptance(uint8_t select, uint32_t code, uint32_t mask) {
  return {FilterOp::Kind::set_acceptance, select, 0, code, mask};
}
FilterOp add_ids(uint8_t select, uint32_t code, uint32_t mask) {
  return {FilterOp::Kind::add_ids, select, 0, code, mask};
}
FilterOp remove_ids(uint8_t select, uint32_t code, uint32_t mask) {
  return {FilterOp::Kind::remove_ids, select, 0, code, mask};
}
FilterOp set_mode(uint8_t select, uint8_t mode) {
  return {FilterOp::Kind::set_mode, select, mode, 0, 0};
}
FilterOp get_mode(uint8_t select) {
  return {FilterOp::Kind::get_mode, select, 0, 0, 0};
}

ixxat::LineInit v1_init(uint8_t op_mode = kOpAll) {
  ixxat::LineInit init;
  init.op_mode = op_mode;
  init.btr0 = CAN_BT0_500KB;
  init.btr1 = CAN_BT1_500KB;
  return init;
}
ixxat::LineInit v2_init(uint8_t sf_mode = CAN_FILTER_INCL, uint8_t ef_mode = CAN_FILTER_INCL) {
  ixxat::LineInit init;
  init.v2 = true;
  init.op_mode = kOpAll;
  init.sf_mode = sf_mode;
  init.ef_mode = ef_mode;
  init.sdr = CAN_BTP_500KB;
  return init;
}

// An SJA1000 station at 500 kbit/s that acknowledges the line's frames once started.
struct Peer : testing::Station<Sja1000Node> {
  using testing::Station<Sja1000Node>::Station;
  void start() {
    HostedNodeSettings s;
    s.btr0 = 0x00;
    s.btr1 = 0x1C;
    testing::Station<Sja1000Node>::start(s);
  }
};

// A line on an SJA1000 with a peer on the same bus (not started unless a test starts it).
struct Rig {
  explicit Rig(const ixxat::Clocks& clocks = {}) : line(b.sched, node, clocks, SimTime{}) {}

  // Control unit opened and the line initialized (v1, 500 kbit/s).
  void init(uint8_t op_mode = kOpAll) {
    ASSERT_EQ(line.open_control(), VCI_OK);
    ASSERT_EQ(line.init_line(v1_init(op_mode)), VCI_OK);
  }
  // A channel opened, initialized with `port` and activated.
  ChannelId channel(Port& port, bool v2 = false, ixxat::ChannelSetup setup = {}) {
    auto id = line.open_channel(false, v2);
    EXPECT_TRUE(id.has_value());
    EXPECT_EQ(line.init_channel(id.value(), setup, &port), VCI_OK);
    EXPECT_EQ(line.activate(*id), VCI_OK);
    return *id;
  }
  // init(), a v1 channel on `port`, the line started and the peer started, all at now.
  ChannelId online(Port& port) {
    init();
    const ChannelId id = channel(port);
    EXPECT_EQ(line.start_line(), VCI_OK);
    peer.start();
    return id;
  }
  void send(Port& port, const CANMSG2& m) {
    port.tx.push_back(m);
    line.tx_ready();
  }
  ixxat::ChannelCounters counters(ChannelId id) const { return line.channel_status(id)->counters; }

  testing::BusFixture b;
  Sja1000Node node{b.sched, b.bus};
  ixxat::CanLine line;
  Peer peer{b};
};

// ---------------------------------------------------------------- control unit

TEST(VciCanLine, CapabilitiesReportTheEmulatedClocksAndFeatures) {
  Rig r;
  const CANCAPABILITIES c = r.line.capabilities();
  EXPECT_EQ(c.wCtrlType, CAN_CTRL_SJA1000);
  EXPECT_EQ(c.wBusCoupling, CAN_BUSC_HIGHSPEED);
  // STDANDEXT RMTFRAME ERRFRAME BUSLOAD IDFILTER LISTONLY SCHEDULER DELAYEDTX SINGLESHOT
  // HIGHPRIOR: 0x2 + 0x4 + 0x8 + 0x10 + 0x20 + 0x40 + 0x80 + 0x200 + 0x400 + 0x800.
  EXPECT_EQ(c.dwFeatures, 0xEFEu);
  EXPECT_EQ(c.dwClockFreq, 1'000'000u);
  EXPECT_EQ(c.dwTscDivisor, 1u);
  EXPECT_EQ(c.dwCmsDivisor, 1000u);
  EXPECT_EQ(c.dwCmsMaxTicks, 0xFFFFu);
  EXPECT_EQ(c.dwDtxDivisor, 1u);
  EXPECT_EQ(c.dwDtxMaxTicks, 0xFFFFu);
  const CANCAPABILITIES2 c2 = r.line.capabilities2();
  EXPECT_EQ(c2.dwFeatures, 0xEFEu);
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
  r.init();
  const ChannelId ch = r.channel(p);
  r.peer.start();
  p.tx = {msg(0x123), msg(0x124)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);  // 0x123 is loaded, its frame has not started
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
  r.init();
  const ChannelId ch = r.channel(p);
  r.peer.start();
  p.tx = {msg(0x123), msg(0x124)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
  ASSERT_EQ(r.line.init_line(v1_init()), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame.id(), 0x124u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
}

TEST(VciCanLine, AFrameOnTheWireAtStopLineCompletes) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.send(p, msg(0x123));
  r.b.run_until(20 * kBit);  // inside the frame
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].at, 62 * kBit);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
}

TEST(VciCanLine, AFrameOnTheWireAtResetLineCompletes) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.send(p, msg(0x123));
  r.b.run_until(20 * kBit);  // inside the frame
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].at, 62 * kBit);
  EXPECT_EQ(r.peer.log.sent.size(), 0u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.counters(ch).dropped, 0u);
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
}

// ---------------------------------------------------------------- channels

TEST(VciCanLine, ExclusiveChannelsExcludeEveryOtherChannel) {
  Rig r;
  auto a = r.line.open_channel(false, false);
  auto b = r.line.open_channel(false, true);
  ASSERT_TRUE(a);
  ASSERT_TRUE(b);
  EXPECT_NE(*a, *b);
  auto denied = r.line.open_channel(true, false);
  ASSERT_FALSE(denied);
  EXPECT_EQ(denied.error(), VCI_E_ACCESSDENIED);
  r.line.close_channel(*a);
  r.line.close_channel(*b);
  auto x = r.line.open_channel(true, true);
  ASSERT_TRUE(x);
  EXPECT_EQ(r.line.open_channel(false, false).error(), VCI_E_ACCESSDENIED);
  EXPECT_EQ(r.line.open_channel(true, false).error(), VCI_E_ACCESSDENIED);
  r.line.close_channel(*x);
  EXPECT_TRUE(r.line.open_channel(false, false));
}

TEST(VciCanLine, ChannelCallsCheckHandleInitializationAndActivity) {
  Rig r;
  Port p, q;
  EXPECT_EQ(r.line.init_channel(99, {}, &p), VCI_E_INVALID_HANDLE);
  EXPECT_EQ(r.line.activate(99), VCI_E_INVALID_HANDLE);
  EXPECT_EQ(r.line.deactivate(99), VCI_E_INVALID_HANDLE);
  EXPECT_FALSE(r.line.channel_status(99));
  const ChannelId id = *r.line.open_channel(false, true);
  const auto fresh = r.line.channel_status(id);
  ASSERT_TRUE(fresh);
  EXPECT_FALSE(fresh->initialized);
  EXPECT_FALSE(fresh->activated);
  EXPECT_EQ(r.line.activate(id), VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(r.line.init_channel(id, {0, CAN_FILTER_VOID}, &p), VCI_E_INVALIDARG);
  EXPECT_EQ(r.line.init_channel(id, {0, CAN_FILTER_PASS | CAN_FILTER_SRRA}, &p), VCI_OK);
  ASSERT_EQ(r.line.activate(id), VCI_OK);
  EXPECT_TRUE(r.line.channel_status(id)->activated);
  EXPECT_EQ(r.line.init_channel(id, {}, &q), VCI_E_INVALID_STATE);
  ASSERT_EQ(r.line.deactivate(id), VCI_OK);
  EXPECT_EQ(r.line.init_channel(id, {}, &q), VCI_OK);
  EXPECT_FALSE(r.line.channel_status(id)->activated);
}

TEST(VciCanLine, AnActiveChannelReceivesNothingWhileTheLineIsNotOnline) {
  Rig r;
  Port p;
  r.init();
  r.channel(p);
  r.peer.start();
  r.peer.send(k123);
  r.b.run_until(1 * kMs);
  EXPECT_TRUE(p.rx.empty());
}

TEST(VciCanLine, ADeactivatedChannelNeitherReceivesNorTransmits) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.line.deactivate(ch), VCI_OK);
  r.send(p, msg(0x201));
  r.peer.send(k123);
  r.b.run_until(2 * kMs);
  EXPECT_EQ(p.rx.size(), 1u);  // the INFO START from before
  EXPECT_EQ(p.tx.size(), 1u);
  ASSERT_EQ(r.peer.log.sent.size(), 1u);
  EXPECT_TRUE(r.peer.log.received.empty());
  ASSERT_EQ(r.line.activate(ch), VCI_OK);  // the transmit FIFO is served again
  r.b.run_until(3 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].at, 2 * kMs + bits_of(classic(0x201)) * kBit);
}

TEST(VciCanLine, ADelayedFrameOfAChannelDeactivatedMeanwhileIsNotSent) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 5000;
  r.send(p, msg(0x123));
  r.send(p, delayed);
  r.b.run_until(1 * kMs);  // 0x124 waits in the firmware for its delay
  EXPECT_TRUE(p.tx.empty());
  ASSERT_EQ(r.line.deactivate(ch), VCI_OK);
  r.b.run_until(10 * kMs);
  ASSERT_EQ(r.line.activate(ch), VCI_OK);
  r.b.run_until(20 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
}

TEST(VciCanLine, TwoChannelsBothReceiveEveryFrame) {
  Rig r;
  Port a, b;
  r.init();
  const ChannelId ca = r.channel(a);
  const ChannelId cb = r.channel(b, true);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(k123);
  r.peer.send(kZero);
  r.b.run_until(1 * kMs);
  for (Port* port : {&a, &b}) {
    ASSERT_EQ(port->data().size(), 2u);
    EXPECT_EQ(port->data()[0].dwTime, 124u);
    EXPECT_EQ(port->data()[1].dwTime, 230u);  // (62 + 3 + 50) bits at 2 us
  }
  EXPECT_EQ(r.counters(ca).received, 3u);  // INFO START and two frames
  EXPECT_EQ(r.counters(cb).received, 3u);
}

TEST(VciCanLine, AReceivedFrameCarriesItsEndOfFrameInTicksAndItsContent) {
  Rig r;
  Port p;
  r.online(p);
  r.peer.send(k123);
  r.b.run_until(10 * kMs);
  r.peer.send(classic(0x1ABCDEF, {1, 2, 3, 4, 5, 6, 7, 8}, true));
  r.peer.send(remote(0x7FF));
  r.b.run_until(20 * kMs);
  const auto d = p.data();
  ASSERT_EQ(d.size(), 3u);
  EXPECT_EQ(d[0].dwTime, 124u);  // 62 bits at 2 us, sent at once from t = 0
  EXPECT_EQ(d[0].dwMsgId, 0x123u);
  EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, 2, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d[0].abData[0], 0x11);
  EXPECT_EQ(d[0].abData[1], 0x22);
  const int64_t ext_bits = bits_of(classic(0x1ABCDEF, {1, 2, 3, 4, 5, 6, 7, 8}, true));
  EXPECT_EQ(d[1].dwTime, static_cast<uint32_t>((10 * kMs + ext_bits * kBit) / kUs));
  EXPECT_EQ(d[1].dwMsgId, 0x1ABCDEFu);
  EXPECT_EQ(info(d[1]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_EXT | 8, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d[1].abData[7], 8);
  const int64_t rtr_end = 10 * kMs + (ext_bits + 3 + bits_of(remote(0x7FF))) * kBit;
  EXPECT_EQ(d[2].dwTime, static_cast<uint32_t>(rtr_end / kUs));
  EXPECT_EQ(d[2].dwMsgId, 0x7FFu);
  EXPECT_EQ(info(d[2]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_RTR, CAN_ACCEPT_FILTER_1}));
}

TEST(VciCanLine, TimeStampsCountFromTheEpochAtTheClockRate) {
  ixxat::Clocks clocks;
  clocks.clock_hz = 8'000'000;
  clocks.tsc_divisor = 4;  // 2 MHz: 0.5 us per tick
  testing::BusFixture b;
  Sja1000Node node(b.sched, b.bus);
  ixxat::CanLine line(b.sched, node, clocks, SimTime::from_ns(-3 * kMs));  // powered on at -3 ms
  Peer peer(b);
  Port p;
  ASSERT_EQ(line.open_control(), VCI_OK);
  ASSERT_EQ(line.init_line(v1_init()), VCI_OK);
  const ChannelId ch = *line.open_channel(false, false);
  ASSERT_EQ(line.init_channel(ch, {}, &p), VCI_OK);
  ASSERT_EQ(line.activate(ch), VCI_OK);
  ASSERT_EQ(line.start_line(), VCI_OK);
  peer.start();
  peer.send(k123);
  b.run_until(1 * kMs);
  ASSERT_EQ(p.rx.size(), 2u);
  EXPECT_EQ(p.rx[0].dwTime, 6000u);                                 // 3 ms at 2 MHz
  EXPECT_EQ(p.rx[1].dwTime, 6000u + 248u);                          // + 124 us
  EXPECT_EQ(line.ticks(SimTime::from_ns(1 * kMs + 1'499)), 8002u);  // whole ticks only
}

TEST(VciCanLine, ARxFifoOverflowDropsTheNewestAndMarksTheNextStoredMessage) {
  Rig r;
  Port p(2);
  const ChannelId ch = r.online(p);
  r.peer.send(classic(0x101));
  r.peer.send(classic(0x102));
  r.peer.send(classic(0x103));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(p.rx.size(), 2u);  // INFO START and 0x101
  EXPECT_EQ(p.rx[1].dwMsgId, 0x101u);
  EXPECT_EQ(p.rx[1].uMsgInfo.Bits.ovr, 0u);
  auto s = *r.line.channel_status(ch);
  EXPECT_TRUE(s.rx_overrun);
  EXPECT_EQ(s.counters.received, 2u);
  EXPECT_EQ(s.counters.lost, 2u);
  p.rx.clear();  // the application reads
  r.peer.send(classic(0x104));
  r.peer.send(classic(0x105));
  r.b.run_until(2 * kMs);
  ASSERT_EQ(p.rx.size(), 2u);
  EXPECT_EQ(p.rx[0].dwMsgId, 0x104u);
  EXPECT_EQ(info(p.rx[0]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_OVR | 2, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(p.rx[1].uMsgInfo.Bits.ovr, 0u);
  EXPECT_TRUE(r.line.channel_status(ch)->rx_overrun);  // sticky
  ASSERT_EQ(r.line.deactivate(ch), VCI_OK);
  ASSERT_EQ(r.line.init_channel(ch, {}, &p), VCI_OK);
  s = *r.line.channel_status(ch);
  EXPECT_FALSE(s.rx_overrun);
  EXPECT_EQ(s.counters.lost, 0u);
  EXPECT_EQ(s.counters.received, 0u);
}

TEST(VciCanLine, FramesOfAFormatTheLineWasNotInitializedForAreNeitherReceivedNorSent) {
  Rig r;
  Port p;
  r.init(CAN_OPMODE_STANDARD);
  const ChannelId ch = r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(classic(0x100, {1}, true));
  r.peer.send(classic(0x101, {1}));
  r.send(p, msg(0x200, {1}, true));
  r.send(p, msg(0x201, {1}));
  r.b.run_until(1 * kMs);
  EXPECT_EQ(p.data_ids(), std::vector<uint32_t>{0x101});
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame.id(), 0x201u);
  EXPECT_FALSE(r.peer.log.received[0].frame.extended());
  EXPECT_EQ(r.counters(ch).rejected, 1u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_TRUE(p.tx.empty());
}

TEST(VciCanLine, TransmitMessagesThatAreNotDataAreDroppedAndCounted) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  CANMSG2 bad = msg(0x100);
  bad.uMsgInfo.Bits.type = CAN_MSGTYPE_INFO;
  CANMSG2 fd = msg(0x101);  // no CAN FD on an SJA1000
  fd.uMsgInfo.Bits.edl = 1;
  r.send(p, bad);
  r.send(p, fd);
  r.send(p, msg(0x123));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.peer.log.received[0].at, 62 * kBit);
  EXPECT_EQ(r.counters(ch).rejected, 2u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
}

// ---------------------------------------------------------------- transmission

TEST(VciCanLine, AFrameFromTheTransmitFifoGoesOutAtOnceAndIsCounted) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.send(p, msg(0x123));
  EXPECT_EQ(r.line.line_status().dwStatus, static_cast<uint32_t>(CAN_STATUS_TXPEND));
  EXPECT_TRUE(p.tx.empty());
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.peer.log.received[0].at, 62 * kBit);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
  EXPECT_TRUE(p.data().empty());  // no srr: no echo
}

TEST(VciCanLine, ADelayedFrameIsHandedOverDwTimeTicksAfterThePreviousOne) {
  Rig r;
  Port p;
  std::vector<BusEvent> events;
  r.b.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  r.init();
  const ChannelId ch = r.channel(p);
  r.peer.start();
  CANMSG2 first = msg(0x123);
  first.dwTime = 5000;  // the first frame after the start is not delayed
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 1000;
  p.tx = {first, delayed, msg(0x125)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].start.ns(), 0);
  // 1000 ticks after 0x123 was handed over (not after it ended at 124 us).
  EXPECT_EQ(events[1].start.ns(), 1000 * kUs);
  EXPECT_EQ(events[1].frame->id(), 0x124u);
  EXPECT_EQ(events[2].start.ns(), events[1].end.ns() + 3 * kBit);  // no delay: after the IFS
  EXPECT_EQ(r.counters(ch).sent, 3u);
}

TEST(VciCanLine, ATransmitDelayAboveTheMaximumIsClamped) {
  ixxat::Clocks clocks;
  clocks.dtx_max_ticks = 300;
  Rig r(clocks);
  Port p;
  std::vector<BusEvent> events;
  r.b.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  r.init();
  r.channel(p);
  r.peer.start();
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 60000;
  p.tx = {msg(0x123), delayed};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].start.ns(), 300 * kUs);
}

TEST(VciCanLine, TheFirstFrameAfterARestartIsNotDelayed) {
  Rig r;
  Port p;
  std::vector<BusEvent> events;
  r.b.bus.on_bus_event = [&](const BusEvent& e) { events.push_back(e); };
  r.online(p);
  r.send(p, msg(0x123));
  r.b.run_until(200 * kUs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 1000;
  p.tx.push_back(delayed);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].start.ns(), 200 * kUs);
}

TEST(VciCanLine, ASingleShotFrameThatLosesArbitrationIsNotRetriedNorEchoed) {
  Rig r;
  Port p;
  r.init();
  const ChannelId ch = r.channel(p);
  r.peer.start();
  r.peer.send(kZero);  // identifier 0 wins
  CANMSG2 m = with_srr(msg(0x123));
  m.uMsgInfo.Bits.ssm = 1;
  p.tx = {m};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(10 * kMs);
  EXPECT_TRUE(r.peer.log.received.empty());
  EXPECT_EQ(r.b.bus.stats(r.node.node()).arbitration_lost, 1u);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
  EXPECT_EQ(r.counters(ch).sent, 0u);
  ASSERT_EQ(p.data().size(), 1u);  // the peer's frame, no echo
  EXPECT_EQ(p.data()[0].dwMsgId, 0u);
  EXPECT_EQ(p.data()[0].dwTime, 100u);  // 50 bits
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
}

TEST(VciCanLine, ASingleShotFrameWithoutAcknowledgeIsGivenUpAfterOneAttempt) {
  Rig r;  // the peer stays off the bus: nobody acknowledges
  Port p;
  r.init();
  const ChannelId ch = r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  CANMSG2 m = msg(0x123);
  m.uMsgInfo.Bits.ssm = 1;
  r.send(p, m);
  r.b.run_until(10 * kMs);
  const auto errors = p.of_type(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].dwTime, 108u);  // ACK slot: bit 53, detected at its end, 54 bits
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_ACK);
  EXPECT_EQ(errors[0].abData[1], CAN_STATUS_TXPEND);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
  EXPECT_EQ(r.counters(ch).sent, 0u);
  EXPECT_EQ(r.line.controller_state().tec, 8);
  EXPECT_EQ(r.line.line_status().dwStatus, 0u);
}

TEST(VciCanLine, AHighPriorityFrameOfAnotherChannelGoesFirst) {
  Rig r;
  Port a, b;
  r.init();
  r.channel(a);
  r.channel(b);
  r.peer.start();
  CANMSG2 h = msg(0x303);
  h.uMsgInfo.Bits.hpm = 1;
  a.tx = {msg(0x301), msg(0x302)};
  b.tx = {h};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(2 * kMs);
  std::vector<uint32_t> order;
  for (const auto& item : r.peer.log.received) {
    order.push_back(item.frame.id());
  }
  EXPECT_EQ(order, (std::vector<uint32_t>{0x303, 0x301, 0x302}));
}

TEST(VciCanLine, AHighPriorityFrameNeverOvertakesFramesAheadOfItInItsFifo) {
  Rig r;
  Port a, b;
  r.init();
  r.channel(a);
  r.channel(b);
  r.peer.start();
  CANMSG2 h = msg(0x302);
  h.uMsgInfo.Bits.hpm = 1;
  a.tx = {msg(0x301), h};
  b.tx = {msg(0x303)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(2 * kMs);
  std::vector<uint32_t> order;
  for (const auto& item : r.peer.log.received) {
    order.push_back(item.frame.id());
  }
  // 0x302 overtakes the other channel's 0x303, not 0x301 before it.
  EXPECT_EQ(order, (std::vector<uint32_t>{0x301, 0x302, 0x303}));
}

TEST(VciCanLine, TheDistributorServesTheChannelsRoundRobin) {
  Rig r;
  Port a, b;
  r.init();
  const ChannelId ca = r.channel(a);
  const ChannelId cb = r.channel(b);
  r.peer.start();
  a.tx = {msg(0x101), msg(0x102), msg(0x103), msg(0x104)};
  b.tx = {msg(0x201), msg(0x202)};
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(5 * kMs);
  std::vector<uint32_t> order;
  for (const auto& item : r.peer.log.received) {
    order.push_back(item.frame.id());
  }
  EXPECT_EQ(order, (std::vector<uint32_t>{0x101, 0x201, 0x102, 0x202, 0x103, 0x104}));
  EXPECT_EQ(r.counters(ca).sent, 4u);
  EXPECT_EQ(r.counters(cb).sent, 2u);
}

// ---------------------------------------------------------------- self reception

TEST(VciCanLine, V1ChannelsReceiveEveryEchoWithSrrSet) {
  Rig r;
  Port a, b;
  r.init();
  r.channel(a);
  r.channel(b);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.send(a, with_srr(msg(0x123)));
  r.b.run_until(1 * kMs);
  for (Port* port : {&a, &b}) {
    const auto d = port->data();
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].dwTime, 124u);  // the end of the frame's transmission
    EXPECT_EQ(d[0].dwMsgId, 0x123u);
    EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_SRR | 2, CAN_ACCEPT_ALWAYS}));
    EXPECT_EQ(d[0].abData[1], 0x22);
  }
  EXPECT_EQ(r.peer.log.received.size(), 1u);
}

TEST(VciCanLine, AV2ChannelGetsItsOwnEchoEvenWithLockButNotOthersWithoutSrra) {
  Rig r;
  Port x, y;
  r.init();
  r.channel(x, true, {0, CAN_FILTER_LOCK});
  r.channel(y, true, {0, CAN_FILTER_PASS});
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.send(x, with_srr(msg(0x123)));
  r.send(y, msg(0x124));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(x.data().size(), 1u);
  EXPECT_EQ(x.data()[0].dwTime, 124u);
  EXPECT_EQ(info(x.data()[0]),
            (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_SRR | 2, CAN_ACCEPT_ALWAYS}));
  EXPECT_TRUE(y.data().empty());
  EXPECT_EQ(r.peer.log.received.size(), 2u);
}

TEST(VciCanLine, AV2ChannelWithSrraGetsOthersEchoesThroughItsFilterWithSrrCleared) {
  Rig r;
  Port x, y;
  r.init();
  r.channel(x);
  const ChannelId cy = r.channel(y, true, {0, CAN_FILTER_INCL | CAN_FILTER_SRRA});
  ASSERT_EQ(r.line.deactivate(cy), VCI_OK);
  ASSERT_EQ(
      r.line.filter(cy, acceptance(CAN_FILTER_STD, ixxat::filter_value(0x123, false), kStdMask)).hr,
      VCI_OK);
  ASSERT_EQ(r.line.activate(cy), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.send(x, with_srr(msg(0x123)));
  r.send(x, with_srr(msg(0x124)));
  r.b.run_until(1 * kMs);
  const auto d = y.data();
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].dwMsgId, 0x123u);
  EXPECT_EQ(d[0].dwTime, 124u);
  EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, 2, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(x.data().size(), 2u);
}

TEST(VciCanLine, AFrameSentWithoutSrrIsInvisibleToEveryChannel) {
  Rig r;
  Port a, b, c;
  r.init();
  r.channel(a);
  r.channel(b);
  r.channel(c, true, {0, CAN_FILTER_PASS | CAN_FILTER_SRRA});
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.send(a, msg(0x123));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_TRUE(a.data().empty());
  EXPECT_TRUE(b.data().empty());
  EXPECT_TRUE(c.data().empty());
}

TEST(VciCanLine, EchoesBypassTheControlUnitFilter) {
  Rig r;
  Port a, b;
  r.init();
  ASSERT_EQ(
      r.line.filter(std::nullopt, acceptance(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE))
          .hr,
      VCI_OK);
  r.channel(a);
  r.channel(b);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.send(a, with_srr(msg(0x123)));
  r.peer.send(classic(0x456));
  r.b.run_until(1 * kMs);
  EXPECT_EQ(a.data_ids(), std::vector<uint32_t>{0x123});
  EXPECT_EQ(b.data_ids(), std::vector<uint32_t>{0x123});
}

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
  FaultRule rule;
  rule.match.transmitter = r.node.node();
  rule.fault.error = CanErrorType::bit;
  rule.count = 32;
  r.b.plan.add(rule);
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
  // Stop and start: recovery takes 128 x 11 recessive bits on the idle bus, then the frame goes.
  p.rx.clear();
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
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
    FaultRule rule;
    rule.match.transmitter = peer;
    rule.fault.error = type;
    rule.fault.bit = type == CanErrorType::stuff ? std::optional<uint16_t>(30) : std::nullopt;
    rule.count = 1;
    r.b.plan.add(rule);
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

TEST(VciCanLine, WithTheAcceptanceFilterClosedOnlyListedIdsPassWithFilter2) {
  Rig r;
  Port p;
  r.init();
  ASSERT_EQ(
      r.line.filter(std::nullopt, acceptance(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE))
          .hr,
      VCI_OK);
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
  ASSERT_EQ(
      r.line.filter(std::nullopt, acceptance(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE))
          .hr,
      VCI_OK);
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

// ---------------------------------------------------------------- CAN FD

// The CAN FD controller at 500 kbit/s nominal and 2 Mbit/s data, as CANBTP in bit/s form: on
// the 80 MHz clock prescaler 10 with 16 quanta, and prescaler 4 with 10 quanta.
const CANBTP kSdr{0, 500'000, 14, 2, 1, 0};
const CANBTP kFdr{0, 2'000'000, 8, 2, 1, 0};

BitTiming fd_timing(const CANBTP& b, const ixxat::BtpRange& range, ixxat::Phase phase) {
  return *ixxat::decode_btp({b.dwMode, b.dwBPS, b.wTS1, b.wTS2, b.wSJW, b.wTDO}, range, phase);
}

struct FdRig {
  FdRig() : line(b.sched, node, ixxat::Clocks{}, SimTime{}) {
    HostedNodeSettings s;
    s.nominal = nominal;
    s.data = data;
    peer.start(s);
  }
  ixxat::LineInit init() const {
    ixxat::LineInit i;
    i.v2 = true;
    i.op_mode = kOpAll;
    i.ex_mode = CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA;
    i.sdr = kSdr;
    i.fdr = kFdr;
    return i;
  }
  ChannelId channel(Port& port, bool v2) {
    const ChannelId id = *line.open_channel(false, v2);
    EXPECT_EQ(line.init_channel(id, {0, CAN_FILTER_PASS}, &port), VCI_OK);
    EXPECT_EQ(line.activate(id), VCI_OK);
    return id;
  }
  void send(Port& port, const CANMSG2& m) {
    port.tx.push_back(m);
    line.tx_ready();
  }
  int64_t duration(const Frame& f) const { return frame_duration(encode(f), nominal, data).ns(); }

  BitTiming nominal = fd_timing(kSdr, ixxat::kFdNominalRange, ixxat::Phase::nominal);
  BitTiming data = fd_timing(kFdr, ixxat::kFdDataRange, ixxat::Phase::data);
  testing::BusFixture b;
  CanFdNode node{b.sched, b.bus};
  ixxat::CanLine line;
  testing::Station<CanFdNode> peer{b};
};

Frame fd(uint32_t id, std::size_t length, bool brs) {
  std::vector<uint8_t> data(length);
  for (std::size_t k = 0; k < length; ++k) {
    data[k] = static_cast<uint8_t>(k + 1);
  }
  return *Frame::fd_frame(id, data, false, brs);
}

TEST(VciCanLine, AnFdLineInitializedThroughV2ReportsItsTimingAndCapabilities) {
  FdRig r;
  EXPECT_TRUE(r.line.fd_controller());
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(r.init()), VCI_OK);
  const CANLINESTATUS2 s = r.line.line_status2();
  EXPECT_EQ(s.bOpMode, kOpAll);
  EXPECT_EQ(s.bExMode, CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  EXPECT_EQ(s.sBtpSdr.dwBPS, 500'000u);  // as given, in bit/s form
  EXPECT_EQ(s.sBtpSdr.wTS1, 14);
  EXPECT_EQ(s.sBtpFdr.dwBPS, 2'000'000u);
  EXPECT_EQ(s.sBtpFdr.wTS1, 8);
  EXPECT_EQ(s.dwStatus, static_cast<uint32_t>(CAN_STATUS_ININIT));
  const CANCAPABILITIES2 c = r.line.capabilities2();
  EXPECT_EQ(c.wCtrlType, CAN_CTRL_IFICFD);
  EXPECT_EQ(c.dwFeatures, 0xEEFEu);  // the classic set + EXTDATA, FASTDATA, ISOFRAME
  EXPECT_EQ(c.dwCanClkFreq, 80'000'000u);
  EXPECT_EQ(c.sFdrRangeMax.dwBPS, 32u);
  EXPECT_EQ(r.nominal.bits_duration(1).ns(), kBit);
  EXPECT_EQ(r.data.bits_duration(1).ns(), 500);
}

TEST(VciCanLine, FdFramesReachV2ChannelsAndV1ChannelsOnlyUpTo8Bytes) {
  FdRig r;
  Port v2, v1;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(r.init()), VCI_OK);
  const ChannelId c2 = r.channel(v2, true);
  const ChannelId c1 = r.channel(v1, false);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  const Frame big = fd(0x100, 64, false);
  const Frame small = fd(0x101, 8, true);
  r.peer.send(big);
  r.peer.send(small);
  r.peer.send(k123);
  r.b.run_until(2 * kMs);
  const int64_t t_big = r.duration(big);
  const int64_t t_small = t_big + 3 * kBit + r.duration(small);
  const int64_t t_classic = t_small + 3 * kBit + 62 * kBit;
  const auto d2 = v2.data();
  ASSERT_EQ(d2.size(), 3u);
  EXPECT_EQ(d2[0].dwMsgId, 0x100u);
  EXPECT_EQ(d2[0].dwTime, static_cast<uint32_t>(t_big / kUs));
  EXPECT_EQ(info(d2[0]), (Info{CAN_MSGTYPE_DATA, CAN_MSGFLAGS2_EDL, 15, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d2[0].abData[63], 64);
  EXPECT_EQ(d2[1].dwTime, static_cast<uint32_t>(t_small / kUs));
  EXPECT_EQ(info(d2[1]), (Info{CAN_MSGTYPE_DATA, CAN_MSGFLAGS2_EDL | CAN_MSGFLAGS2_FDR, 8,
                               CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d2[2].dwTime, static_cast<uint32_t>(t_classic / kUs));
  const auto d1 = v1.data();
  ASSERT_EQ(d1.size(), 2u);
  EXPECT_EQ(d1[0].dwMsgId, 0x101u);
  EXPECT_EQ(info(d1[0]), (Info{CAN_MSGTYPE_DATA, CAN_MSGFLAGS2_EDL | CAN_MSGFLAGS2_FDR, 8,
                               CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d1[0].abData[7], 8);
  EXPECT_EQ(d1[1].dwMsgId, 0x123u);
  EXPECT_EQ(r.line.channel_status(c1)->counters.not_shown, 1u);
  EXPECT_EQ(r.line.channel_status(c2)->counters.not_shown, 0u);
}

TEST(VciCanLine, AnFdLineSendsFdFramesAndFdrAloneAsksForTheRateSwitch) {
  FdRig r;
  Port p;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(r.init()), VCI_OK);
  const ChannelId ch = r.channel(p, true);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  CANMSG2 a = msg(0x200, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  a.uMsgInfo.Bits.dlc = 9;  // 12 bytes
  a.uMsgInfo.Bits.edl = 1;
  a.uMsgInfo.Bits.fdr = 1;
  CANMSG2 b = msg(0x201, {0x55});
  b.uMsgInfo.Bits.fdr = 1;
  CANMSG2 c = msg(0x202, {1, 2});
  c.uMsgInfo.Bits.edl = 1;
  c.uMsgInfo.Bits.rtr = 1;  // ignored on FD frames
  r.send(p, a);
  r.send(p, b);
  r.send(p, c);
  r.b.run_until(2 * kMs);
  const auto& got = r.peer.log.received;
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].frame.id(), 0x200u);
  EXPECT_TRUE(got[0].frame.fd());
  EXPECT_TRUE(got[0].frame.brs());
  EXPECT_EQ(got[0].frame.length(), 12u);
  EXPECT_EQ(got[0].frame.data()[11], 12);
  EXPECT_EQ(got[0].at, r.duration(got[0].frame));
  EXPECT_TRUE(got[1].frame.fd());
  EXPECT_TRUE(got[1].frame.brs());
  EXPECT_EQ(got[1].frame.length(), 1u);
  EXPECT_TRUE(got[2].frame.fd());
  EXPECT_FALSE(got[2].frame.brs());
  EXPECT_FALSE(got[2].frame.remote());
  EXPECT_EQ(got[2].frame.length(), 2u);
  EXPECT_EQ(r.line.channel_status(ch)->counters.sent, 3u);
}

TEST(VciCanLine, AnFdLineLeavesBusOffAfterARestartAndSendsItsFrameOnce) {
  FdRig r;
  Port p;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(r.init()), VCI_OK);
  const ChannelId ch = r.channel(p, true);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  FaultRule rule;
  rule.match.transmitter = r.node.node();
  rule.fault.error = CanErrorType::bit;
  rule.count = 32;
  r.b.plan.add(rule);
  CANMSG2 m = msg(0x200, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  m.uMsgInfo.Bits.dlc = 9;
  m.uMsgInfo.Bits.edl = 1;
  m.uMsgInfo.Bits.fdr = 1;
  r.send(p, m);
  r.b.run_until(100 * kMs);
  EXPECT_EQ(r.line.controller_state().state, ErrorState::bus_off);
  EXPECT_EQ(p.of_type(CAN_MSGTYPE_ERROR).size(), 32u);
  EXPECT_TRUE(r.peer.log.received.empty());
  p.rx.clear();
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(200 * kMs);
  const int64_t recovered = 100 * kMs + 128 * 11 * kBit;
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].at, recovered + r.duration(r.peer.log.received[0].frame));
  EXPECT_EQ(r.peer.log.received[0].frame.length(), 12u);
  EXPECT_EQ(r.line.channel_status(ch)->counters.sent, 1u);
  const auto status = p.of_type(CAN_MSGTYPE_STATUS);
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].dwTime, static_cast<uint32_t>(recovered / kUs));
  EXPECT_EQ(r.line.line_status2().dwStatus, 0u);
}

TEST(VciCanLine, ABitErrorInTheFastDataPhaseIsReportedAsABitError) {
  FdRig r;
  Port p;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.init_line(r.init()), VCI_OK);
  r.channel(p, true);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  FaultRule rule;
  rule.match.transmitter = r.node.node();
  rule.fault.error = CanErrorType::bit;
  rule.fault.bit = 40;  // in the data field of a 12-byte frame
  rule.count = 1;
  r.b.plan.add(rule);
  CANMSG2 m = msg(0x200, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  m.uMsgInfo.Bits.dlc = 9;
  m.uMsgInfo.Bits.fdr = 1;
  r.send(p, m);
  r.b.run_until(2 * kMs);
  const auto errors = p.of_type(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_BIT);
  EXPECT_EQ(errors[0].abData[1], CAN_STATUS_TXPEND);
  ASSERT_EQ(r.peer.log.received.size(), 1u);  // the retransmission
  // Detected at the end of bit 40: the 40 bits before it with the rate switch, then the bus
  // engine switches back to the nominal rate at the erroneous bit (docs/bus-engine.md).
  const int64_t at =
      frame_prefix_duration(encode(r.peer.log.received[0].frame), r.nominal, r.data, 40).ns() +
      kBit;
  EXPECT_EQ(errors[0].dwTime, static_cast<uint32_t>(at / kUs));
}

TEST(VciCanLine, InitLineRefusesModesAndTimingsTheControllerDoesNotHave) {
  Rig classic_line;
  ASSERT_EQ(classic_line.line.open_control(), VCI_OK);
  ixxat::LineInit fd_modes = v2_init();
  fd_modes.ex_mode = CAN_EXMODE_EXTDATA;
  EXPECT_EQ(classic_line.line.init_line(fd_modes), VCI_E_INVALIDARG);
  EXPECT_EQ(classic_line.line.init_line(v1_init(CAN_OPMODE_STANDARD | CAN_OPMODE_LOWSPEED)),
            VCI_E_INVALIDARG);
  EXPECT_EQ(classic_line.line.init_line(v1_init(CAN_OPMODE_STANDARD | CAN_OPMODE_AUTOBAUD)),
            VCI_E_INVALIDARG);
  ixxat::LineInit bad_rate = v2_init();
  bad_rate.sdr = CANBTP{0, 300'000, 14, 2, 1, 0};  // 8 MHz / (300 kbit/s x 16) is no prescaler
  EXPECT_EQ(classic_line.line.init_line(bad_rate), VCI_E_INVALIDARG);
  ixxat::LineInit bad_filter = v2_init(CAN_FILTER_VOID);
  EXPECT_EQ(classic_line.line.init_line(bad_filter), VCI_E_INVALIDARG);
  EXPECT_EQ(classic_line.line.state(), ixxat::LineState::not_initialized);
  // The bit/s form on the SJA1000 gives the registers of the BTR table.
  ASSERT_EQ(classic_line.line.init_line(v2_init()), VCI_OK);
  EXPECT_EQ(classic_line.line.line_status().bBtReg0, CAN_BT0_500KB);
  EXPECT_EQ(classic_line.line.line_status().bBtReg1, CAN_BT1_500KB);

  FdRig fd_line;
  ASSERT_EQ(fd_line.line.open_control(), VCI_OK);
  ixxat::LineInit noniso = fd_line.init();
  noniso.ex_mode |= CAN_EXMODE_NONISO;
  EXPECT_EQ(fd_line.line.init_line(noniso), VCI_E_INVALIDARG);
  ixxat::LineInit bad_data = fd_line.init();
  bad_data.fdr = CANBTP{0, 3'000'000, 8, 2, 1, 0};
  EXPECT_EQ(fd_line.line.init_line(bad_data), VCI_E_INVALIDARG);
  EXPECT_EQ(fd_line.line.state(), ixxat::LineState::not_initialized);
}

// ---------------------------------------------------------------- cyclic transmit list

CANCYCLICTXMSG2 cyclic(uint32_t id, uint16_t cycle, uint8_t incr = CAN_CTXMSG_INC_NO,
                       uint8_t index = 0, std::vector<uint8_t> data = {0x11, 0x22},
                       bool ext = false) {
  CANCYCLICTXMSG2 m{};
  m.wCycleTime = cycle;
  m.bIncrMode = incr;
  m.bByteIndex = index;
  m.dwMsgId = id;
  m.uMsgInfo.Bits.type = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = data.size() & 0x0FU;
  m.uMsgInfo.Bits.ext = ext ? 1 : 0;
  std::memcpy(m.abData, data.data(), data.size());
  return m;
}

// A rig with the line online, the peer started and the bus's frames recorded.
struct ListRig : Rig {
  ListRig() {
    b.bus.on_bus_event = [this](const BusEvent& e) {
      if (e.kind == BusEvent::Kind::frame) {
        frames.push_back(e);
      }
    };
    online(port);
    EXPECT_EQ(line.open_scheduler(), VCI_OK);
  }
  // Start of frame instants of `id`, in list ticks (ms).
  std::vector<int64_t> ticks_of(uint32_t id) const {
    std::vector<int64_t> out;
    for (const BusEvent& e : frames) {
      if (e.frame->id() == id) {
        EXPECT_EQ(e.start.ns() % kMs, 0) << e.start.ns();
        out.push_back(e.start.ns() / kMs);
      }
    }
    return out;
  }
  Port port;
  std::vector<BusEvent> frames;
};

TEST(VciCanLine, CollidingCyclicEntriesShiftToTheNextFreeTickAndKeepTheirRhythm) {
  ListRig r;
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 2));
  const uint32_t b = *r.line.scheduler_add(cyclic(0x200, 3));
  EXPECT_EQ(a, 0u);
  EXPECT_EQ(b, 1u);
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(b, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(20 * kMs + 500 * kUs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 6, 8, 10, 12, 14, 16, 18, 20}));
  // The older entry wins the ties at 6, 12 and 18; the cycle-3 entry goes one tick later.
  EXPECT_EQ(r.ticks_of(0x200), (std::vector<int64_t>{3, 7, 9, 13, 15, 19}));
}

TEST(VciCanLine, TheTaskIsStoppedAfterOpeningAndResumeStartsEveryStartedEntryTogether) {
  ListRig r;
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 4));
  const uint32_t b = *r.line.scheduler_add(cyclic(0x200, 4));
  const uint32_t idle = *r.line.scheduler_add(cyclic(0x300, 1));
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_DONE);  // added, not started
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(b, 0), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(10 * kMs);
  EXPECT_TRUE(r.frames.empty());
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  r.b.run_until(19 * kMs);  // frames are recorded at their start of frame
  // Both due in tick 4 after the resume at 10 ms: the older goes, the other in the next tick.
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{14, 18}));
  EXPECT_EQ(r.ticks_of(0x200), (std::vector<int64_t>{15, 19}));  // due 18, a goes then
  EXPECT_TRUE(r.ticks_of(0x300).empty());
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[idle], CAN_CTXMSG_STAT_DONE);
}

TEST(VciCanLine, AnEntryStartedWhileTheTaskRunsCountsItsCycleFromThatMoment) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(5 * kMs + 300 * kUs);
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 3));
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  r.b.run_until(15 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{8, 11, 14}));
}

TEST(VciCanLine, StartMessageWithACountSendsExactlyThatManyFrames) {
  ListRig r;
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 2));
  ASSERT_EQ(r.line.scheduler_start(a, 3), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(5 * kMs + 500 * kUs);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(20 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 6}));
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_DONE);
  // Started again, it sends again; stopped, it stops.
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  r.b.run_until(25 * kMs);
  ASSERT_EQ(r.line.scheduler_stop(a), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_DONE);
  r.b.run_until(40 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 6, 22, 24}));
}

TEST(VciCanLine, IncrementsApplyAfterEachFrameAndWrap) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(cyclic(0x7FE, 1, CAN_CTXMSG_INC_ID)), 3),
            VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(
                *r.line.scheduler_add(cyclic(0x1FFFFFFF, 4, CAN_CTXMSG_INC_ID, 0, {1}, true)), 2),
            VCI_OK);
  ASSERT_EQ(
      r.line.scheduler_start(
          *r.line.scheduler_add(cyclic(0x300, 4, CAN_CTXMSG_INC_8, 1, {0xAA, 0xFE, 0x00})), 3),
      VCI_OK);
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(cyclic(0x400, 4, CAN_CTXMSG_INC_16, 1,
                                                                {0xAA, 0xFE, 0xFF, 0x07})),
                                   3),
            VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(30 * kMs);
  std::vector<uint32_t> ids;
  std::vector<std::vector<uint8_t>> data8, data16;
  std::vector<uint32_t> ext_ids;
  for (const BusEvent& e : r.frames) {
    const auto d = e.frame->data();
    if (e.frame->extended()) {
      ext_ids.push_back(e.frame->id());
    } else if (e.frame->id() == 0x300) {
      data8.emplace_back(d.begin(), d.end());
    } else if (e.frame->id() == 0x400) {
      data16.emplace_back(d.begin(), d.end());
    } else {
      ids.push_back(e.frame->id());
    }
  }
  EXPECT_EQ(ids, (std::vector<uint32_t>{0x7FE, 0x7FF, 0x000}));  // wraps at 2048
  EXPECT_EQ(ext_ids, (std::vector<uint32_t>{0x1FFFFFFF, 0x0}));  // wraps at 2^29
  using Bytes = std::vector<std::vector<uint8_t>>;
  EXPECT_EQ(data8, (Bytes{{0xAA, 0xFE, 0x00}, {0xAA, 0xFF, 0x00}, {0xAA, 0x00, 0x00}}));
  // Little-endian 16 bits at byte 1: 0xFFFE, 0xFFFF, then 0 (byte 3 is not touched).
  EXPECT_EQ(data16,
            (Bytes{{0xAA, 0xFE, 0xFF, 0x07}, {0xAA, 0xFF, 0xFF, 0x07}, {0xAA, 0x00, 0x00, 0x07}}));
}

TEST(VciCanLine, SixteenBitIncrementsCarryIntoTheHighByte) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_start(
                *r.line.scheduler_add(cyclic(0x400, 1, CAN_CTXMSG_INC_16, 0, {0xFF, 0x00})), 2),
            VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(r.frames.size(), 2u);
  EXPECT_EQ(r.frames[1].frame->data()[0], 0x00);
  EXPECT_EQ(r.frames[1].frame->data()[1], 0x01);
}

TEST(VciCanLine, AddMessageChecksCycleTypeIncrementAndRoom) {
  ListRig r;
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 0)).error(), VCI_E_INVALIDARG);
  ixxat::Clocks small;
  small.cms_max_ticks = 24;
  Rig limited(small);
  ASSERT_EQ(limited.line.open_scheduler(), VCI_OK);
  EXPECT_EQ(limited.line.scheduler_add(cyclic(0x100, 25)).error(), VCI_E_INVALIDARG);
  EXPECT_TRUE(limited.line.scheduler_add(cyclic(0x100, 24)).has_value());
  CANCYCLICTXMSG2 info_msg = cyclic(0x100, 5);
  info_msg.uMsgInfo.Bits.type = CAN_MSGTYPE_INFO;
  EXPECT_EQ(r.line.scheduler_add(info_msg).error(), VCI_E_INVALIDARG);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x800, 5)).error(), VCI_E_INVALIDARG);  // not 11-bit
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 5, 4)).error(), VCI_E_INVALIDARG);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 5, CAN_CTXMSG_INC_8, 2)).error(),
            VCI_E_INVALIDARG);  // 2 bytes: index 0..1
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x100, 5, CAN_CTXMSG_INC_16, 1)).error(),
            VCI_E_INVALIDARG);  // index 0 only
  for (uint32_t k = 0; k < CAN_MAX_CTX_MSGS; ++k) {
    EXPECT_EQ(r.line.scheduler_add(cyclic(0x100 + k, 5, CAN_CTXMSG_INC_16, 0)).value(), k);
  }
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x120, 5)).error(), VCI_E_OUTOFMEMORY);
  ASSERT_EQ(r.line.scheduler_remove(7), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[7], CAN_CTXMSG_STAT_EMPTY);
  EXPECT_EQ(r.line.scheduler_remove(7), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_start(7, 0), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_stop(7), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_start(16, 0), VCI_E_INVALID_INDEX);
  EXPECT_EQ(r.line.scheduler_add(cyclic(0x120, 5)).value(), 7u);  // the free index again
}

TEST(VciCanLine, SuspendStopsTheListResumeRestartsItAndResetEmptiesIt) {
  ListRig r;
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 2));
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(5 * kMs);
  ASSERT_EQ(r.line.scheduler_suspend(), VCI_OK);
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(11 * kMs);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(15 * kMs + 500 * kUs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 4, 13, 15}));
  ASSERT_EQ(r.line.scheduler_reset(), VCI_OK);
  const CANSCHEDULERSTATUS s = r.line.scheduler_status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  for (uint8_t stat : s.abMsgStat) {
    EXPECT_EQ(stat, CAN_CTXMSG_STAT_EMPTY);
  }
  r.b.run_until(30 * kMs);
  EXPECT_EQ(r.frames.size(), 4u);
}

TEST(VciCanLine, TheListIsExclusiveAndKeepsItsEntriesWhenReopened) {
  ListRig r;
  EXPECT_EQ(r.line.open_scheduler(), VCI_E_ACCESSDENIED);
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 2));
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(3 * kMs);
  r.line.close_scheduler();
  EXPECT_FALSE(r.line.scheduler_open());
  ASSERT_EQ(r.line.open_scheduler(), VCI_OK);  // the task is off again, the entry kept
  EXPECT_EQ(r.line.scheduler_status().bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(r.line.scheduler_status().abMsgStat[a], CAN_CTXMSG_STAT_BUSY);
  r.b.run_until(10 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2}));
}

TEST(VciCanLine, TheListKeepsItsRhythmButSendsNothingWhileTheLineIsOffline) {
  ListRig r;
  const uint32_t a = *r.line.scheduler_add(cyclic(0x100, 2));
  ASSERT_EQ(r.line.scheduler_start(a, 0), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(3 * kMs);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  r.b.run_until(7 * kMs);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.b.run_until(11 * kMs);
  EXPECT_EQ(r.ticks_of(0x100), (std::vector<int64_t>{2, 8, 10}));
}

TEST(VciCanLine, CyclicFramesWithSrrAreEchoedWithSrrToV1ChannelsAndV2ChannelsWithSrra) {
  ListRig r;
  Port v2, srra;
  r.channel(v2, true, {0, CAN_FILTER_PASS});
  r.channel(srra, true, {0, CAN_FILTER_PASS | CAN_FILTER_SRRA});
  CANCYCLICTXMSG2 m = cyclic(0x123, 1);
  m.uMsgInfo.Bits.srr = 1;
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(m), 1), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(3 * kMs);
  ASSERT_EQ(r.port.data().size(), 1u);
  EXPECT_EQ(r.port.data()[0].dwTime, 1124u);  // sent at 1 ms, 62 bits
  EXPECT_EQ(r.port.data()[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_TRUE(v2.data().empty());
  ASSERT_EQ(srra.data().size(), 1u);
  EXPECT_EQ(srra.data()[0].uMsgInfo.Bits.srr, 1u);  // the line's own frame, no channel's
  EXPECT_EQ(r.peer.log.received.size(), 1u);
}

TEST(VciCanLine, CyclicFramesShareTheControllerWithTheChannels) {
  ListRig r;
  ASSERT_EQ(r.line.scheduler_start(*r.line.scheduler_add(cyclic(0x100, 1)), 2), VCI_OK);
  ASSERT_EQ(r.line.scheduler_resume(), VCI_OK);
  r.b.run_until(1 * kMs - 10 * kBit);
  r.send(r.port, msg(0x300, {1, 2, 3, 4, 5, 6, 7, 8}));  // still on the wire at 1 ms
  r.b.run_until(5 * kMs);
  ASSERT_EQ(r.frames.size(), 3u);
  EXPECT_EQ(r.frames[0].frame->id(), 0x300u);
  EXPECT_EQ(r.frames[1].frame->id(), 0x100u);
  EXPECT_EQ(r.frames[1].start.ns(), r.frames[0].end.ns() + 3 * kBit);
  EXPECT_EQ(r.frames[2].start.ns(), 2 * kMs);
}

}  // namespace
}  // namespace canemu::model

// ---------------------------------------------------------------- bit-rate detection

namespace canemu::model {
namespace {

// Two SJA1000 stations talking at 250 kbit/s: one sends `frames` frames, the other acknowledges.
struct Traffic250k {
  Traffic250k(testing::BusFixture& b, int frames) : sender(b), acker(b) {
    HostedNodeSettings s;
    s.btr0 = 0x01;
    s.btr1 = 0x1C;
    sender.start(s);
    acker.start(s);
    for (int i = 0; i < frames; ++i) {
      sender.queue.push_back(TxFrame{k123, false, false});
    }
    sender.node.kick();
  }
  testing::Station<Sja1000Node> sender;
  testing::Station<Sja1000Node> acker;
};

std::vector<ixxat::LineInit> btr_table(std::vector<std::pair<uint8_t, uint8_t>> pairs) {
  std::vector<ixxat::LineInit> t;
  for (auto [btr0, btr1] : pairs) {
    ixxat::LineInit e = v1_init();
    e.btr0 = btr0;
    e.btr1 = btr1;
    t.push_back(e);
  }
  return t;
}

TEST(VciCanLine, DetectionFindsTheTableEntryThatDecodesTheTraffic) {
  Rig r;
  Traffic250k traffic(r.b, 200);
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  // 500, 250, 125 kbit/s: the first sees errors in the 250 kbit/s frames and gives way at
  // once; the second receives a frame.
  ASSERT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}, {0x01, 0x1C}, {0x03, 0x1C}}),
                                   milliseconds(10)),
            VCI_OK);
  EXPECT_EQ(r.line.detection().hr, VCI_E_PENDING);
  EXPECT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}}), milliseconds(10)), VCI_E_BUSY);
  EXPECT_EQ(r.line.init_line(v1_init()), VCI_E_BUSY);
  r.b.run_until(5 * kMs);  // well under one entry's wait: errors, not silence, moved it on
  EXPECT_EQ(r.line.detection().hr, VCI_OK);
  EXPECT_EQ(r.line.detection().index, 1u);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
  // The detector only listened: every frame was acknowledged by the other station.
  const NodeStats& s = r.b.bus.stats(traffic.sender.node.node());
  EXPECT_EQ(s.errors_as_transmitter.total(), 0u);
  EXPECT_EQ(r.b.bus.stats(r.node.node()).frames_sent, 0u);
  // Then the application initializes the line with what was found.
  EXPECT_EQ(r.line.init_line(btr_table({{0x01, 0x1C}})[0]), VCI_OK);
}

TEST(VciCanLine, DetectionOnASilentBusTimesOutAfterEveryEntrysWait) {
  Rig r;
  ASSERT_EQ(r.line.open_control(), VCI_OK);
  ASSERT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}, {0x01, 0x1C}}), milliseconds(10)),
            VCI_OK);
  r.b.run_until(20 * kMs - 1);
  EXPECT_EQ(r.line.detection().hr, VCI_E_PENDING);
  r.b.run_until(20 * kMs);
  EXPECT_EQ(r.line.detection().hr, VCI_E_TIMEOUT);
  EXPECT_EQ(r.line.state(), ixxat::LineState::not_initialized);
}

TEST(VciCanLine, DetectionIsRefusedOnlineAndEndedByResetLine) {
  Rig r;
  Port port;
  r.online(port);
  EXPECT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}}), milliseconds(10)),
            VCI_E_INVALID_STATE);
  ASSERT_EQ(r.line.stop_line(), VCI_OK);
  EXPECT_EQ(r.line.start_detection({}, milliseconds(10)), VCI_E_INVALIDARG);
  ASSERT_EQ(r.line.start_detection(btr_table({{0x00, 0x1C}}), milliseconds(10)), VCI_OK);
  EXPECT_EQ(r.line.start_line(), VCI_E_BUSY);
  ASSERT_EQ(r.line.reset_line(), VCI_OK);
  EXPECT_EQ(r.line.detection().hr, VCI_E_ABORT);
  r.b.run_until(50 * kMs);
  EXPECT_EQ(r.line.detection().hr, VCI_E_ABORT);  // no timer of the cancelled run fires
}

}  // namespace
}  // namespace canemu::model
