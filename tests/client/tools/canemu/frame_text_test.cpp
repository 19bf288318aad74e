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

// candump writes a classic DLC above 8 as a `_X` suffix (can-utils' len8_dlc): such a line of a
// recording is sent again as it was, with its DLC.
TEST(FrameText, ReadsTheDlcSuffixOfAClassicFrameAsCandumpWritesIt) {
  auto m = parse("123#1122334455667788_E");
  EXPECT_EQ(m.flags, 0);
  EXPECT_EQ(m.dlc, 14);
  EXPECT_EQ(m.data[7], 0x88);
  m = parse("12345678#R8_9");
  EXPECT_EQ(m.flags, ipc::kMsgExtended | ipc::kMsgRemote);
  EXPECT_EQ(m.dlc, 9);
  m = parse("7FF#11.22.33.44.55.66.77.88_f");
  EXPECT_EQ(m.dlc, 15);
  for (const char* text : {"123#1122334455667788_E", "12345678#R8_9", "7FF#0102030405060708_F"}) {
    EXPECT_EQ(candump_frame(parse(text)), text);
  }
  EXPECT_EQ(refused("123#112233_E"),
            "'_E' follows 8 data bytes only, not 3 (a DLC above 8 still carries 8)");
  EXPECT_EQ(refused("123#R4_E"), "'_E' follows R8 only (a remote frame's DLC above 8)");
  const std::string digit =
      " a classic DLC above 8 is one hex digit 9..F after 8 data bytes or R8, as candump writes "
      "it (123#1122334455667788_E, 123#R8_E)";
  EXPECT_EQ(refused("123#1122334455667788_8"), "'_8':" + digit);
  EXPECT_EQ(refused("123#1122334455667788_"), "'_':" + digit);
  EXPECT_EQ(refused("123#1122334455667788_EE"), "'_EE':" + digit);
  EXPECT_EQ(refused("123##11122334455667788_E"),
            "a CAN FD frame takes no _DLC suffix (its length gives the DLC)");
  EXPECT_EQ(refused("123#R9"), "a remote frame takes one length digit (0..8) after R");
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
