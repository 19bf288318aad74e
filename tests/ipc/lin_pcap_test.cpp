#include "canemu/ipc/lin_pcap.hpp"

#include <cstdio>
#include <initializer_list>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../support/lin_reference.hpp"

namespace canemu::ipc::lin_pcap {
namespace {

using test_support::lin::hex;
using test_support::lin::inverted_sum;
using test_support::lin::pid;

Message frame(int id, std::initializer_list<int> data, ChecksumType kind, uint8_t checksum) {
  Message m;
  m.pid = pid(id);
  m.checksum_type = kind;
  m.checksum = checksum;
  for (int b : data) {
    m.data[m.length++] = static_cast<uint8_t>(b);
  }
  return m;
}

// A frame record as encode writes it, in hex, field by field: version 1 (four bytes), the byte of
// length, checksum type and message type, the PID, the checksum, the error bits, then the
// payload (words of four bytes).
std::string frame_record(const char* kinds, const char* protected_id, const char* checksum,
                         const char* errors, const char* payload) {
  return std::string("01000000") + kinds + protected_id + checksum + errors + payload;
}

TEST(LinPcap, TheTestsOwnParityAndChecksumsMatchKnownFrames) {
  // From LIN 2.x: IDs 3Ch and 3Dh are 3Ch and 7Dh protected; the frames canemu send's
  // documentation shows.
  EXPECT_EQ(pid(0x3C), 0x3C);
  EXPECT_EQ(pid(0x3D), 0x7D);
  EXPECT_EQ(pid(0x00), 0x80);
  EXPECT_EQ(pid(0x10), 0x50);
  EXPECT_EQ(pid(0x33), 0x73);
  EXPECT_EQ(inverted_sum({0x50, 0x01, 0x00}), 0xAE);
  EXPECT_EQ(inverted_sum({0x73, 0xAA, 0xBB}), 0x26);
}

TEST(LinPcap, TheHeaderCarriesLinktypeLin) {
  // Magic (nanoseconds), version 2.4, zone 0, sigfigs 0, snap length 16, link type 212.
  EXPECT_EQ(hex(pcap_file_header()),
            "4D3CB2A1020004000000000000000000"
            "10000000D4000000");
}

TEST(LinPcap, TheWorkedExampleOfTheHeader) {
  const Message m = frame(0x10, {0x01, 0x00}, ChecksumType::enhanced, inverted_sum({0x50, 1, 0}));
  std::vector<uint8_t> out;
  append_pcap_record(out, 3'333'333, m);
  EXPECT_EQ(hex(out),
            "00000000D5DC32000C0000000C000000"
            "0100000022"
            "50"
            "AE"
            "00"
            "01000000");
}

TEST(LinPcap, FramesOfEightBytesTakeTwoPayloadWords) {
  // The go-to-sleep command: 3Ch 00 FF FF FF FF FF FF FF, classic checksum (data only).
  const uint8_t cs = inverted_sum({0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF});
  EXPECT_EQ(cs, 0x00);
  const Message m =
      frame(0x3C, {0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}, ChecksumType::classic, cs);
  // Length 8, type 0, classic 1: 81h.
  EXPECT_EQ(hex(encode(m)), frame_record("81", "3C", "00", "00", "00FFFFFFFFFFFFFF"));

  const Message classic =
      frame(0x33, {0xAA, 0xBB}, ChecksumType::classic, inverted_sum({0xAA, 0xBB}));
  EXPECT_EQ(hex(encode(classic)), frame_record("21", "73", "99", "00", "AABB0000"));

  const Message five = frame(0x01, {1, 2, 3, 4, 5}, ChecksumType::enhanced,
                             inverted_sum({pid(0x01), 1, 2, 3, 4, 5}));
  EXPECT_EQ(pid(0x01), 0xC1);
  EXPECT_EQ(hex(encode(five)), frame_record("52", "C1", "2F", "00", "0102030405000000"));
}

TEST(LinPcap, ErrorsAreBitsBesideWhatWasReceived) {
  // A header nobody answered: no payload, checksum unknown, the PID sent.
  Message none;
  none.pid = pid(0x20);
  none.errors = kErrorNoSlaveResponse;
  EXPECT_EQ(pid(0x20), 0x20);
  EXPECT_EQ(hex(encode(none)), frame_record("00", "20", "00", "01", "00000000"));

  // A response whose checksum matches neither kind: the characters as received.
  Message bad = frame(0x10, {0x01, 0x00}, ChecksumType::unknown, 0xAF);
  bad.errors = kErrorChecksum;
  EXPECT_EQ(hex(encode(bad)), frame_record("20", "50", "AF", "08", "01000000"));

  Message parity;
  parity.errors = kErrorParity;
  EXPECT_EQ(hex(encode(parity)), frame_record("00", "00", "00", "04", "00000000"));

  Message reserved = frame(0x3E, {0x11}, ChecksumType::enhanced, inverted_sum({pid(0x3E), 0x11}));
  reserved.errors = kErrorInvalidId;
  EXPECT_EQ(pid(0x3E), 0xFE);
  EXPECT_EQ(hex(encode(reserved)), frame_record("12", "FE", "EF", "10", "11000000"));
}

TEST(LinPcap, EventsCarryTheirTypeBigEndian) {
  // Length 4, type 3 (event), checksum type 0: 4Ch; PID, checksum and errors 0.
  EXPECT_EQ(hex(encode(event(kEventWakeUp))),
            "01000000"
            "4C000000"
            "B0B00004");
  EXPECT_EQ(hex(encode(event(kEventGoToSleep))),
            "01000000"
            "4C000000"
            "B0B00001");
  Message noisy = event(kEventInactivity);
  noisy.pid = 0x50;
  noisy.errors = 0x01;
  noisy.checksum_type = ChecksumType::enhanced;
  EXPECT_EQ(hex(encode(noisy)),
            "01000000"
            "4C000000"
            "B0B00002");
}

TEST(LinPcap, TimeStampsAreSecondsAndNanoseconds) {
  std::vector<uint8_t> out;
  append_pcap_record(out, 4'000'000'001, event(kEventInactivity));
  append_pcap_record(out, -5, event(kEventWakeUp));
  EXPECT_EQ(hex(out),
            "04000000"
            "01000000"
            "0C000000"
            "0C000000"
            "010000004C000000B0B00002"
            "00000000"
            "00000000"
            "0C000000"
            "0C000000"
            "010000004C000000B0B00004");
  Message long_one;
  long_one.length = 12;
  EXPECT_EQ(encode(long_one).size(), 16u);
  EXPECT_EQ(encode(long_one)[4], 0x80);
}

}  // namespace
}  // namespace canemu::ipc::lin_pcap
