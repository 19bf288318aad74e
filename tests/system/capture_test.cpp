// Recordings against a real canemud in stepped time: canemu dump --format pcap, canemu record,
// and the daemon's own [[recorder]] with its line in canemu status.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "../support/temp_dir.hpp"

#include "cli_process.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

namespace fs = std::filesystem;
using testing::connect;
using testing::Daemon;

using testing::read_file;
using testing::TempDir;

std::string hex(const std::string& bytes) {
  std::string s;
  for (unsigned char b : bytes) {
    char two[3];
    std::snprintf(two, sizeof two, "%02X", b);
    s += two;
  }
  return s;
}

// The frames of Cli.SendAndDumpSpeakCanUtilsSyntax: each at the end of its EOF.
const std::vector<std::string> kFrames = {"123#1122", "12345678#R4"};
constexpr const char* kLog =
    "(0000000000.000124) can0 123#1122\n"
    "(0000000000.000258) can0 12345678#R4\n";

TEST(CliCapture, DumpWritesPcapWithTheSimulatedInstants) {
  TempDir dir;
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  auto watcher = connect(d, "watcher");
  ASSERT_TRUE(watcher.subscribe(ipc::kEventDevices));
  const std::string file = (dir.path / "can0.pcap").string();
  Cli dump(d, {"dump", "can0", "--format", "pcap", "-o", file, "-n", "2"});
  ASSERT_TRUE(watcher.next_notification(10'000));
  Cli send(d, {"send", "can0", kFrames[0], kFrames[1], "--step", "1ms"});
  EXPECT_EQ(send.wait(), 0) << Cli::read_all(send.err);
  EXPECT_EQ(dump.wait(), 0) << Cli::read_all(dump.err);
  EXPECT_EQ(hex(read_file(file)),
            "4D3CB2A1020004000000000000000000"
            "48000000E3000000"
            // 0.000124000 s, 16 bytes: 0x123, len 2, 11 22
            "0000000060E401001000000010000000"
            "00000123020000001122000000000000"
            // 0.000258000 s: 0x12345678 | EFF | RTR, len 4
            "00000000D0EF03001000000010000000"
            "D2345678040000000000000000000000");
}

TEST(CliCapture, RecordListensOnlyAndWritesACandumpLog) {
  TempDir dir;
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  auto watcher = connect(d, "watcher");
  ASSERT_TRUE(watcher.subscribe(ipc::kEventDevices));
  const std::string file = (dir.path / "can0.log").string();
  Cli record(d, {"record", "can0", "-o", file, "-n", "2"});
  ASSERT_TRUE(watcher.next_notification(10'000));
  Cli send(d, {"send", "can0", kFrames[0], kFrames[1], "--step", "1ms"});
  EXPECT_EQ(send.wait(), 0) << Cli::read_all(send.err);
  EXPECT_EQ(record.wait(), 0);
  EXPECT_EQ(Cli::read_all(record.err),
            "canemu: listening on can0 as eph2 (listen-only, 500000 bit/s, time stamps in "
            "simulated seconds)\ncanemu: 2 frame(s) recorded in " +
                file + " (candump)\n");
  EXPECT_EQ(read_file(file), kLog);

  Cli bad(d, {"record", "can0", "-o", "/nonexistent-dir/x.log"});
  EXPECT_EQ(bad.wait(), 1);
  EXPECT_NE(Cli::read_all(bad.err).find("open /nonexistent-dir/x.log: No such file or directory"),
            std::string::npos);
}

TEST(DaemonRecorder, RecordsFromTheStartAndShowsInStatus) {
  TempDir dir;
  const fs::path config = dir.path / "canemu.toml";
  std::ofstream(config) << "[[bus]]\nname = \"can0\"\n"
                           "[[recorder]]\nbus = \"can0\"\npath = \"can0.log\"\n"
                           "[[recorder]]\nbus = \"can0\"\npath = \"can0.pcap\"\n";
  Daemon d("stepped", {"--config", config.string()});
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  Cli send(d, {"send", "can0", kFrames[0], kFrames[1], "--step", "1ms"});
  EXPECT_EQ(send.wait(), 0) << Cli::read_all(send.err);
  // Written when the step ended, before its reply.
  EXPECT_EQ(read_file(dir.path / "can0.log"), kLog);
  EXPECT_EQ(read_file(dir.path / "can0.pcap").size(), 24u + 2 * 32);
  // Wireshark reads the capture back (tshark is in scripts/apt-packages.txt).
  const std::string command = "tshark -r " + (dir.path / "can0.pcap").string() +
                              " -T fields -e frame.time_relative -e can.id -e can.flags.xtd"
                              " -e can.flags.rtr -e can.len -e data.data 2>/dev/null";
  FILE* tshark = ::popen(command.c_str(), "r");
  ASSERT_NE(tshark, nullptr);
  std::string fields;
  char line[256];
  while (std::fgets(line, sizeof line, tshark) != nullptr) {
    fields += line;
  }
  EXPECT_EQ(::pclose(tshark), 0) << "tshark missing? make deps installs it";
  EXPECT_EQ(fields,
            "0.000000000\t291\t0\t0\t2\t1122\n"
            "0.000134000\t305419896\t1\t1\t4\t00000000\n");

  Cli status(d, {"status"});
  const std::string text = Cli::read_all(status.out);
  EXPECT_EQ(status.wait(), 0);
  EXPECT_NE(text.find("RECORDER     FORMAT      FRAMES        BYTES ROTATED     LOST FILE\n"
                      "can0         candump          2           71       0        0 " +
                      (dir.path / "can0.log").string() + "\n"),
            std::string::npos)
      << text;
  Cli json(d, {"status", "--json"});
  const std::string j = Cli::read_all(json.out);
  EXPECT_NE(j.find("\"recorders\" : [{\"bus\" : \"can0\",\"bytes\" : 71,\"error\" : \"\","
                   "\"errors\" : true,\"format\" : \"candump\",\"frames\" : 2,\"lost\" : 0,"
                   "\"path\" : \"" +
                   (dir.path / "can0.log").string() + "\",\"rotations\" : 0},"),
            std::string::npos)
      << j;
}

// canemu bridge against canemud on a host whose kernel may have no CAN at all: every failure
// says which interface and why; the bridge itself is tested in tests/daemon and tests/guest.
TEST(CliBridge, AddListAndRemoveSayWhatIsWrong) {
  Daemon d;
  Cli add(d, {"bridge", "add", "can0", "vcan-none"});
  EXPECT_EQ(add.wait(), 1);
  EXPECT_NE(Cli::read_all(add.err).find("canemu: canemud: bad_argument: bridge to vcan-none: "),
            std::string::npos);
  Cli nobus(d, {"bridge", "add", "can9", "vcan0"});
  EXPECT_EQ(nobus.wait(), 1);
  EXPECT_NE(Cli::read_all(nobus.err).find("no bus named \"can9\""), std::string::npos);
  Cli badname(d, {"bridge", "add", "can0", "a/b"});
  EXPECT_EQ(badname.wait(), 1);
  EXPECT_NE(Cli::read_all(badname.err).find("\"a/b\" is not an interface name"), std::string::npos);
  Cli list(d, {"bridge", "list", "--json"});
  EXPECT_EQ(Cli::read_all(list.out), "[]\n");
  EXPECT_EQ(list.wait(), 0);
  Cli remove(d, {"bridge", "remove", "vcan0"});
  EXPECT_EQ(remove.wait(), 1);
  EXPECT_NE(Cli::read_all(remove.err).find("no bridge on interface \"vcan0\""), std::string::npos);
}

}  // namespace
}  // namespace canemu
