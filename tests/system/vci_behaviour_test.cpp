// Behaviours of the VCI emulation seen through the VCI "2" C API (libvcinpl2) against a real
// canemud in stepped time: the fast data bit error, bit-rate detection at initialization
// (CAN_OPMODE_AUTOBAUD), and what a listen-only line does with the frames it is given.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"
#include "vci2_c_test_support.hpp"

namespace canemu {
namespace {

using testing::fd_timing;
using testing::kData;
using testing::kFd;
using testing::kMode;
using testing::kNominal;
using testing::Line;
using testing::msg;
using testing::step_ns;
using testing::VciDaemon;

// kFdAdapters and two more classic adapters on can0.
const std::string kAdapters =
    testing::kFdAdapters +
    "\n[[device]]\nname = \"delta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"epsilon\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n";

constexpr CANBTP k250k{0, 250000, 14, 2, 1, 0};  // on the SJA1000: 32 quanta of 125 ns
constexpr CANBTP k500k{0, 500000, 14, 2, 1, 0};

// ---------------------------------------------------------------- fast data bit error

// A bit error in the data field of an FD frame with bit-rate switch is CAN_ERROR_FDB; the same
// fault in its identifier is CAN_ERROR_BIT. The ERROR message is stamped with the end of the
// erroneous bit: the bits before it at their rates, that bit at the nominal rate (the engine
// switches back to it at the error).
TEST(VciBehaviour, ABitErrorInTheFastDataPhaseIsAFastDataBitError) {
  VciDaemon d(kAdapters);
  Line alpha("alpha", kMode, kFd, kNominal, kData);
  Line beta("beta", kMode, kFd, kNominal, kData);
  testing::load_faults(d.daemon,
                       "[[fault]]\nat = \"0s\"\nbus = \"fd0\"\nmatch = { from = \"alpha:0\" }\n"
                       "effect = \"bit_error\"\nbit = 40\ncount = 1\n");
  const std::vector<uint8_t> twelve{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  alpha.post(msg(0x123, twelve, true, true));
  step_ns(2'000'000);
  const auto errors = alpha.drain(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].dwMsgId, CAN_MSGID_ERROR);
  EXPECT_EQ(errors[0].abData[0], CAN_ERROR_FDB);
  EXPECT_EQ(errors[0].abData[1], CAN_STATUS_TXPEND);
  const auto nominal =
      fd_timing(kNominal, model::ixxat::kFdNominalRange, model::ixxat::Phase::nominal);
  const auto data = fd_timing(kData, model::ixxat::kFdDataRange, model::ixxat::Phase::data);
  const auto enc = model::encode(*model::Frame::fd_frame(0x123, twelve, false, true));
  const int64_t at = model::frame_prefix_duration(enc, nominal, data, 40).ns() + 2000;
  EXPECT_EQ(errors[0].dwTime, static_cast<UINT32>(at / 1000));
  const auto got = beta.drain(CAN_MSGTYPE_DATA);  // the repetition
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 1u);

  // BRS itself (the rate switches at its sample point): a plain bit error, at the end of BRS
  // at the nominal rate of 2 us a bit.
  const auto enc2 = model::encode(*model::Frame::fd_frame(0x124, twelve, false, true));
  testing::load_faults(d.daemon,
                       "[scenario]\nname = \"brs\"\n[[fault]]\nat = \"0s\"\n"
                       "bus = \"fd0\"\nmatch = { from = \"alpha:0\" }\n"
                       "effect = \"bit_error\"\ncount = 1\nbit = " +
                           std::to_string(enc2.brs_index) + "\n");
  alpha.post(msg(0x124, twelve, true, true));
  step_ns(2'000'000);
  const auto second = alpha.drain(CAN_MSGTYPE_ERROR);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0].abData[0], CAN_ERROR_BIT);
  EXPECT_EQ(second[0].dwTime, 2000u + (enc2.brs_index + 1u) * 2u);
}

// ---------------------------------------------------------------- CAN_OPMODE_AUTOBAUD

// epsilon starts with CAN_OPMODE_AUTOBAUD (timing fields garbage) on a bus where gamma sends ten
// frames back to back at 250 kbit/s and delta acknowledges them. epsilon tries 1000, 800 and
// 500 kbit/s on the first three (an error each, nothing disturbed), decodes the fourth with
// 250 kbit/s and locks in at its end: it receives the fourth to the tenth with their exact time
// stamps, then sends at 250 kbit/s itself.
TEST(VciBehaviour, AnAutobaudLineFindsTheRateOfTheTrafficAndReceivesFromThen) {
  VciDaemon d(kAdapters);
  constexpr CANBTP kGarbage{0, 300000, 1, 0, 0, 0};
  Line epsilon("epsilon", kMode | CAN_OPMODE_AUTOBAUD, CAN_EXMODE_DISABLED, kGarbage, CANBTP{});
  CANCAPABILITIES2 caps{};
  ASSERT_EQ(canControlGetCaps(epsilon.control, &caps), VCI_OK);
  EXPECT_EQ(caps.dwFeatures & CAN_FEATURE_AUTOBAUD, static_cast<UINT32>(CAN_FEATURE_AUTOBAUD));
  CANLINESTATUS2 s{};
  ASSERT_EQ(canControlGetStatus(epsilon.control, &s), VCI_OK);
  EXPECT_EQ(s.bOpMode, kMode | CAN_OPMODE_AUTOBAUD);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));  // listening
  EXPECT_EQ(s.sBtpSdr.dwBPS, 0u);                                 // no rate yet
  Line delta("delta", kMode, CAN_EXMODE_DISABLED, k250k, CANBTP{});
  Line gamma("gamma", kMode, CAN_EXMODE_DISABLED, k250k, CANBTP{});
  const std::vector<uint8_t> two{0x11, 0x22};
  for (int k = 0; k < 10; ++k) {
    gamma.post(msg(0x123, two));
  }
  // Frame k starts at k x (L + 3) bits of 4 us (L from SOF to the end of EOF, 3 of
  // intermission) and is delivered at the end of its EOF.
  const int64_t bits =
      model::frame_duration(model::encode(*model::Frame::classic(0x123, two, false)),
                            model::sja1000::timing_from_btr(CAN_BT0_250KB, CAN_BT1_250KB))
          .ns() /
      4000;
  auto received_us = [&](int64_t k) { return static_cast<UINT32>((k * (bits + 3) + bits) * 4); };
  step_ns(uint64_t{received_us(3)} * 1000 - 1000);
  ASSERT_EQ(canControlGetStatus(epsilon.control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  step_ns(1000);
  ASSERT_EQ(canControlGetStatus(epsilon.control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, 0u);  // locked in
  EXPECT_EQ(s.bOpMode, kMode | CAN_OPMODE_AUTOBAUD);
  EXPECT_EQ(s.sBtpSdr.dwMode, static_cast<UINT32>(CAN_BTMODE_RAW));  // 250 kbit/s, raw
  EXPECT_EQ(s.sBtpSdr.dwBPS, 2u);  // 2 periods of the 8 MHz clock a quantum
  EXPECT_EQ(s.sBtpSdr.wTS1, 13u);
  EXPECT_EQ(s.sBtpSdr.wTS2, 2u);
  step_ns(10'000'000);
  const auto got = epsilon.drain(CAN_MSGTYPE_DATA);
  ASSERT_EQ(got.size(), 7u);
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].dwMsgId, 0x123u);
    EXPECT_EQ(got[k].dwTime, received_us(3 + static_cast<int64_t>(k))) << k;
  }
  EXPECT_EQ(delta.drain(CAN_MSGTYPE_ERROR).size(), 0u);  // nobody saw an error flag
  EXPECT_EQ(gamma.drain(CAN_MSGTYPE_ERROR).size(), 0u);
  EXPECT_EQ(epsilon.drain(CAN_MSGTYPE_ERROR).size(), 0u);
  // It sends at 250 kbit/s now: delta receives it.
  epsilon.post(msg(0x321, {5}));
  step_ns(1'000'000);
  const auto heard = delta.drain(CAN_MSGTYPE_DATA);
  ASSERT_FALSE(heard.empty());
  EXPECT_EQ(heard.back().dwMsgId, 0x321u);
}

// On a silent bus it stays listening: ININIT, no timing, and a posted frame stays unsent.
TEST(VciBehaviour, AnAutobaudLineOnASilentBusKeepsListening) {
  VciDaemon d(kAdapters);
  Line epsilon("epsilon", kMode | CAN_OPMODE_AUTOBAUD, CAN_EXMODE_DISABLED, k500k, CANBTP{});
  Line delta("delta", kMode, CAN_EXMODE_DISABLED, k250k, CANBTP{});
  epsilon.post(msg(0x321, {5}));
  step_ns(500'000'000);
  CANLINESTATUS2 s{};
  ASSERT_EQ(canControlGetStatus(epsilon.control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(s.sBtpSdr.dwBPS, 0u);
  EXPECT_TRUE(delta.drain(CAN_MSGTYPE_DATA).empty());
  CANCHANSTATUS2 cs{};
  ASSERT_EQ(canChannelGetStatus(epsilon.channel, &cs), VCI_OK);
  EXPECT_EQ(cs.sLineStatus.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
}

// ---------------------------------------------------------------- listen-only

// A listen-only line never sends: what a program posts waits in the transmit FIFO (the
// firmware hands nothing to the controller), so the line status never shows TXPEND. It still
// receives. Initialized to send again, the line sends what waited.
TEST(VciBehaviour, AListenOnlyLineKeepsWhatItIsGivenInTheFifoAndNeverShowsTxpend) {
  VciDaemon d(kAdapters);
  Line gamma("gamma", kMode | CAN_OPMODE_LISTONLY, CAN_EXMODE_DISABLED, k500k, CANBTP{});
  Line delta("delta", kMode, CAN_EXMODE_DISABLED, k500k, CANBTP{});
  Line epsilon("epsilon", kMode, CAN_EXMODE_DISABLED, k500k, CANBTP{});
  for (uint32_t id : {0x100u, 0x101u, 0x102u}) {
    gamma.post(msg(id, {1}));
  }
  step_ns(5'000'000);
  CANCHANSTATUS2 cs{};
  ASSERT_EQ(canChannelGetStatus(gamma.channel, &cs), VCI_OK);
  EXPECT_EQ(cs.sLineStatus.dwStatus, 0u);  // online, nothing pending
  // 3 messages waiting: 3 % of the FIFO (64 asked for, a whole page of CANMSG2 given).
  EXPECT_EQ(cs.bTxFifoLoad, 3u);
  EXPECT_EQ(gamma.line_status(), 0u);
  EXPECT_TRUE(delta.drain(CAN_MSGTYPE_DATA).empty());
  EXPECT_TRUE(epsilon.drain(CAN_MSGTYPE_DATA).empty());
  // It receives delta's frame (acknowledged by epsilon): 62 bits of 2 us after it was posted.
  delta.post(msg(0x123, {0x11, 0x22}));
  step_ns(1'000'000);
  const auto got = gamma.drain(CAN_MSGTYPE_DATA);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x123u);
  EXPECT_EQ(got[0].dwTime, 5000u + 62 * 2);
  EXPECT_EQ(gamma.line_status(), 0u);
  // Initialized to send: the three go out in order.
  ASSERT_EQ(canControlReset(gamma.control), VCI_OK);
  CANBTP sdr = k500k;
  ASSERT_EQ(testing::init_classic(gamma.control, sdr), VCI_OK);
  ASSERT_EQ(canControlStart(gamma.control, TRUE), VCI_OK);
  step_ns(2'000'000);
  std::vector<uint32_t> ids;
  for (const CANMSG2& m : delta.drain(CAN_MSGTYPE_DATA)) {
    ids.push_back(m.dwMsgId);
  }
  EXPECT_EQ(ids, (std::vector<uint32_t>{0x100, 0x101, 0x102}));
  ASSERT_EQ(canChannelGetStatus(gamma.channel, &cs), VCI_OK);
  EXPECT_EQ(cs.bTxFifoLoad, 0u);
}

}  // namespace
}  // namespace canemu
