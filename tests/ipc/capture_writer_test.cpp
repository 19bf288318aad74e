#include "canemu/ipc/capture_writer.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>

#include "../support/temp_dir.hpp"

namespace canemu::ipc {
namespace {

namespace fs = std::filesystem;

using testing::read_file;
using testing::TempDir;

socketcan::Frame frame(uint32_t id, uint8_t len) {
  socketcan::Frame f;
  f.can_id = id;
  f.len = len;
  for (uint8_t i = 0; i < len; ++i) {
    f.data[i] = static_cast<uint8_t>(0x10 + i);
  }
  return f;
}

uint32_t le32(const std::string& s, std::size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) {
    v = (v << 8) | static_cast<uint8_t>(s[at + static_cast<std::size_t>(i)]);
  }
  return v;
}

// A pcap file's records as (seconds, nanoseconds, CAN ID from the big-endian header, length).
struct PcapRecord {
  uint32_t sec, nsec, can_id, size;
  uint8_t len;
  bool operator==(const PcapRecord&) const = default;
};
std::vector<PcapRecord> parse_pcap(const std::string& s) {
  EXPECT_GE(s.size(), 24u);
  EXPECT_EQ(le32(s, 0), 0xA1B23C4Du);
  EXPECT_EQ(le32(s, 20), 227u);
  std::vector<PcapRecord> out;
  for (std::size_t at = 24; at < s.size();) {
    PcapRecord r{};
    r.sec = le32(s, at);
    r.nsec = le32(s, at + 4);
    r.size = le32(s, at + 8);
    EXPECT_EQ(le32(s, at + 12), r.size);
    const auto* p = reinterpret_cast<const uint8_t*>(s.data() + at + 16);
    r.can_id = (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
    r.len = p[4];
    out.push_back(r);
    at += 16 + r.size;
  }
  return out;
}

TEST(CaptureWriter, WritesCandumpLogLines) {
  TempDir dir;
  const auto path = dir.path / "can0.log";
  {
    auto w = CaptureWriter::open({path.string(), CaptureFormat::candump, "can0"});
    ASSERT_TRUE(w) << w.error().message;
    w->record(1'000'250'000, frame(0x123, 2));
    w->record(2'500'000'000, frame(0x12345678 | socketcan::kEffFlag, 0));
    EXPECT_TRUE(w->flush());
    EXPECT_EQ(w->frames(), 2u);
    EXPECT_EQ(w->lost(), 0u);
  }
  EXPECT_EQ(read_file(path),
            "(0000000001.000250) can0 123#1011\n"
            "(0000000002.500000) can0 12345678#\n");
}

TEST(CaptureWriter, WritesPcapThatReadsBack) {
  TempDir dir;
  const auto path = dir.path / "can0.pcap";
  {
    auto w = CaptureWriter::open({path.string(), CaptureFormat::pcap, "can0"});
    ASSERT_TRUE(w) << w.error().message;
    w->record(7, frame(0x7FF, 8));
    socketcan::Frame fd = frame(0x100, 64);
    fd.fd = true;
    fd.flags = socketcan::kFdBrs;
    w->record(1'000'000'001, fd);
  }  // the destructor flushes
  const std::string bytes = read_file(path);
  EXPECT_EQ(bytes.size(), 24u + 16 + 16 + 16 + 72);
  EXPECT_EQ(parse_pcap(bytes),
            (std::vector<PcapRecord>{{0, 7, 0x7FF, 16, 8}, {1, 1, 0x100, 72, 64}}));
}

TEST(CaptureWriter, RotatesBySizeKeepingNumberedFiles) {
  TempDir dir;
  const auto path = dir.path / "can0.log";
  // Each line is 34 bytes: two fit into 80, the third starts a new file.
  auto w = CaptureWriter::open({path.string(), CaptureFormat::candump, "can0", 80, 2});
  ASSERT_TRUE(w) << w.error().message;
  for (int i = 0; i < 7; ++i) {
    w->record(int64_t{i} * 1'000'000'000, frame(0x100 + static_cast<uint32_t>(i), 2));
  }
  EXPECT_TRUE(w->flush());
  EXPECT_EQ(w->rotations(), 3u);
  EXPECT_EQ(w->frames(), 7u);
  EXPECT_EQ(read_file(path), "(0000000006.000000) can0 106#1011\n");
  EXPECT_EQ(read_file(dir.path / "can0.log.1"),
            "(0000000004.000000) can0 104#1011\n(0000000005.000000) can0 105#1011\n");
  EXPECT_EQ(read_file(dir.path / "can0.log.2"),
            "(0000000002.000000) can0 102#1011\n(0000000003.000000) can0 103#1011\n");
  EXPECT_FALSE(fs::exists(dir.path / "can0.log.3"));  // the oldest went
}

TEST(CaptureWriter, EveryRotatedPcapFileHasItsHeader) {
  TempDir dir;
  const auto path = dir.path / "can0.pcap";
  auto w = CaptureWriter::open({path.string(), CaptureFormat::pcap, "can0", 24 + 2 * 32, 5});
  ASSERT_TRUE(w);
  for (int i = 0; i < 3; ++i) {
    w->record(i, frame(0x200 + static_cast<uint32_t>(i), 1));
  }
  EXPECT_TRUE(w->flush());
  EXPECT_EQ(parse_pcap(read_file(dir.path / "can0.pcap.1")),
            (std::vector<PcapRecord>{{0, 0, 0x200, 16, 1}, {0, 1, 0x201, 16, 1}}));
  EXPECT_EQ(parse_pcap(read_file(path)), (std::vector<PcapRecord>{{0, 2, 0x202, 16, 1}}));
}

lin_pcap::Message lin_frame(uint8_t pid, uint8_t length) {
  lin_pcap::Message m;
  m.pid = pid;
  m.length = length;
  m.checksum_type = lin_pcap::ChecksumType::classic;
  return m;
}

TEST(CaptureWriter, WritesLinRecordsUnderLinktypeLin) {
  TempDir dir;
  const auto path = dir.path / "lin0.pcap";
  {
    auto w = CaptureWriter::open({path.string(), CaptureFormat::pcap, "lin0", 0, 10, true});
    ASSERT_TRUE(w) << w.error().message;
    w->record(5, lin_frame(0x50, 2));
    w->record(6, frame(0x123, 2));  // not a LIN message: ignored
    w->record(1'000'000'000, lin_pcap::event(lin_pcap::kEventWakeUp));
    EXPECT_TRUE(w->flush());
    EXPECT_EQ(w->frames(), 2u);
  }
  const std::string s = read_file(path);
  ASSERT_EQ(s.size(), 24u + 2 * (16 + 12));
  EXPECT_EQ(le32(s, 16), 16u);   // snap length
  EXPECT_EQ(le32(s, 20), 212u);  // LINKTYPE_LIN
  EXPECT_EQ(le32(s, 24 + 4), 5u);
  EXPECT_EQ(le32(s, 24 + 8), 12u);
  EXPECT_EQ(static_cast<uint8_t>(s[24 + 16 + 5]), 0x50);
  EXPECT_EQ(le32(s, 24 + 28), 1u);
  EXPECT_EQ(static_cast<uint8_t>(s[24 + 28 + 16 + 4]), 0x4C);  // an event

  // A CAN recording ignores LIN messages.
  const auto can = dir.path / "can0.pcap";
  {
    auto w = CaptureWriter::open({can.string(), CaptureFormat::pcap, "can0"});
    ASSERT_TRUE(w);
    w->record(5, lin_frame(0x50, 2));
  }
  EXPECT_EQ(read_file(can).size(), 24u);
}

TEST(CaptureWriter, RotatedLinFilesHaveTheLinHeader) {
  TempDir dir;
  const auto path = dir.path / "lin0.pcap";
  // Records of 28 and 32 bytes: two fit into 24 + 60.
  auto w = CaptureWriter::open({path.string(), CaptureFormat::pcap, "lin0", 24 + 60, 3, true});
  ASSERT_TRUE(w);
  w->record(1, lin_frame(0x50, 2));
  w->record(2, lin_frame(0x50, 8));
  w->record(3, lin_frame(0x50, 1));
  EXPECT_TRUE(w->flush());
  EXPECT_EQ(w->rotations(), 1u);
  const std::string old = read_file(dir.path / "lin0.pcap.1");
  const std::string now = read_file(path);
  ASSERT_EQ(old.size(), 24u + 28 + 32);
  ASSERT_EQ(now.size(), 24u + 28);
  EXPECT_EQ(le32(old, 20), 212u);
  EXPECT_EQ(le32(now, 20), 212u);
  EXPECT_EQ(le32(now, 24 + 4), 3u);
}

TEST(CaptureWriter, ALinBusHasNoCandumpLog) {
  TempDir dir;
  auto w = CaptureWriter::open(
      {(dir.path / "lin0.log").string(), CaptureFormat::candump, "lin0", 0, 10, true});
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error().message,
            "a candump log holds CAN frames only; LIN bus lin0 is recorded as pcap (LINKTYPE_LIN)");
  EXPECT_FALSE(fs::exists(dir.path / "lin0.log"));
}

TEST(CaptureWriter, AFullDiskCountsTheLostFramesAndSaysWhy) {
  auto w = CaptureWriter::open({"/dev/full", CaptureFormat::candump, "can0"});
  ASSERT_TRUE(w) << w.error().message;
  w->record(0, frame(0x1, 0));
  w->record(1, frame(0x2, 0));
  EXPECT_FALSE(w->flush());
  EXPECT_EQ(w->lost(), 2u);
  EXPECT_EQ(w->frames(), 0u);
  EXPECT_EQ(w->error(), "write /dev/full: No space left on device");
  w->record(2, frame(0x3, 0));
  EXPECT_FALSE(w->flush());
  EXPECT_EQ(w->lost(), 3u);
}

TEST(CaptureWriter, RefusesAPathItCannotOpenNamingIt) {
  auto w = CaptureWriter::open({"/nonexistent-dir/x.log", CaptureFormat::candump, "can0"});
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error().message, "open /nonexistent-dir/x.log: No such file or directory");
  EXPECT_EQ(parse_capture_format("pcap"), CaptureFormat::pcap);
  EXPECT_EQ(parse_capture_format("candump"), CaptureFormat::candump);
  EXPECT_FALSE(parse_capture_format("asc"));
}

}  // namespace
}  // namespace canemu::ipc
