// canemu dump --summary: a JSON line per bus and identifier and interval (dump_summary.hpp).
#include "dump_summary.hpp"

#include <gtest/gtest.h>

#include <initializer_list>

namespace canemu::cli {
namespace {

namespace sc = ipc::socketcan;

sc::Frame frame(uint32_t can_id, std::initializer_list<uint8_t> data, bool fd = false) {
  sc::Frame f;
  f.can_id = can_id;
  f.fd = fd;
  for (const uint8_t b : data) {
    f.data[f.len++] = b;
  }
  return f;
}

sc::Frame remote(uint32_t can_id, uint8_t len) {
  sc::Frame f;
  f.can_id = can_id | sc::kRtrFlag;
  f.len = len;
  return f;
}

TEST(DumpSummary, AnIntervalGivesALinePerBusAndIdentifierInOrder) {
  DumpSummary s({"can0", "can1"});
  s.add(1, 5000, frame(0x123, {0x11}));
  s.add(0, 1000, frame(0x123, {0x11, 0x22}));
  s.add(0, 2000, frame(0x100, {}));
  s.add(0, 3000, frame(0x123, {0x11, 0x33}));
  s.add(0, 4000, frame(sc::kEffFlag | 0x12345678, {0xAB}));
  EXPECT_EQ(s.take(),
            "{\"bus\":\"can0\",\"id\":\"100\",\"count\":1,\"first_ns\":2000,\"last_ns\":2000,"
            "\"data\":\"\",\"changed\":0}\n"
            "{\"bus\":\"can0\",\"id\":\"123\",\"count\":2,\"first_ns\":1000,\"last_ns\":3000,"
            "\"data\":\"1133\",\"changed\":2}\n"
            "{\"bus\":\"can0\",\"id\":\"12345678\",\"count\":1,\"first_ns\":4000,"
            "\"last_ns\":4000,\"data\":\"AB\",\"changed\":0}\n"
            "{\"bus\":\"can1\",\"id\":\"123\",\"count\":1,\"first_ns\":5000,\"last_ns\":5000,"
            "\"data\":\"11\",\"changed\":0}\n");
  // Nothing new: no lines.
  EXPECT_EQ(s.take(), "");
}

TEST(DumpSummary, TheFirstFrameOfAnIntervalIsComparedWithTheLastBeforeIt) {
  DumpSummary s({"can0"});
  s.add(0, 1000, frame(0x7FF, {1, 2, 3}));
  EXPECT_NE(s.take(), "");
  s.add(0, 9000, frame(0x7FF, {1, 2, 4, 5}));  // byte 2 changed, byte 3 is new
  EXPECT_EQ(s.take(),
            "{\"bus\":\"can0\",\"id\":\"7FF\",\"count\":1,\"first_ns\":9000,\"last_ns\":9000,"
            "\"data\":\"01020405\",\"changed\":12}\n");
}

TEST(DumpSummary, ErrorFramesAreCountedPerBus) {
  DumpSummary s({"can0", "can1"});
  s.add(1, 1000, frame(sc::kErrFlag | 0x88, {0, 0, 4, 5, 0, 0, 0, 0}));
  s.add(1, 2000, frame(sc::kErrFlag | 0x88, {0, 0, 4, 5, 0, 0, 0, 0}));
  EXPECT_EQ(s.take(), "{\"bus\":\"can1\",\"error_frames\":2}\n");
  EXPECT_EQ(s.take(), "");
}

TEST(DumpSummary, RemoteAndFdFramesAsCandumpWritesTheirData) {
  DumpSummary s({"fd0"});
  s.add(0, 1000, remote(0x123, 4));
  s.add(0, 2000, frame(0x456, {0xAA, 0xBB}, true));
  EXPECT_EQ(s.take(),
            "{\"bus\":\"fd0\",\"id\":\"123\",\"count\":1,\"first_ns\":1000,\"last_ns\":1000,"
            "\"data\":\"R\",\"changed\":0}\n"
            "{\"bus\":\"fd0\",\"id\":\"456\",\"count\":1,\"first_ns\":2000,\"last_ns\":2000,"
            "\"data\":\"AABB\",\"changed\":0}\n");
}

TEST(DumpSummary, BusNamesAreWrittenAsJsonStrings) {
  DumpSummary s({"odd\"name"});
  s.add(0, 0, frame(0x1, {}));
  EXPECT_TRUE(s.take().starts_with("{\"bus\":\"odd\\\"name\",\"id\":\"001\","));
}

TEST(DumpSummary, ChangedBytesFollowTheDataTexts) {
  EXPECT_EQ(changed_bytes(frame(1, {1, 2}), frame(1, {1, 2})), 0u);
  EXPECT_EQ(changed_bytes(frame(1, {1, 2}), frame(1, {9, 2})), 0b01u);
  EXPECT_EQ(changed_bytes(frame(1, {1, 2, 3}), frame(1, {1})), 0b110u);
  EXPECT_EQ(changed_bytes(frame(1, {}), frame(1, {7, 7})), 0b11u);
  // A remote frame against data: every byte of the data, at least one.
  EXPECT_EQ(changed_bytes(remote(1, 2), frame(1, {1, 2, 3})), 0b111u);
  EXPECT_EQ(changed_bytes(frame(1, {}), remote(1, 0)), 0b1u);
  EXPECT_EQ(changed_bytes(remote(1, 2), remote(1, 5)), 0u);
  // A 64-byte CAN FD frame's last byte is bit 63.
  sc::Frame a;
  a.fd = true;
  a.len = 64;
  sc::Frame b = a;
  b.data[63] = 1;
  EXPECT_EQ(changed_bytes(a, b), uint64_t{1} << 63);
}

}  // namespace
}  // namespace canemu::cli
