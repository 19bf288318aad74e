// A VCI line on the CAN FD controller: v2 initialization with nominal and data timing, FD
// frames to v1 and v2 channels, sending FD frames, bus-off, errors in the fast data phase.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"

namespace canemu::model {
namespace {

using namespace testing;  // line_rig.hpp, hosted_station.hpp

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
  // The line initialized for FD (init()) and started with one v2 channel on `port`; its id.
  ChannelId online(Port& port) {
    EXPECT_EQ(line.open_control(), VCI_OK);
    EXPECT_EQ(line.init_line(init()), VCI_OK);
    const ChannelId id = channel(port, true);
    EXPECT_EQ(line.start_line(), VCI_OK);
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

// The 12-byte FD message 0x200 (DLC 9, bytes 1 to 12), with the rate switch if `fdr`.
CANMSG2 fd_msg_12(bool fdr) {
  CANMSG2 m = msg(0x200, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  m.uMsgInfo.Bits.dlc = 9;
  m.uMsgInfo.Bits.edl = 1;
  m.uMsgInfo.Bits.fdr = fdr ? 1 : 0;
  return m;
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
  EXPECT_EQ(c.dwFeatures, 0xFEFEu);  // the classic set + EXTDATA, FASTDATA, ISOFRAME
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
  const ChannelId ch = r.online(p);
  const CANMSG2 a = fd_msg_12(true);
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
  const ChannelId ch = r.online(p);
  r.b.plan.add(errors_from(r.node.node(), CanErrorType::bit, 32));
  r.send(p, fd_msg_12(true));
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

// One bit error injected at frame bit `bit` of a 12-byte FD frame the line sends (with or
// without bit-rate switch): the ERROR messages the line's channel gets, and the peer's log.
struct InjectedBitError {
  std::vector<CANMSG2> errors;
  std::vector<Frame> received;
  int64_t expected_at = 0;  // end of bit `bit` of the retransmitted frame, ns from 0
};
InjectedBitError inject_bit_error(uint16_t bit, bool brs) {
  FdRig r;
  Port p;
  EXPECT_EQ(r.line.open_control(), VCI_OK);
  EXPECT_EQ(r.line.init_line(r.init()), VCI_OK);
  r.channel(p, true);
  EXPECT_EQ(r.line.start_line(), VCI_OK);
  r.b.plan.add(errors_from(r.node.node(), CanErrorType::bit, 1, bit));
  r.send(p, fd_msg_12(brs));
  r.b.run_until(2 * kMs);
  InjectedBitError out;
  out.errors = p.of_type(CAN_MSGTYPE_ERROR);
  for (const auto& rx : r.peer.log.received) {
    out.received.push_back(rx.frame);
  }
  if (!out.received.empty()) {
    // Detected at the end of the bit: the bits before it at their rates, then the bus engine
    // switches back to the nominal rate at the erroneous bit (docs/bus-engine.md).
    out.expected_at =
        frame_prefix_duration(encode(out.received[0]), r.nominal, r.data, bit).ns() + kBit;
  }
  return out;
}

TEST(VciCanLine, ABitErrorInTheFastDataPhaseIsReportedAsAFastDataBitError) {
  const InjectedBitError e = inject_bit_error(40, true);  // in the data field
  ASSERT_EQ(e.errors.size(), 1u);
  EXPECT_EQ(e.errors[0].abData[0], CAN_ERROR_FDB);
  EXPECT_EQ(e.errors[0].abData[1], CAN_STATUS_TXPEND);
  EXPECT_EQ(e.errors[0].abData[4], 8u);  // TEC after the error
  ASSERT_EQ(e.received.size(), 1u);      // the retransmission
  EXPECT_TRUE(e.received[0].brs());
  EXPECT_EQ(e.errors[0].dwTime, static_cast<uint32_t>(e.expected_at / kUs));
}

TEST(VciCanLine, TheFastDataPhaseRunsFromAfterBrsToBeforeTheCrcDelimiter) {
  const EncodedFrame enc = encode(*Frame::fd_frame(
      0x200, std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}, false, true));
  // The first bit after BRS (ESI) and the last CRC bit are at the data rate: FDB.
  for (const uint16_t bit : {static_cast<uint16_t>(enc.brs_index + 1),
                             static_cast<uint16_t>(enc.crc_delimiter_index - 1)}) {
    const InjectedBitError e = inject_bit_error(bit, true);
    ASSERT_EQ(e.errors.size(), 1u) << bit;
    EXPECT_EQ(e.errors[0].abData[0], CAN_ERROR_FDB) << bit;
    EXPECT_EQ(e.errors[0].dwTime, static_cast<uint32_t>(e.expected_at / kUs)) << bit;
  }
  // The identifier (arbitration phase) and BRS itself (the rate switches at its sample point):
  // a plain bit error.
  for (const uint16_t bit : {uint16_t{5}, enc.brs_index}) {
    const InjectedBitError e = inject_bit_error(bit, true);
    ASSERT_EQ(e.errors.size(), 1u) << bit;
    EXPECT_EQ(e.errors[0].abData[0], CAN_ERROR_BIT) << bit;
  }
}

TEST(VciCanLine, ABitErrorInTheDataFieldOfAnFdFrameWithoutBitRateSwitchIsABitError) {
  const InjectedBitError e = inject_bit_error(40, false);
  ASSERT_EQ(e.errors.size(), 1u);
  EXPECT_EQ(e.errors[0].abData[0], CAN_ERROR_BIT);
  ASSERT_EQ(e.received.size(), 1u);
  EXPECT_FALSE(e.received[0].brs());
  EXPECT_EQ(e.errors[0].dwTime, static_cast<uint32_t>(e.expected_at / kUs));
}

TEST(VciCanLine, InitLineRefusesModesAndTimingsTheControllerDoesNotHave) {
  Rig classic_line;
  ASSERT_EQ(classic_line.line.open_control(), VCI_OK);
  ixxat::LineInit fd_modes = v2_init();
  fd_modes.ex_mode = CAN_EXMODE_EXTDATA;
  EXPECT_EQ(classic_line.line.init_line(fd_modes), VCI_E_INVALIDARG);
  EXPECT_EQ(classic_line.line.init_line(v1_init(CAN_OPMODE_STANDARD | CAN_OPMODE_LOWSPEED)),
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

}  // namespace
}  // namespace canemu::model
