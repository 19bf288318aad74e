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

TEST(FrameText, WritesFramesBackInTheSameSyntax) {
  for (const char* text : {"123#1122", "1ABCDEF0#", "12345678#R4", "7FF#R",
                           "123##3000102030405060708090A0B", "7FF#0102030405060708", "001##0"}) {
    ipc::ChannelMessage m = parse(text);
    EXPECT_EQ(candump_frame(m), text);
  }
  ipc::ChannelMessage done;
  done.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::tx_done);
  EXPECT_EQ(candump_frame(done), "");
}

}  // namespace
}  // namespace canemu::cli
