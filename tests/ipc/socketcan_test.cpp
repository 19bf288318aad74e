#include "canemu/ipc/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/error.h>

#include <cstring>

#include <gtest/gtest.h>

namespace canemu::ipc::socketcan {
namespace {

static_assert(kEffFlag == CAN_EFF_FLAG && kRtrFlag == CAN_RTR_FLAG && kErrFlag == CAN_ERR_FLAG);
static_assert(kCanMtu == CAN_MTU && kCanFdMtu == CANFD_MTU);
static_assert(kFdBrs == CANFD_BRS && kFdEsi == CANFD_ESI && kFdFdf == CANFD_FDF);
static_assert(kErrCrtl == CAN_ERR_CRTL && kErrProt == CAN_ERR_PROT && kErrAck == CAN_ERR_ACK &&
              kErrBusOff == CAN_ERR_BUSOFF && kErrBusError == CAN_ERR_BUSERROR &&
              kErrRestarted == CAN_ERR_RESTARTED && kErrCnt == CAN_ERR_CNT);
static_assert(kCrtlRxWarning == CAN_ERR_CRTL_RX_WARNING &&
              kCrtlTxWarning == CAN_ERR_CRTL_TX_WARNING &&
              kCrtlRxPassive == CAN_ERR_CRTL_RX_PASSIVE &&
              kCrtlTxPassive == CAN_ERR_CRTL_TX_PASSIVE && kCrtlActive == CAN_ERR_CRTL_ACTIVE);
static_assert(kProtBit == CAN_ERR_PROT_BIT && kProtForm == CAN_ERR_PROT_FORM &&
              kProtStuff == CAN_ERR_PROT_STUFF && kProtTx == CAN_ERR_PROT_TX);

ChannelMessage frame(uint32_t id, uint8_t flags, uint8_t dlc, std::initializer_list<uint8_t> data) {
  ChannelMessage m;
  m.id = id;
  m.flags = flags;
  m.dlc = dlc;
  std::size_t i = 0;
  for (uint8_t b : data) {
    m.data[i++] = b;
  }
  return m;
}

std::string text(const ChannelMessage& m) {
  const auto f = from_message(m);
  return f ? candump_text(*f) : "(none)";
}

std::string hex(const std::vector<uint8_t>& bytes) {
  std::string s;
  for (uint8_t b : bytes) {
    char two[3];
    std::snprintf(two, sizeof two, "%02X", b);
    s += two;
  }
  return s;
}

TEST(SocketCan, FramesAsCandumpWritesThem) {
  EXPECT_EQ(text(frame(0x123, 0, 2, {0x11, 0x22})), "123#1122");
  EXPECT_EQ(text(frame(0x1ABCDEF0, kMsgExtended, 0, {})), "1ABCDEF0#");
  EXPECT_EQ(text(frame(0x7FF, kMsgRemote, 0, {})), "7FF#R");
  EXPECT_EQ(text(frame(0x12345678, kMsgExtended | kMsgRemote, 4, {})), "12345678#R4");
  EXPECT_EQ(text(frame(0x123, kMsgRemote, 15, {})), "123#R8_F");
  EXPECT_EQ(text(frame(0x123, 0, 14, {1, 2, 3, 4, 5, 6, 7, 8})), "123#0102030405060708_E");
  EXPECT_EQ(text(frame(0x123, kMsgFd | kMsgBrs, 1, {0xAB})), "123##1AB");
  EXPECT_EQ(text(frame(0x001, kMsgFd, 0, {})), "001##0");
  EXPECT_EQ(text(frame(0x10, kMsgFd | kMsgExtended | kMsgBrs | kMsgEsi, 9,
                       {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11})),
            "00000010##3000102030405060708090A0B");
  ChannelMessage done;
  done.kind = static_cast<uint8_t>(ChannelMessageKind::tx_done);
  EXPECT_EQ(text(done), "(none)");
  done.kind = static_cast<uint8_t>(ChannelMessageKind::tx_dropped);
  EXPECT_EQ(text(done), "(none)");
}

TEST(SocketCan, CandumpLogLinesHaveTenDigitSecondsAndMicroseconds) {
  const auto f = from_message(frame(0x123, 0, 2, {0x11, 0x22}));
  EXPECT_EQ(candump_line(12'345'678'901, "can0", *f), "(0000000012.345678) can0 123#1122");
  EXPECT_EQ(candump_line(1'700'000'000'000'000'999, "bus1", *f),
            "(1700000000.000000) bus1 123#1122");
  EXPECT_EQ(candump_line(-5, "can0", *f), "(0000000000.000000) can0 123#1122");
}

TEST(SocketCan, BusErrorsAreProtocolErrorFramesAsCandumpEDecodesThem) {
  ChannelMessage e;
  e.kind = static_cast<uint8_t>(ChannelMessageKind::bus_error);
  e.error_type = 0;         // bit
  e.error_role = 0;         // transmitter
  e.error_location = 0x02;  // CAN_ERR_PROT_LOC_ID28_21
  e.tec = 8;
  // PROT | BUSERROR | CNT; data[2] = BIT | TX, data[3] = location, data[6..7] = counters.
  EXPECT_EQ(text(e), "20000288#0000810200000800");
  e.error_type = 4;  // ACK: CAN_ERR_ACK too, type unspecified
  e.error_location = CAN_ERR_PROT_LOC_ACK;
  e.tec = 128;
  EXPECT_EQ(text(e), "200002A8#0000801900008000");
  e.error_type = 1;  // stuff, as receiver
  e.error_role = 1;
  e.error_location = CAN_ERR_PROT_LOC_DATA;
  e.tec = 0;
  e.rec = 1;
  EXPECT_EQ(text(e), "20000288#0000040A00000001");
  e.error_type = 2;  // form
  e.error_location = CAN_ERR_PROT_LOC_CRC_DEL;
  EXPECT_EQ(text(e), "20000288#0000021800000001");
  e.error_type = 3;  // CRC: unspecified type at the CRC sequence
  e.error_location = CAN_ERR_PROT_LOC_CRC_SEQ;
  e.rec = 300;  // counters above 255 print as 255
  EXPECT_EQ(text(e), "20000288#00000008000000FF");
}

TEST(SocketCan, StateChangesAreControllerOrBusOffErrorFrames) {
  ChannelMessage s;
  s.kind = static_cast<uint8_t>(ChannelMessageKind::state);
  s.state = 2;  // passive, from the transmit counter
  s.tec = 128;
  EXPECT_EQ(text(s), "20000204#0020000000008000");
  s.state = 1;  // warning, from the receive counter
  s.tec = 0;
  s.rec = 96;
  EXPECT_EQ(text(s), "20000204#0004000000000060");
  s.state = 3;  // bus-off
  s.tec = 256;
  s.rec = 0;
  EXPECT_EQ(text(s), "20000240#000000000000FF00");
  s.state = 0;  // back to error-active
  s.tec = 0;
  EXPECT_EQ(text(s), "20000204#0040000000000000");
  EXPECT_EQ(from_message(s)->len, CAN_ERR_DLC);
}

TEST(SocketCan, ARestartIsTheKernelsRestartedErrorFrame) {
  // can_restart(): CAN_ERR_FLAG | CAN_ERR_RESTARTED, CAN_ERR_DLC bytes of 0.
  const Frame f = restarted_frame();
  EXPECT_EQ(f.can_id, CAN_ERR_FLAG | CAN_ERR_RESTARTED);
  EXPECT_EQ(f.len, CAN_ERR_DLC);
  EXPECT_EQ(candump_text(f), "20000100#0000000000000000");
}

TEST(SocketCan, StructBytesAreTheKernelsCanFrameAndCanFdFrame) {
  const auto classic = from_message(frame(0x12345678, kMsgExtended, 13, {1, 2, 3, 4, 5, 6, 7, 8}));
  const auto bytes = to_struct(*classic);
  ASSERT_EQ(bytes.size(), sizeof(can_frame));
  can_frame cf;
  std::memcpy(&cf, bytes.data(), sizeof cf);
  EXPECT_EQ(cf.can_id, 0x12345678u | CAN_EFF_FLAG);
  EXPECT_EQ(cf.len, 8);
  EXPECT_EQ(cf.len8_dlc, 13);
  EXPECT_EQ(cf.data[7], 8);
  EXPECT_EQ(from_struct(bytes.data(), bytes.size()), classic);

  const auto fd = from_message(frame(0x123, kMsgFd | kMsgEsi, 10, {0xAA}));
  const auto fd_bytes = to_struct(*fd);
  ASSERT_EQ(fd_bytes.size(), sizeof(canfd_frame));
  canfd_frame ff;
  std::memcpy(&ff, fd_bytes.data(), sizeof ff);
  EXPECT_EQ(ff.can_id, 0x123u);
  EXPECT_EQ(ff.len, 16);
  EXPECT_EQ(ff.flags, CANFD_ESI | CANFD_FDF);
  EXPECT_EQ(ff.data[0], 0xAA);
  EXPECT_EQ(from_struct(fd_bytes.data(), fd_bytes.size()), fd);
  EXPECT_FALSE(from_struct(fd_bytes.data(), 20));
}

TEST(SocketCan, FramesFromASocketBecomeChannelMessages) {
  std::string error;
  for (const auto& m :
       {frame(0x123, 0, 2, {0x11, 0x22}), frame(0x1ABCDEF0, kMsgExtended | kMsgRemote, 3, {}),
        frame(0x7FF, 0, 15, {1, 2, 3, 4, 5, 6, 7, 8}),
        frame(0x42, kMsgFd | kMsgBrs | kMsgEsi, 15, {9, 8, 7})}) {
    const auto f = from_message(m);
    const auto back = to_message(*f, error);
    ASSERT_TRUE(back) << error;
    EXPECT_EQ(back->id, m.id);
    EXPECT_EQ(back->flags, m.flags);
    EXPECT_EQ(back->dlc, m.dlc);
    EXPECT_EQ(std::memcmp(back->data, m.data, sizeof m.data), 0);
  }
  // A CAN FD length between two DLCs' lengths goes out as kernel drivers send it
  // (canfd_sanitize_len()): the next DLC, the bytes up to its length zero.
  Frame odd;
  odd.fd = true;
  odd.flags = kFdFdf;
  odd.len = 13;
  for (uint8_t k = 0; k < 13; ++k) {
    odd.data[k] = static_cast<uint8_t>(k + 1);
  }
  odd.data[13] = 0xEE;  // beyond len: not part of the frame
  const auto padded = to_message(odd, error);
  ASSERT_TRUE(padded) << error;
  EXPECT_EQ(padded->dlc, 10);
  EXPECT_EQ(padded->flags, kMsgFd);
  EXPECT_EQ(padded->data[12], 13);
  for (int k = 13; k < 64; ++k) {
    EXPECT_EQ(padded->data[k], 0) << k;
  }
  odd.len = 49;
  ASSERT_TRUE(to_message(odd, error));
  EXPECT_EQ(to_message(odd, error)->dlc, 15);
  Frame bad;
  bad.fd = true;
  bad.len = 65;
  EXPECT_FALSE(to_message(bad, error));
  EXPECT_EQ(error, "CAN FD length 65 is above 64");
  bad.len = 8;
  bad.can_id = kRtrFlag | 0x100;
  EXPECT_FALSE(to_message(bad, error));
  EXPECT_EQ(error, "CAN FD has no remote frames");
  bad.can_id = kErrFlag | kErrBusOff;
  EXPECT_FALSE(to_message(bad, error));
  EXPECT_EQ(error, "an error frame cannot be sent onto a bus");
}

// The worked example of socketcan.hpp.
TEST(SocketCan, PcapFilesHaveTheNanosecondHeaderAndLinktype227) {
  EXPECT_EQ(hex(pcap_file_header()),
            "4D3CB2A1"    // magic: nanosecond time stamps, little-endian
            "02000400"    // version 2.4
            "00000000"    // thiszone
            "00000000"    // sigfigs
            "48000000"    // snaplen 72
            "E3000000");  // LINKTYPE_CAN_SOCKETCAN
  std::vector<uint8_t> out;
  append_pcap_record(out, 1'000'000'500, *from_message(frame(0x123, 0, 2, {0x11, 0x22})));
  EXPECT_EQ(hex(out),
            "01000000F40100001000000010000000"
            "00000123020000001122000000000000");
}

TEST(SocketCan, PcapRecordsCarryTheIdBigEndianAndWholeFdFrames) {
  std::vector<uint8_t> out;
  append_pcap_record(out, 2'000'000'007,
                     *from_message(frame(0x1ABCDEF0, kMsgExtended | kMsgFd | kMsgBrs, 9,
                                         {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11})));
  ASSERT_EQ(out.size(), kPcapRecordHeaderSize + kCanFdMtu);
  EXPECT_EQ(hex({out.begin(), out.begin() + 32}),
            "020000000700000048000000480000009ABCDEF00C0500000001020304050607");
  out.clear();
  ChannelMessage s;
  s.kind = static_cast<uint8_t>(ChannelMessageKind::state);
  s.state = 3;
  s.tec = 256;
  append_pcap_record(out, 0, *from_message(s));
  EXPECT_EQ(hex({out.begin() + 16, out.end()}), "2000024008000000000000000000FF00");
  out.clear();
  append_pcap_record(out, 0, *from_message(frame(0x7FF, kMsgRemote, 15, {})));
  EXPECT_EQ(hex({out.begin() + 16, out.end()}), "400007FF0800000F0000000000000000");
}

}  // namespace
}  // namespace canemu::ipc::socketcan
