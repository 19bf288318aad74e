#include "frame_text.hpp"

#include <gtest/gtest.h>

namespace canemu::cli {
namespace {

ipc::ChannelMessage parse(std::string_view text) {
  std::string error;
  auto m = parse_cansend(text, error);
  EXPECT_TRUE(m) << text << ": " << error;
  return m ? *m : ipc::ChannelMessage{};
}

std::string refused(std::string_view text) {
  std::string error;
  auto m = parse_cansend(text, error);
  EXPECT_FALSE(m) << text;
  return error;
}

TEST(FrameText, ReadsCansendSyntax) {
  auto m = parse("123#11.22");
  EXPECT_EQ(m.id, 0x123u);
  EXPECT_EQ(m.flags, 0);
  EXPECT_EQ(m.dlc, 2);
  EXPECT_EQ(m.data[0], 0x11);
  EXPECT_EQ(m.data[1], 0x22);
  m = parse("1abcdef0#");
  EXPECT_EQ(m.id, 0x1ABCDEF0u);
  EXPECT_EQ(m.flags, ipc::kMsgExtended);
  EXPECT_EQ(m.dlc, 0);
  m = parse("12345678#R4");
  EXPECT_EQ(m.flags, ipc::kMsgExtended | ipc::kMsgRemote);
  EXPECT_EQ(m.dlc, 4);
  m = parse("7FF#R");
  EXPECT_EQ(m.dlc, 0);
  // CAN FD: flags nibble 1 = BRS, 2 = ESI; 12 bytes is DLC 9.
  m = parse("123##3000102030405060708090A0B");
  EXPECT_EQ(m.flags, ipc::kMsgFd | ipc::kMsgBrs | ipc::kMsgEsi);
  EXPECT_EQ(m.dlc, 9);
  EXPECT_EQ(m.data[11], 0x0B);
}

TEST(FrameText, RefusesWhatIsNotAFrameAndSaysWhy) {
  EXPECT_EQ(refused("12#11"), "expected <id>#<data> with a 3- or 8-digit hex identifier");
  EXPECT_EQ(refused("12G#11"), "expected <id>#<data> with a 3- or 8-digit hex identifier");
  EXPECT_EQ(refused("123#112"), "data must be pairs of hex digits");
  EXPECT_EQ(refused("123#112233445566778899"), "9 data bytes is not a classic CAN frame length");
  EXPECT_EQ(refused("123##1112233445566778899"), "9 data bytes is not a CAN FD frame length");
  EXPECT_EQ(refused("123##"), "CAN FD frames need a flags digit after ## (1 = BRS, 2 = ESI)");
  EXPECT_EQ(refused("123#R12"), "a remote frame takes one length digit (0..8) after R");
  EXPECT_EQ(refused("800#"), "identifier 0x800 does not fit 11 bits (maximum 0x7FF)");
}

TEST(FrameText, WritesCandumpLinesBackInTheSameSyntax) {
  for (const char* text : {"123#1122", "1ABCDEF0#", "12345678#R4", "123##3000102030405060708090A0B",
                           "7FF#0102030405060708", "001##0"}) {
    ipc::ChannelMessage m = parse(text);
    EXPECT_EQ(candump_frame(m), text);
  }
  ipc::ChannelMessage m = parse("123#1122");
  m.timestamp_ns = 12'345'678'901;
  EXPECT_EQ(candump_line(m, "can0"), "(0000000012.345678) can0 123#1122");
}

TEST(FrameText, WritesErrorsAsSocketCanErrorFrames) {
  ipc::ChannelMessage e;
  e.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::bus_error);
  e.error_type = 0;         // bit
  e.error_role = 0;         // transmitter
  e.error_location = 0x02;  // ID.28..21
  e.tec = 8;
  // PROT | BUSERROR | CNT; data[2] = BIT | TX, data[3] = location, data[6..7] = counters.
  EXPECT_EQ(candump_frame(e), "20000288#0000810200000800");
  e.error_type = 4;  // ACK
  e.error_role = 0;
  e.error_location = 0x19;
  e.tec = 128;
  EXPECT_EQ(candump_frame(e), "200002A8#0000801900008000");
  e.error_type = 1;  // stuff, as receiver
  e.error_role = 1;
  e.error_location = 0x0A;
  e.tec = 0;
  e.rec = 1;
  EXPECT_EQ(candump_frame(e), "20000288#0000040A00000001");
  ipc::ChannelMessage s;
  s.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::state);
  s.state = 2;  // passive
  s.tec = 128;
  EXPECT_EQ(candump_frame(s), "20000204#0020000000008000");
  s.state = 1;  // warning, from the receive counter
  s.tec = 0;
  s.rec = 96;
  EXPECT_EQ(candump_frame(s), "20000204#0004000000000060");
  s.state = 3;  // bus-off
  s.tec = 256;
  s.rec = 0;
  EXPECT_EQ(candump_frame(s), "20000240#000000000000FF00");
  s.state = 0;
  s.tec = 0;
  EXPECT_EQ(candump_frame(s), "20000204#0040000000000000");
  ipc::ChannelMessage done;
  done.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::tx_done);
  EXPECT_EQ(candump_frame(done), "");
}

}  // namespace
}  // namespace canemu::cli
