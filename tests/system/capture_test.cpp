// Recordings against a real canemud in stepped time: canemu dump --format pcap, canemu record,
// and the daemon's own [[recorder]] with its line in canemu status.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "../support/lin_reference.hpp"
#include "../support/temp_dir.hpp"

#include "cli_process.hpp"
#include "cli_run_support.hpp"
#include "daemon_process.hpp"
#include "shell_support.hpp"

namespace canemu {
namespace {

namespace fs = std::filesystem;
using testing::connect;
using testing::Daemon;

using testing::read_file;
using testing::run_shell;
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

// What tshark (Wireshark; scripts/apt-packages.txt) makes of a capture: `fields` (-e ...) of
// every record, one line each, separated by `separator` (tshark's -E separator: /s a space, /t
// a tab).
std::string tshark_fields(const fs::path& file, const std::string& fields,
                          const std::string& separator = "/s") {
  const auto tshark =
      run_shell("tshark -r " + file.string() + " -T fields -E separator=" + separator + " " +
                fields + " 2>/dev/null");
  EXPECT_EQ(tshark.status, 0) << "tshark missing? make deps installs it";
  return tshark.out;
}

// canemu send of kFrames on can0, in one step of 1 ms; it must succeed.
void send_the_frames(const Daemon& d) {
  Cli send(d, {"send", "can0", kFrames[0], kFrames[1], "--step", "1ms"});
  EXPECT_EQ(send.wait(), 0) << Cli::read_all(send.err);
}

// canemu `args` (a recording of can0) started against `d`, where a node acknowledges on can0,
// and kFrames sent once it listens. Call it in ASSERT_NO_FATAL_FAILURE.
void record_the_frames(std::optional<Cli>& cli, const Daemon& d, std::vector<std::string> args) {
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  ASSERT_NO_FATAL_FAILURE(start_listening(cli, d, std::move(args)));
  send_the_frames(d);
}

TEST(CliCapture, DumpWritesPcapWithTheSimulatedInstants) {
  TempDir dir;
  Daemon d;
  const std::string file = (dir.path / "can0.pcap").string();
  std::optional<Cli> dump;
  ASSERT_NO_FATAL_FAILURE(
      record_the_frames(dump, d, {"dump", "can0", "--format", "pcap", "-o", file, "-n", "2"}));
  EXPECT_EQ(dump->wait(), 0) << Cli::read_all(dump->err);
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
  const std::string file = (dir.path / "can0.log").string();
  std::optional<Cli> record;
  ASSERT_NO_FATAL_FAILURE(record_the_frames(record, d, {"record", "can0", "-o", file, "-n", "2"}));
  EXPECT_EQ(record->wait(), 0);
  EXPECT_EQ(Cli::read_all(record->err),
            "canemu: listening on can0 as eph2 (listen-only, 500000 bit/s, time stamps in "
            "simulated seconds)\ncanemu: 2 frame(s) recorded in " +
                file + " (candump)\n");
  EXPECT_EQ(read_file(file), kLog);

  EXPECT_NE(refusal_of(d, {"record", "can0", "-o", "/nonexistent-dir/x.log"})
                .find("open /nonexistent-dir/x.log: No such file or directory"),
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
  send_the_frames(d);
  // Written when the step ended, before its reply.
  EXPECT_EQ(read_file(dir.path / "can0.log"), kLog);
  EXPECT_EQ(read_file(dir.path / "can0.pcap").size(), 24u + 2 * 32);
  // Wireshark reads the capture back.
  EXPECT_EQ(tshark_fields(dir.path / "can0.pcap",
                          "-e frame.time_relative -e can.id -e can.flags.xtd -e can.flags.rtr "
                          "-e can.len -e data.data",
                          "/t"),
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
  const std::string j = output_of(d, {"status", "--json"});
  EXPECT_NE(j.find("\"recorders\" : [{\"bus\" : \"can0\",\"bytes\" : 71,\"error\" : \"\","
                   "\"errors\" : true,\"format\" : \"candump\",\"frames\" : 2,\"lost\" : 0,"
                   "\"path\" : \"" +
                   (dir.path / "can0.log").string() + "\",\"rotations\" : 0},"),
            std::string::npos)
      << j;
  const std::string m = output_of(d, {"metrics"});
  EXPECT_NE(m.find("canemu_recorder_frames_total{bus=\"can0\",path=\"" +
                   (dir.path / "can0.log").string() + "\"} 2\n"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("# TYPE canemu_bridge_dropped_total counter\n"), std::string::npos) << m;
}

// ---- LIN: pcap with LINKTYPE_LIN (212), at 19200 bit/s

// LIN 2.x's protected identifier and checksum, computed independently of the model.
using test_support::lin::inverted_sum;
using test_support::lin::pid;

// Bit k of a frame at 19200 bit/s from its break, rounded down to the ns.
int64_t bits_ns(int64_t bits) {
  return bits * 1'000'000'000 / 19200;
}

// A pcap record header: seconds, nanoseconds and twice the length, little-endian, as hex.
std::string record_header(int64_t ns, int size) {
  const auto le = [](uint32_t v) {
    char text[9];
    std::snprintf(text, sizeof text, "%02X%02X%02X%02X", v & 0xFF, (v >> 8) & 0xFF,
                  (v >> 16) & 0xFF, v >> 24);
    return std::string(text);
  };
  return le(static_cast<uint32_t>(ns / 1'000'000'000)) +
         le(static_cast<uint32_t>(ns % 1'000'000'000)) + le(static_cast<uint32_t>(size)) +
         le(static_cast<uint32_t>(size));
}

std::string hex2(int v) {
  char two[3];
  std::snprintf(two, sizeof two, "%02X", v);
  return two;
}

constexpr const char* kLinFileHeader =
    "4D3CB2A1020004000000000000000000"
    "10000000D4000000";

// canemud's [[recorder]] on a LIN bus whose commander is a simulated node: a frame the commander
// answers itself, one a simulated responder answers and a header nobody answers, every record at
// its exact simulated instant.
TEST(DaemonRecorder, RecordsALinBusAsLinktypeLin) {
  TempDir dir;
  const fs::path config = dir.path / "canemu.toml";
  std::ofstream(config)
      << "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n"
         "[[lin_node]]\nname = \"bcm\"\nbus = \"lin0\"\nschedule = \"normal\"\n"
         "[[lin_node.schedules]]\nname = \"normal\"\n"
         "slots = [{ frame = 0x10, delay = \"10ms\" }, "
         "{ frame = 0x20, delay = \"10ms\" }, { frame = 0x21, delay = \"10ms\" }]\n"
         "[[lin_node.response]]\nid = 0x10\ndata = [0x01, 0x00]\n"
         "[[lin_node]]\nname = \"door\"\nbus = \"lin0\"\n"
         "[[lin_node.response]]\nid = 0x20\ndata = [0x00, 0x01, 0x64]\n"
         "[[recorder]]\nbus = \"lin0\"\npath = \"lin0.pcap\"\n";
  Daemon d("stepped", {"--config", config.string()});
  Cli step(d, {"time", "step", "30ms"});
  EXPECT_EQ(step.wait(), 0) << Cli::read_all(step.err);
  // 10h: 34 header bits and 3 characters. 20h from 10 ms: 4 characters. 21h from 20 ms: the
  // no-response error after the longest response (34 + 14 x 9 bits). Written when the step
  // ended.
  const std::string expected = std::string(kLinFileHeader) + record_header(bits_ns(64), 12) +
                               "01000000" + "22" + hex2(pid(0x10)) +
                               hex2(inverted_sum({pid(0x10), 0x01, 0x00})) + "00" + "01000000" +
                               record_header(10'000'000 + bits_ns(74), 12) + "01000000" + "32" +
                               hex2(pid(0x20)) + hex2(inverted_sum({pid(0x20), 0x00, 0x01, 0x64})) +
                               "00" + "00016400" + record_header(20'000'000 + bits_ns(160), 12) +
                               "01000000" + "00" + hex2(pid(0x21)) + "00" + "01" + "00000000";
  EXPECT_EQ(hex(read_file(dir.path / "lin0.pcap")), expected);
  EXPECT_EQ(record_header(bits_ns(64), 12).substr(8, 8), "D5DC3200");  // 3333333 ns

  // Wireshark's LIN dissector reads it back.
  EXPECT_EQ(tshark_fields(dir.path / "lin0.pcap",
                          "-e frame.time_epoch -e lin.frame_id -e lin.checksum_type -e "
                          "lin.checksum -e lin.errors -e data.data"),
            "0.003333333 0x10 2 0xae 0x00 0100\n"
            "0.013854166 0x20 2 " +
                fmt::format("{:#04x}", inverted_sum({pid(0x20), 0x00, 0x01, 0x64})) +
                " 0x00 000164\n"
                "0.028333333 0x21 0 0x00 0x01 \n");

  const std::string text = output_of(d, {"status"});
  EXPECT_NE(text.find("lin0         pcap             3          108       0        0 " +
                      (dir.path / "lin0.pcap").string() + "\n"),
            std::string::npos)
      << text;
}

// canemu record on a LIN bus writes pcap (a LIN bus has no candump log), with the instants of
// its monitor (microseconds); candump into a file is refused naming the bus.
TEST(CliCapture, RecordOnALinBusWritesLinktypeLin) {
  TempDir dir;
  Daemon d;
  const fs::path file = dir.path / "lin0.rec";
  std::optional<Cli> record;
  ASSERT_NO_FATAL_FAILURE(start_listening_lin(
      record, d,
      {"record", "lin0", "-o", file.string(), "-n", "4"}));  // the recorder's line is started
  Cli send(d, {"send", "lin0", "33#AABB", "20#", "sleep", "wakeup", "--step", "30ms"});
  EXPECT_EQ(send.wait(), 1) << Cli::read_all(send.err);  // 20# ends in an error
  EXPECT_EQ(record->wait(), 0);
  const std::string err = Cli::read_all(record->err);
  EXPECT_NE(err.find("(LIN, the rate of each header, time stamps in simulated seconds)\n"
                     "canemu: 5 record(s) recorded in " +
                     file.string() + " (pcap, LINKTYPE_LIN)\n"),
            std::string::npos)
      << err;
  // The instants of Cli.SendAndDumpOnALinBus, in whole microseconds; the VCI's error message
  // tells no identifier (PID 0).
  const std::string expected =
      std::string(kLinFileHeader) + record_header(3'333'000, 12) + "01000000" + "22" +
      hex2(pid(0x33)) + hex2(inverted_sum({pid(0x33), 0xAA, 0xBB})) + "00" + "AABB0000" +
      record_header(12'333'000, 12) + "01000000" + "00" + "00" + "00" + "01" + "00000000" +
      record_header(19'458'000, 16) + "01000000" + "81" + hex2(pid(0x3C)) +
      hex2(inverted_sum({0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF})) + "00" +
      "00FFFFFFFFFFFFFF" + record_header(19'458'000, 12) + "010000004C000000B0B00001" +
      record_header(20'250'000, 12) + "010000004C000000B0B00004";
  EXPECT_EQ(hex(read_file(file)), expected);
  EXPECT_EQ(tshark_fields(file, "-e lin.message_type -e lin.frame_id -e lin.event_id"),
            "0 0x33 \n0 0x00 \n0 0x3c \n3  0xb0b00001\n3  0xb0b00004\n");

  for (const std::string tool : {"record", "dump"}) {
    const fs::path log = dir.path / "lin0.log";
    EXPECT_EQ(refusal_of(d, {tool, "lin0", "--format", "candump", "-o", log.string()}),
              "canemu: a candump log holds CAN frames only; LIN bus lin0 is recorded as pcap "
              "(LINKTYPE_LIN)\n");
    EXPECT_FALSE(fs::exists(log));
  }
}

// canemu bridge against canemud on a host whose kernel may have no CAN at all: every failure
// says which interface and why; the bridge itself is tested in tests/daemon and tests/guest.
TEST(CliBridge, AddListAndRemoveSayWhatIsWrong) {
  Daemon d;
  Cli add(d, {"bridge", "add", "can0", "vcan-none"});
  EXPECT_EQ(add.wait(), 1);
  EXPECT_NE(Cli::read_all(add.err).find("canemu: canemud: bad_argument: bridge to vcan-none: "),
            std::string::npos);
  EXPECT_NE(refusal_of(d, {"bridge", "add", "can9", "vcan0"}).find("no bus named \"can9\""),
            std::string::npos);
  EXPECT_NE(
      refusal_of(d, {"bridge", "add", "can0", "a/b"}).find("\"a/b\" is not an interface name"),
      std::string::npos);
  EXPECT_EQ(output_of(d, {"bridge", "list", "--json"}), "[]\n");
  EXPECT_NE(refusal_of(d, {"bridge", "remove", "vcan0"}).find("no bridge on interface \"vcan0\""),
            std::string::npos);
  Cli restart(d, {"bridge", "restart", "vcan0"});
  EXPECT_EQ(restart.wait(), 1);
  EXPECT_EQ(Cli::read_all(restart.err),
            "canemu: canemud: bad_argument: no bridge on interface \"vcan0\"\n");
  for (const std::string ms : {"-5", "60001"}) {
    EXPECT_EQ(refusal_of(d, {"bridge", "add", "can0", "vcan0", "--restart-ms", ms}),
              "canemu: --restart-ms " + ms +
                  " is outside 0..60000 (ms after bus-off; 0: stay "
                  "bus-off)\n");
  }
  Cli huge(d, {"bridge", "add", "can0", "vcan0", "--restart-ms", "99999999999999999999"});
  EXPECT_NE(huge.wait(), 0);
  EXPECT_NE(Cli::read_all(huge.err).find("--restart-ms"), std::string::npos);
  // canemud checks it too, for clients other than canemu.
  auto c = connect(d, "raw");
  auto req = ipc::make_message<ipc::BridgeAddRequest>();
  ipc::copy_name(req.bus, "can0");
  ipc::copy_name(req.interface, "vcan0");
  req.restart_ms = 70'000;
  auto r = c.call<ipc::BridgeAddRequest, ipc::BridgeAddReply>(req);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("restart_ms 70000 is outside 0..60000"), std::string::npos)
      << r.error().message;
}

// canemu bridge with --lcm, on LCM's in-process memq:// provider (no network needed; the bridge
// between processes is tested in tests/python/test_lcm_bridge.py).
TEST(CliBridge, AnLcmBridgeIsAddedListedRestartedAndRemovedByItsBus) {
#ifndef CANEMU_HAVE_LCM
  GTEST_SKIP() << "canemu was built without LCM";
#endif
  Daemon d;
  Cli add(d, {"bridge", "add", "can0", "--lcm", "memq://", "--restart-ms", "10"});
  EXPECT_EQ(Cli::read_all(add.out),
            "can0 bridged to LCM channels CANEMU_CAN0_* on memq:// (restart 10 ms after "
            "bus-off)\n");
  EXPECT_EQ(add.wait(), 0) << Cli::read_all(add.err);
  EXPECT_EQ(refusal_of(d, {"bridge", "add", "can0", "--lcm", "memq://"}),
            "canemu: canemud: bad_argument: can0 has an LCM bridge already\n");
  Cli list(d, {"bridge", "list", "--json"});
  const std::string json = Cli::read_all(list.out);
  EXPECT_EQ(list.wait(), 0);
  EXPECT_NE(json.find("\"kind\" : \"lcm\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"tx\" : \"CANEMU_CAN0_TX\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"url\" : \"memq://\""), std::string::npos) << json;
  const std::string text = output_of(d, {"bridge", "list"});
  EXPECT_EQ(text.substr(0, 10), "LCM-BRIDGE") << text;
  EXPECT_EQ(refusal_of(d, {"bridge", "restart", "can0", "--lcm"}),
            "canemu: canemud: bad_argument: LCM bridge of can0 is error-active, not bus-off: "
            "nothing to restart\n");
  Cli remove(d, {"bridge", "remove", "can0", "--lcm"});
  EXPECT_EQ(Cli::read_all(remove.out), "LCM bridge of can0 removed\n");
  EXPECT_EQ(remove.wait(), 0);
  EXPECT_EQ(refusal_of(d, {"bridge", "remove", "can0", "--lcm"}),
            "canemu: canemud: bad_argument: no LCM bridge on bus \"can0\"\n");
  EXPECT_EQ(refusal_of(d, {"bridge", "add", "can0"}),
            "canemu: which interface? canemu bridge add BUS INTERFACE, or BUS --lcm [URL], or BUS "
            "--dds [DOMAIN/PARTITION]\n");
  Cli both(d, {"bridge", "add", "can0", "vcan0", "--lcm"});
  EXPECT_EQ(both.wait(), 1);
  EXPECT_NE(Cli::read_all(both.err).find("an LCM bridge has no INTERFACE"), std::string::npos);
  EXPECT_EQ(refusal_of(d, {"bridge", "add", "can0", "--lcm", "--prefix", "A B"}),
            "canemu: canemud: bad_argument: \"A B\" is not a channel prefix (letters, digits, "
            "'_', '-', '.', '/')\n");
  EXPECT_NE(refusal_of(d, {"bridge", "add", "can0", "--lcm", "nowhere"})
                .find("\"nowhere\" is not an LCM URL"),
            std::string::npos);
  EXPECT_EQ(refusal_of(d, {"bridge", "add", "can0", "--lcm", "--dds"}),
            "canemu: --lcm or --dds, not both\n");
  EXPECT_EQ(refusal_of(d, {"bridge", "add", "can0", "vcan0", "--prefix", "X_"}),
            "canemu: --prefix is for LCM and DDS bridges (--lcm, --dds)\n");
}

}  // namespace
}  // namespace canemu
