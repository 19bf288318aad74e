// The 82527 message object's register encodings: identifier layout, flag pairs, acceptance.
#include "canemu/firmware_model/chips/i82527/message_object.hpp"

#include <gtest/gtest.h>

namespace canemu::model::i82527 {
namespace {

using Bytes = std::array<uint8_t, 4>;

TEST(I82527IdEncoding, WorkedExampleOfTheHeaderComment) {
  // Standard 0x123 = 001 0010 0011: ID10..3 = 0010 0100, ID2..0 = 011 in bits 7..5.
  EXPECT_EQ(encode_id(0x123, false), (Bytes{0x24, 0x60, 0x00, 0x00}));
  // Extended 0x12345678 << 3 = 0x91A2B3C0, most significant byte first.
  EXPECT_EQ(encode_id(0x12345678, true), (Bytes{0x91, 0xA2, 0xB3, 0xC0}));
  EXPECT_EQ(decode_id({0x24, 0x60, 0x00, 0x00}, false), 0x123u);
  EXPECT_EQ(decode_id({0x91, 0xA2, 0xB3, 0xC0}, true), 0x12345678u);
  // Unused bits do not reach the identifier.
  EXPECT_EQ(decode_id({0x24, 0x7F, 0xFF, 0xFF}, false), 0x123u);
  EXPECT_EQ(decode_id({0x91, 0xA2, 0xB3, 0xC7}, true), 0x12345678u);
  // The largest identifiers fill their fields.
  EXPECT_EQ(encode_id(0x7FF, false), (Bytes{0xFF, 0xE0, 0x00, 0x00}));
  EXPECT_EQ(encode_id(0x1FFFFFFF, true), (Bytes{0xFF, 0xFF, 0xFF, 0xF8}));
}

TEST(I82527FlagPairs, WritesOf01ResetAnd10SetAnd11LeaveTheFlag) {
  EXPECT_EQ(pair_write(MSGVAL), 0xBF);
  EXPECT_EQ(pair_write(0, MSGVAL), 0x7F);
  EXPECT_EQ(pair_write(TXRQST | NEWDAT, CPUUPD), 0xE6);
  EXPECT_EQ(pair_write(MSGVAL | RXIE, TXIE | INTPND), 0x99);
  uint8_t reg = kAllPairsReset;
  reg = apply_pair_write(reg, pair_write(MSGVAL | RXIE));
  EXPECT_EQ(reg, 0x99);  // 10 01 10 01
  EXPECT_TRUE(pair_is_set(reg, MSGVAL));
  EXPECT_FALSE(pair_is_set(reg, TXIE));
  EXPECT_TRUE(pair_is_set(reg, RXIE));
  reg = apply_pair_write(reg, 0xFF);  // all 11: nothing changes
  EXPECT_EQ(reg, 0x99);
  reg = apply_pair_write(reg, pair_write(INTPND, RXIE));
  EXPECT_EQ(reg, 0x96);  // 10 01 01 10
}

TEST(I82527Acceptance, MaskBitsSetMustMatchAndFormatMustAgree) {
  MessageObject o;
  o.arb = encode_id(0x120, false);
  const Bytes std_mask = encode_id(0x7F0, false);  // the low nibble is don't care
  EXPECT_TRUE(matches(o, *Frame::classic(0x12F, {}), std_mask));
  EXPECT_FALSE(matches(o, *Frame::classic(0x130, {}), std_mask));
  EXPECT_FALSE(matches(o, *Frame::classic(0x120, {}, true), std_mask));  // XTD = 0
  o.config = CONFIG_XTD;
  o.arb = encode_id(0x12345600, true);
  const Bytes ext_mask = encode_id(0x1FFFFF00, true);
  EXPECT_TRUE(matches(o, *Frame::classic(0x123456AB, {}, true), ext_mask));
  EXPECT_FALSE(matches(o, *Frame::classic(0x12345700, {}, true), ext_mask));
}

TEST(I82527MessageObject, StoresTheFrameKeepingDirAndXtdAndBuildsItsOwnFrame) {
  MessageObject o;
  o.config = CONFIG_DIR | 0x03;  // transmit, reserved bits set
  const uint8_t bytes[3] = {0xA1, 0xB2, 0xC3};
  o.store(*Frame::classic(0x456, bytes));
  EXPECT_EQ(o.config, 0x3B);  // DLC 3, DIR, reserved bits as they were
  EXPECT_EQ(o.arb, (Bytes{0x8A, 0xC0, 0x00, 0x00}));
  EXPECT_EQ(o.frame(), *Frame::classic(0x456, bytes));
  o.config = 0x30;  // receive object: it sends a remote frame with DLC 3
  const Frame remote = o.frame();
  EXPECT_TRUE(remote.remote());
  EXPECT_EQ(remote.dlc(), 3);
  EXPECT_EQ(remote.id(), 0x456u);
}

}  // namespace
}  // namespace canemu::model::i82527
