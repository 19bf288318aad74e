// canemu dump's lines for LIN monitor messages: frames with their protected identifier and
// checksum (computed here by hand), errors, wake-ups, and what a dump leaves out; canemu send's
// LIN frame syntax.
#include "lin_dump.hpp"
#include "lin_send.hpp"

#include <gtest/gtest.h>

namespace canemu::cli {
namespace {

LINMSG msg(uint8_t type, uint8_t pid, std::vector<uint8_t> data, bool ecs = true) {
  LINMSG m{};
  m.uMsgInfo.Bytes.bType = type;
  m.uMsgInfo.Bytes.bPid = pid;
  m.uMsgInfo.Bytes.bDlen = static_cast<uint8_t>(data.size());
  m.uMsgInfo.Bits.ecs = ecs ? 1 : 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    m.abData[i] = data[i];
  }
  return m;
}

TEST(LinDump, FramesShowTheirProtectedIdentifierAndChecksum) {
  // 10h: P0 = 0, P1 = !(ID4) = 0 -> PID 50h (bit 6 from ID4); enhanced: ~(50h + 01h) = AEh.
  EXPECT_EQ(lin_line(msg(LIN_MSGTYPE_DATA, 0x10, {0x01, 0x00}), 3'333'000, "lin0"),
            "(0000000000.003333) lin0 10#0100 pid 50 enhanced checksum AE");
  // Classic over 42h alone: BDh. 21h: P0 = 1 ^ 0 ^ 0 ^ 0 = 1, P1 = !(0 ^ 0 ^ 0 ^ 1) = 0 -> 61h.
  EXPECT_EQ(lin_line(msg(LIN_MSGTYPE_DATA, 0x21, {0x42}, false), 1'234'567'890'123, "lin1"),
            "(0000001234.567890) lin1 21#42 pid 61 classic checksum BD");
  // The go-to-sleep command: 3Ch (PID 3Ch), classic, 00 FF x 7: ~(00h + 7 x FFh, carries
  // added back) = 00h.
  EXPECT_EQ(
      lin_line(msg(LIN_MSGTYPE_DATA, 0x3C, {0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}, false), 0,
               "lin0"),
      "(0000000000.000000) lin0 3C#00FFFFFFFFFFFFFF pid 3C classic checksum 00 go-to-sleep");
}

TEST(LinDump, ErrorsAndWakeUpsAreNamedAndTheRestLeftOut) {
  LINMSG e = msg(LIN_MSGTYPE_ERROR, 0xFF, {});
  e.abData[0] = LIN_ERROR_SLNORE;
  EXPECT_EQ(lin_line(e, 8'333'000, "lin0"), "(0000000000.008333) lin0 error no-response");
  e.abData[0] = LIN_ERROR_CHKSUM;
  EXPECT_EQ(lin_line(e, 0, "lin0"), "(0000000000.000000) lin0 error checksum");
  e.abData[0] = LIN_ERROR_NOBUS;
  EXPECT_EQ(lin_line(e, 0, "lin0"), "(0000000000.000000) lin0 error no-bus-activity");
  EXPECT_EQ(lin_line(msg(LIN_MSGTYPE_WAKEUP, 0xFF, {}), 250'000, "lin0"),
            "(0000000000.000250) lin0 wake-up");
  EXPECT_EQ(lin_line(msg(LIN_MSGTYPE_INFO, 0xFF, {LIN_INFO_START}), 0, "lin0"), "");
  EXPECT_EQ(lin_line(msg(LIN_MSGTYPE_TMOVR, 0xFF, {}), 0, "lin0"), "");
}

TEST(LinRecord, MonitorMessagesBecomeLinktypeLinRecords) {
  namespace lp = ipc::lin_pcap;
  // 10h with 01 00, enhanced: PID 50h, ~(50h + 01h + 00h) = AEh.
  auto r = lin_pcap_messages(msg(LIN_MSGTYPE_DATA, 0x10, {0x01, 0x00}));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].pid, 0x50);
  EXPECT_EQ(r[0].checksum, 0xAE);
  EXPECT_EQ(r[0].checksum_type, lp::ChecksumType::enhanced);
  EXPECT_EQ(r[0].length, 2);
  EXPECT_EQ(r[0].data[0], 0x01);
  EXPECT_EQ(r[0].errors, 0);
  // 21h with 42h, classic: PID 61h, ~42h = BDh.
  r = lin_pcap_messages(msg(LIN_MSGTYPE_DATA, 0x21, {0x42}, false));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].pid, 0x61);
  EXPECT_EQ(r[0].checksum, 0xBD);
  EXPECT_EQ(r[0].checksum_type, lp::ChecksumType::classic);
  // The go-to-sleep command is its frame and the go-to-sleep event.
  r = lin_pcap_messages(
      msg(LIN_MSGTYPE_DATA, 0x3C, {0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}, false));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].pid, 0x3C);
  EXPECT_EQ(r[0].checksum, 0x00);
  EXPECT_EQ(r[1], lp::event(lp::kEventGoToSleep));
  // 3Fh: P0 = 1 ^ 1 ^ 1 ^ 1 = 0, P1 = !(1 ^ 1 ^ 1 ^ 1) = 1 -> BFh; reserved: invalid ID.
  r = lin_pcap_messages(msg(LIN_MSGTYPE_DATA, 0x3F, {0x00}));
  EXPECT_EQ(r.at(0).pid, 0xBF);
  EXPECT_EQ(r.at(0).errors, lp::kErrorInvalidId);
  // A message that filled the monitor's FIFO.
  LINMSG full = msg(LIN_MSGTYPE_DATA, 0x10, {0x01});
  full.uMsgInfo.Bits.ovr = 1;
  EXPECT_EQ(lin_pcap_messages(full).at(0).errors, lp::kErrorOverflow);
}

TEST(LinRecord, ErrorsAreBitsAndTheRestEvents) {
  namespace lp = ipc::lin_pcap;
  LINMSG e = msg(LIN_MSGTYPE_ERROR, 0xFF, {});
  const auto errors = [&](uint8_t code) {
    e.abData[0] = code;
    const auto r = lin_pcap_messages(e);
    EXPECT_EQ(r.size(), 1u);
    EXPECT_EQ(r.at(0).pid, 0);
    EXPECT_EQ(r.at(0).length, 0);
    EXPECT_EQ(r.at(0).checksum_type, lp::ChecksumType::unknown);
    return r.at(0).errors;
  };
  EXPECT_EQ(errors(LIN_ERROR_SLNORE), lp::kErrorNoSlaveResponse);
  EXPECT_EQ(errors(LIN_ERROR_CHKSUM), lp::kErrorChecksum);
  EXPECT_EQ(errors(LIN_ERROR_PARITY), lp::kErrorParity);
  EXPECT_EQ(errors(LIN_ERROR_SYNC), lp::kErrorFraming);
  EXPECT_EQ(errors(LIN_ERROR_BIT), lp::kErrorFraming);
  EXPECT_EQ(errors(LIN_ERROR_OTHER), lp::kErrorFraming);
  e.abData[0] = LIN_ERROR_NOBUS;
  EXPECT_EQ(lin_pcap_messages(e), std::vector<lp::Message>{lp::event(lp::kEventInactivity)});
  EXPECT_EQ(lin_pcap_messages(msg(LIN_MSGTYPE_WAKEUP, 0xFF, {})),
            std::vector<lp::Message>{lp::event(lp::kEventWakeUp)});
  EXPECT_TRUE(lin_pcap_messages(msg(LIN_MSGTYPE_INFO, 0xFF, {LIN_INFO_START})).empty());
  EXPECT_TRUE(lin_pcap_messages(msg(LIN_MSGTYPE_TMOVR, 0xFF, {})).empty());
}

TEST(LinSend, FramesHeadersSleepAndWakeupInTheirOwnSyntax) {
  std::string error;
  auto m = parse_lin_send("3a#0102", false, error);
  ASSERT_TRUE(m) << error;
  EXPECT_EQ(m->uMsgInfo.Bytes.bType, LIN_MSGTYPE_DATA);
  EXPECT_EQ(m->uMsgInfo.Bytes.bPid, 0x3A);
  EXPECT_EQ(m->uMsgInfo.Bytes.bDlen, 2);
  EXPECT_EQ(m->uMsgInfo.Bits.ecs, 1U);
  EXPECT_EQ(m->uMsgInfo.Bits.ido, 0U);
  EXPECT_EQ(m->abData[1], 0x02);
  m = parse_lin_send("10#", true, error);
  ASSERT_TRUE(m) << error;
  EXPECT_EQ(m->uMsgInfo.Bits.ido, 1U);
  EXPECT_EQ(m->uMsgInfo.Bits.ecs, 0U);
  m = parse_lin_send("sleep", false, error);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->uMsgInfo.Bytes.bType, LIN_MSGTYPE_SLEEP);
  m = parse_lin_send("wakeup", false, error);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->uMsgInfo.Bytes.bType, LIN_MSGTYPE_WAKEUP);
  for (const char* bad :
       {"40#01", "1#01", "123#01", "10#1", "10#010203040506070809", "10#0G", "wake", "Sleep"}) {
    EXPECT_FALSE(parse_lin_send(bad, false, error)) << bad;
  }
}

}  // namespace
}  // namespace canemu::cli
