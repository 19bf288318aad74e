// The canemu command line against a real canemud: send and dump in stepped time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include <grp.h>
#include <sys/stat.h>

#include <fmt/format.h>

#include "../support/temp_dir.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "cli_process.hpp"
#include "cli_run_support.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

using testing::connect;
using testing::Daemon;
using testing::readable;
using testing::TempDir;

// canemu send `args` against `d` while `dump` listens: send exits `code`, and both print
// `expected`.
void expect_sent_and_dumped(Cli& dump, const Daemon& d, std::vector<std::string> args, int code,
                            const std::string& expected) {
  Cli send(d, std::move(args));
  const std::string sent = Cli::read_all(send.out);
  EXPECT_EQ(send.wait(), code) << Cli::read_all(send.err);
  EXPECT_EQ(sent, expected);
  EXPECT_EQ(Cli::read_all(dump.out), expected);
}

TEST(Cli, SendAndDumpSpeakCanUtilsSyntax) {
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  std::optional<Cli> dump;
  ASSERT_NO_FATAL_FAILURE(
      start_listening(dump, d, {"dump", "can0", "-n", "3"}));  // the dump's device is there
  // Each frame at the end of its EOF: 62 bits, then 3 + 64, then 3 + 108 bits at 2 us.
  expect_sent_and_dumped(
      *dump, d,
      {"send", "can0", "123#1122", "12345678#R4", "7FF#0102030405060708", "--step", "1ms"}, 0,
      "(0000000000.000124) can0 123#1122\n"
      "(0000000000.000258) can0 12345678#R4\n"
      "(0000000000.000500) can0 7FF#0102030405060708\n");
  EXPECT_EQ(dump->wait(), 0);
}

// On the default configuration's LIN bus: send publishes, sends a header nobody answers and the
// go-to-sleep command and a wake-up pulse (250 us), one after another (each at the next whole
// millisecond after the last one's outcome); dump shows the same.
TEST(CliLin, SendAndDumpOnALinBus) {
  Daemon d;
  std::optional<Cli> dump;
  ASSERT_NO_FATAL_FAILURE(
      start_listening_lin(dump, d, {"dump", "lin0", "-n", "4"}));  // the dump's line is started
  // 34 + 30 bits from 0; the header from 4 ms, no response 160 bits after it; the
  // go-to-sleep command from 13 ms, 124 bits (at 19200 bit/s). send exits 1: a frame ended in an
  // error.
  expect_sent_and_dumped(
      *dump, d, {"send", "lin0", "33#AABB", "20#", "sleep", "wakeup", "--step", "30ms"}, 1,
      "(0000000000.003333) lin0 33#AABB pid 73 enhanced checksum 26\n"
      "(0000000000.012333) lin0 error no-response\n"
      "(0000000000.019458) lin0 3C#00FFFFFFFFFFFFFF pid 3C classic checksum 00 go-to-sleep\n"
      "(0000000000.020250) lin0 wake-up\n");
  EXPECT_EQ(dump->wait(), 0);
  EXPECT_EQ(refusal_of(d, {"send", "lin0", "40#01", "--step", "1ms"}),
            "canemu: '40#01': a LIN frame is ID#DATA, ID# (the header alone), sleep or wakeup, "
            "with ID 00..3F in hex\n");
}

// On a CAN FD bus the ephemeral nodes are CAN FD controllers: FD frames with the rate switch go
// out and are logged in candump's FD syntax.
TEST(Cli, OnACanFdBusFdFramesGoOutWithTheRateSwitch) {
  TempDir dir;
  const std::string file = (dir.path / "fd.toml").string();
  FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs(
      "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\n"
      "data_bitrate = 2000000\n",
      f);
  std::fclose(f);
  Daemon d("stepped", {"--config=" + file});
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "fd0");
  std::optional<Cli> dump;
  ASSERT_NO_FATAL_FAILURE(start_listening(dump, d, {"dump", "fd0", "-n", "2"}));
  // The FD frame's exact length with the data phase at 2 Mbit/s, then 3 bits of intermission
  // and the classic frame.
  const auto fd = model::Frame::fd_frame(
      0x123, std::vector<uint8_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, false, true);
  const model::BitTiming nominal{5'000'000, 1, 7, 2, 1, 1};
  const model::BitTiming data{20'000'000, 1, 7, 2, 1, 1};
  const int64_t first = model::frame_duration(model::encode(*fd), nominal, data).ns();
  const auto classic = model::Frame::classic(0x456, std::vector<uint8_t>{0x11, 0x22});
  const int64_t second =
      first + 3 * 2000 + model::frame_duration(model::encode(*classic), nominal).ns();
  expect_sent_and_dumped(
      *dump, d, {"send", "fd0", "123##1000102030405060708090A0B", "456#1122", "--step", "1ms"}, 0,
      fmt::format("(0000000000.{:06}) fd0 123##1000102030405060708090A0B\n", first / 1000) +
          fmt::format("(0000000000.{:06}) fd0 456#1122\n", second / 1000));
}

// Faults at run time: loaded from a file or one from the command line, applied from now, listed
// with their hits, cleared; a bad one is refused with its problems and changes nothing.
TEST(Cli, FaultsLoadListInjectAndClear) {
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  EXPECT_EQ(output_of(d, {"fault", "load", CANEMU_SOURCE_DIR "/config/faults/corrupt-id.toml"}),
            "scenario \"three CRC errors on 0x1A0\": 1 fault applied\n");
  EXPECT_NE(output_of(d, {"fault", "inject", "--effect", "bit_error", "--bus", "can0", "--id",
                          "0x123", "--count", "2"})
                .find(": 1 fault applied"),
            std::string::npos);
  Cli bad(d, {"fault", "inject", "--effect", "node_off", "--node", "ixxat0:9"});
  EXPECT_EQ(Cli::read_all(bad.err),
            "node_off: no node named \"ixxat0:9\" (configured nodes are DEVICE:N; simulated "
            "CAN nodes NAME, or BUS/NAME where several buses have that NAME)\ncanemu: scenario "
            "rejected; nothing of it applied\n");  // no line numbers
                                                   // of a text the
                                                   // user never saw
  EXPECT_EQ(bad.wait(), 1);
  // The injected fault hits 0x123 twice: two bit errors, then the frame goes out.
  EXPECT_EQ(output_of(d, {"send", "can0", "123#11", "--step", "5ms"}),
            "(0000000000.000246) can0 123#11\n");
  const std::string listed = output_of(d, {"fault", "list"});
  EXPECT_NE(listed.find("three CRC errors on 0x1A0     6 crc_error       can0              "
                        "12.000000              -        0        0 pending"),
            std::string::npos)
      << listed;
  EXPECT_NE(listed.find("4 bit_error       can0               0.000000              -        3 "
                        "       2 done"),
            std::string::npos)
      << listed;
  EXPECT_EQ(output_of(d, {"fault", "clear", "three CRC errors on 0x1A0"}), "1 scenario cleared\n");
  EXPECT_NE(output_of(d, {"fault", "list"}).find("0        0 cleared"), std::string::npos);
  EXPECT_NE(refusal_of(d, {"fault", "clear", "nope"}).find("no scenario named \"nope\" to clear"),
            std::string::npos);
}

// A scenario file whose path is longer than the request's source field: its errors name the
// whole path, not a cut one.
TEST(Cli, AScenarioWithALongPathIsNamedWhole) {
  Daemon d;
  const std::string dir = d.dir() + "/a-folder-with-a-name-long-enough-to-pass-sixty-four-bytes";
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/bad-scenario.toml";
  std::FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs("[[fault]]\nat = \"0s\"\neffect = \"ack_error\"\nbus = \"nope\"\n", f);
  std::fclose(f);
  ASSERT_GT(file.size(), 64u);
  EXPECT_EQ(refusal_of(d, {"fault", "load", file}),
            file +
                ":1: ack_error: no bus named \"nope\"\ncanemu: scenario "
                "rejected; nothing of it applied\n");
  std::filesystem::remove_all(dir);
}

// A client's name is the peer's choice: canemud keeps printable ASCII only, and the JSON
// escapes quotes, so a name can neither add a field nor break a line or a table row.
TEST(Cli, HostileClientNameCannotForgeStatusFields) {
  Daemon d;
  auto c = connect(d, "x\",\"uid\":0\n\x1b[2J");
  const std::string j = output_of(d, {"status", "--json"});
  EXPECT_EQ(std::count(j.begin(), j.end(), '\n'), 1) << j;
  EXPECT_EQ(j.find('\x1b'), std::string::npos) << j;
  EXPECT_NE(j.find("\"name\" : \"x\\\",\\\"uid\\\":0??[2J\""), std::string::npos) << j;
  const std::string t = output_of(d, {"status"});
  EXPECT_NE(t.find("x\",\"uid\":0??[2J"), std::string::npos) << t;
  EXPECT_EQ(t.find('\x1b'), std::string::npos) << t;
}

// canemu metrics: the Prometheus text format, one family after the other, labels escaped.
TEST(Cli, MetricsSpeakThePrometheusTextFormat) {
  Daemon d;
  Cli step(d, {"time", "step", "10ms"});
  EXPECT_EQ(step.wait(), 0);
  const std::string m = output_of(d, {"metrics"});
  for (const char* line :
       {"# HELP canemu_sim_time_seconds Simulated time.\n"
        "# TYPE canemu_sim_time_seconds gauge\n"
        "canemu_sim_time_seconds 0.010000000\n",
        "# TYPE canemu_bus_frames_total counter\n",
        "canemu_bus_bitrate_bits_per_second{bus=\"can0\",kind=\"can\"} 500000\n",
        "canemu_bus_load_ratio{bus=\"can1\"} 0.000\n",
        "canemu_node_error_state{node=\"ixxat0:0\",bus=\"can0\",state=\"error-active\"} 1\n",
        "canemu_node_error_state{node=\"ixxat0:0\",bus=\"can0\",state=\"bus-off\"} 0\n",
        "canemu_node_tec{node=\"ixxat0:1\",bus=\"can1\"} 0\n",
        "# TYPE canemu_fault_hits_total counter\n"}) {
    EXPECT_NE(m.find(line), std::string::npos) << line << "\nin:\n" << m;
  }
  // Every line is a comment or `name{labels} value`.
  std::size_t start = 0;
  while (start < m.size()) {
    const std::size_t end = m.find('\n', start);
    ASSERT_NE(end, std::string::npos);
    const std::string line = m.substr(start, end - start);
    EXPECT_TRUE(line.rfind("# ", 0) == 0 || line.rfind("canemu_", 0) == 0) << line;
    start = end + 1;
  }
}

// canemud on config/examples/`example`: canemu status shows each of `rows`, and canemu status
// --json each of `json`.
void expect_status_shows(const std::string& example, std::initializer_list<std::string> rows,
                         std::initializer_list<std::string> json) {
  Daemon d("stepped", {"--config", CANEMU_SOURCE_DIR "/config/examples/" + example});
  expect_holds(output_of(d, {"status"}), rows);
  expect_holds(output_of(d, {"status", "--json"}), json);
}

// A SORCUS X-CAN-2i module is a DEVICE row like an IXXAT adapter's (model, buses), and its
// interfaces are nodes NAME:0 and NAME:1 (config/examples/x-can-2i.toml). No program initialized
// the modules: their 82527s are in their init mode.
TEST(Cli, StatusListsAnXcanModuleAndItsInterfacesLikeAnIxxatAdapter) {
  expect_status_shows(
      "x-can-2i.toml",
      {"ixxat0         ixxat-usb-to-can     config   can0 can1\n"
       "xcan0          sorcus-x-can-2i      config   can0 can1\n",
       "xcan0:0        can0         init              0    0",
       "xcan0:1        can1         init              0    0"},
      {"{\"buses\" : [\"can0\",\"can1\"],\"ephemeral\" : false,\"model\" : "
       "\"sorcus-x-can-2i\",\"name\" : \"xcan0\",\"nodes\" : [\"xcan0:0\",\"xcan0:1\"],"
       "\"owner_pid\" : 0}",
       "\"name\" : \"xcan0:1\",\"rec\" : 0,\"state\" : \"init\""});
}

// An SL-CANi is a DEVICE row too (model, its bus), beside its node NAME:0
// (config/examples/sl-cani.toml).
TEST(Cli, StatusListsAnSlCaniAsADeviceRowBesideItsNode) {
  expect_status_shows(
      "sl-cani.toml",
      {"sl0            sorcus-sl-cani       config   can0\n", "sl0:0          can0 "},
      {"{\"buses\" : [\"can0\"],\"ephemeral\" : false,\"model\" : "
       "\"sorcus-sl-cani\",\"name\" : \"sl0\",\"nodes\" : [\"sl0:0\"],"
       "\"owner_pid\" : 0}"});
}

// status (text and JSON), time step and calc, as a user types them.
TEST(Cli, StatusTimeStepAndCalcPrintWhatTheySay) {
  Daemon d;
  auto c = connect(d, "holder");
  client::ChannelOptions o;
  o.bus = "can1";
  o.device = "probe";
  auto ch = client::Channel::open(c, o);
  ASSERT_TRUE(ch) << ch.error().message;

  EXPECT_NE(output_of(d, {"time", "step", "10ms"}).find("simulated time 0.010000000 s"),
            std::string::npos);

  expect_holds(output_of(d, {"status"}), {"time stepped, simulated 0.010000000 s, 2 clients",
                                          "can0         can        500000",
                                          "ixxat0:1       can1         init              0    0",
                                          "probe:0        can1         error-active",
                                          "ixxat0         ixxat-usb-to-can     config   can0 can1",
                                          "probe          ephemeral", "holder"});

  const std::string j = output_of(d, {"status", "--json"});
  ASSERT_FALSE(j.empty());
  EXPECT_EQ(j.front(), '{');
  EXPECT_EQ(j.substr(j.size() - 2), "}\n");
  // toml++ writes it: keys sorted, `"key" : value`.
  expect_holds(j, {"\"time_mode\" : \"stepped\"", "\"sim_time_ns\" : 10000000",
                   "{\"bitrate\" : 500000,\"data_bitrate\" : 0,\"error_frames\" : 0,\"frames\" : "
                   "0,\"kind\" : \"can\",\"load_percent\" : 0.0,\"name\" : \"can1\","
                   "\"transceiver\" : \"high-speed\"}",
                   "\"ephemeral\" : true,\"model\" : \"ephemeral\",\"name\" : \"probe\""});

  expect_holds(output_of(d, {"calc", "frame", "123#1122"}),
               {"DLC      00[1]10\n",
                "bits: 62 (+3 intermission), stuff bits: 2 dynamic, 0 fixed; CRC-15 0x4B7\n"
                "at 500000 bit/s: 124000 ns (62 nominal + 0 data-phase bits), 130000 ns with "
                "intermission\n"});
  EXPECT_EQ(output_of(d, {"calc", "bittiming", "00", "1C"}),
            "SJA1000 at 16 MHz: 500000.000 bit/s, tq 125.000 ns, 16 quanta (1 + 13 + 2), sample "
            "point 87.5 %, SJW 1, 1 sample per bit\n");

  // A LIN frame: its protected identifier, the enhanced checksum, the times at 19200 bit/s.
  EXPECT_EQ(output_of(d, {"calc", "lin", "10#1122"}),
            "break    13 dominant bits, delimiter 1 recessive bit\n"
            "sync     0x55\n"
            "PID      0x50 (ID 0x10, parity P0 1 P1 0)\n"
            "data     11 22\n"
            "checksum 0x7C (enhanced)\n"
            "bits: 64 (header 34, response 30)\n"
            "at 19200 bit/s: 3333333 ns (header 1770833 ns); nominal 3333333 ns, at most "
            "4666666 ns (1.4 x)\n");
  const std::string spaced =
      output_of(d, {"calc", "lin", "3C#00", "--bitrate", "20000", "--break-bits", "20",
                    "--interbyte-bits", "1", "--response-space-bits", "2"});
  // 20 + 1 + 10 + 1 + 10 header bits; 2 + 10 + 1 + 10 response bits: whole 50 us bits.
  EXPECT_NE(spaced.find("checksum 0xFF (classic)\nbits: 65 (header 42, response 23)\n"
                        "at 20000 bit/s: 3250000 ns (header 2100000 ns)"),
            std::string::npos)
      << spaced;
  EXPECT_EQ(refusal_of(d, {"calc", "lin", "40#11"}),
            "canemu: '40#11': the identifier is hex 0..3F (examples: 10#1122, "
            "3C#0000000000000000, 21 for a header alone)\n");

  EXPECT_EQ(refusal_of(d, {"time", "step", "soon"}),
            "canemu: 'soon' is not a duration (examples: 150ns, 20us, 10ms, 2s)\n");
}

TEST(Cli, SendRefusesBadFramesAndUnsteppedStepsWithReasons) {
  Daemon d;
  EXPECT_EQ(refusal_of(d, {"send", "can0", "800#11", "--step", "1ms"}),
            "canemu: '800#11': identifier 0x800 does not fit 11 bits (maximum 0x7FF)\n");
  EXPECT_NE(refusal_of(d, {"send", "can0", "123#"}).find("add --step DURATION"), std::string::npos);
  EXPECT_NE(refusal_of(d, {"send", "can9", "123#", "--step", "1ms"}).find("no bus named \"can9\""),
            std::string::npos);
}

}  // namespace
}  // namespace canemu

namespace canemu {
namespace {

// canemu dump acknowledges by default, as candump on a real interface does: a lone sender's
// frames go out with nobody else on the bus. With --listen-only it only watches, and the
// sender gets no acknowledgement.
TEST(CliDump, AcknowledgesByDefaultAndListenOnlyDoesNot) {
  Daemon d;
  auto watcher = connect(d, "watcher");
  ASSERT_TRUE(watcher.subscribe(ipc::kEventDevices));
  Cli dump(d, {"dump", "can0", "-n", "1"});
  ASSERT_TRUE(watcher.next_notification(10'000));
  EXPECT_EQ(output_of(d, {"send", "can0", "123#1122", "--step", "1ms"}),
            "(0000000000.000124) can0 123#1122\n");
  EXPECT_EQ(Cli::read_all(dump.out), "(0000000000.000124) can0 123#1122\n");
  EXPECT_EQ(Cli::read_all(dump.err),
            "canemu: listening on can0 as eph1 (acknowledging, 500000 bit/s, time stamps in "
            "simulated seconds)\n");
  EXPECT_EQ(dump.wait(), 0);

  Cli quiet(d, {"dump", "can0", "--listen-only", "--no-errors", "-n", "1"});
  ASSERT_TRUE(watcher.next_notification(10'000));  // eph1 gone
  ASSERT_TRUE(watcher.next_notification(10'000));  // the listener's device
  EXPECT_NE(refusal_of(d, {"send", "can0", "123#1122", "--step", "1ms"})
                .find("is a node on can0 acknowledging"),
            std::string::npos);
}

// The lines of `text` that hold one of `wanted` (frame texts), in order.
std::string lines_with(const std::string& text, const std::vector<std::string>& wanted) {
  std::string out;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = text.find('\n', at);
    const std::string line = text.substr(at, end - at);
    for (const std::string& w : wanted) {
      if (line.ends_with(" " + w)) {
        out += line + "\n";
      }
    }
    at = end == std::string::npos ? text.size() : end + 1;
  }
  return out;
}

// candump's bus arguments: several buses in one dump, each with its filters
// (<id>:<mask>, <id>~<mask>; an 8-digit identifier is a 29-bit one), and no error frames once a
// filter list is given without #<mask>, as candump's socket gets none. The first lines say what
// each bus lets through.
TEST(CliDump, TakesCandumpsFiltersOnSeveralBuses) {
  Daemon d;
  Cli dump(d, {"dump", "can0,123:7FF,00000456:9FFFFFFF", "can1,400~7F0", "-n", "4"});
  std::string err = Cli::read_until(dump.err, "listening on can1");
  ASSERT_NE(err.find("listening on can1"), std::string::npos) << err;
  const std::string sent0 = output_of(d, {"send", "can0", "124#01", "123#11", "00000123#R",
                                          "456#22", "00000456#33", "--step", "1ms"});
  const std::string sent1 = output_of(d, {"send", "can1", "405#01", "7FF#02", "--step", "1ms"});
  // 123:7FF takes 123 in both formats and remote frames; 00000456:9FFFFFFF only the 29-bit 456.
  const std::string expected =
      lines_with(sent0, {"123#11", "00000123#R", "00000456#33"}) + lines_with(sent1, {"7FF#02"});
  EXPECT_EQ(std::count(expected.begin(), expected.end(), '\n'), 4) << sent0 << sent1;
  EXPECT_EQ(Cli::read_all(dump.out), expected);
  EXPECT_EQ(dump.wait(), 0);
  err += Cli::read_all(dump.err);
  EXPECT_EQ(err,
            "canemu: listening on can0 as eph1 (acknowledging, 500000 bit/s, time stamps in "
            "simulated seconds)\n"
            "canemu: on can0: frames that match 123:7FF or 00000456:9FFFFFFF; no error frames "
            "(#<mask> selects them)\n"
            "canemu: listening on can1 as eph2 (acknowledging, 500000 bit/s, time stamps in "
            "simulated seconds)\n"
            "canemu: on can1: frames that match 400~7F0; no error frames (#<mask> selects "
            "them)\n");
}

// `any` dumps every CAN bus (not the LIN bus), each line naming its bus.
TEST(CliDump, AnyDumpsEveryCanBus) {
  Daemon d;
  Cli dump(d, {"dump", "any", "--no-errors", "-n", "2"});
  const std::string err = Cli::read_until(dump.err, "listening on can1");
  ASSERT_NE(err.find("listening on can1"), std::string::npos) << err;
  EXPECT_EQ(err.find("lin0"), std::string::npos) << err;
  const std::string sent0 = output_of(d, {"send", "can0", "123#11", "--step", "1ms"});
  const std::string sent1 = output_of(d, {"send", "can1", "321#22", "--step", "1ms"});
  EXPECT_EQ(Cli::read_all(dump.out), sent0 + sent1);
  EXPECT_EQ(dump.wait(), 0);
}

// -l is candump's: the log goes into candump-YYYY-MM-DD_HHMMSS.log in the current directory,
// nothing on standard output, and the node still acknowledges (a lone sender gets its frame
// out). Listen-only is --listen-only.
TEST(CliDump, LogsIntoACandumpNamedFileWithL) {
  Daemon d;
  const std::string dir = d.dir() + "/logs";
  ASSERT_EQ(::mkdir(dir.c_str(), 0700), 0);
  Cli dump(d, {"dump", "can0", "-l", "-n", "1"}, nullptr, dir);
  std::string err = Cli::read_until(dump.err, "listening on");
  ASSERT_NE(err.find("listening on can0 as eph1 (acknowledging"), std::string::npos) << err;
  const std::string sent = output_of(d, {"send", "can0", "123#1122", "--step", "1ms"});
  EXPECT_EQ(Cli::read_all(dump.out), "");
  EXPECT_EQ(dump.wait(), 0);
  err += Cli::read_all(dump.err);
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    files.push_back(e.path().filename().string());
  }
  ASSERT_EQ(files.size(), 1u);
  const std::string& name = files[0];
  EXPECT_TRUE(name.size() == 29 && name.starts_with("candump-") && name.ends_with(".log") &&
              name[12] == '-' && name[15] == '-' && name[18] == '_')
      << name;
  EXPECT_NE(err.find("canemu: logging into " + name), std::string::npos) << err;
  FILE* f = std::fopen((dir + "/" + name).c_str(), "r");
  ASSERT_NE(f, nullptr);
  char text[256] = {};
  const std::size_t n = std::fread(text, 1, sizeof text - 1, f);
  std::fclose(f);
  EXPECT_EQ(std::string(text, n), sent);
}

// The time stamp in ns of the line of `log` (a candump -L log) that ends with `frame`, or -1.
int64_t stamp_of(const std::string& log, const std::string& frame) {
  const std::size_t end = log.find(" " + frame + "\n");
  if (end == std::string::npos) {
    return -1;
  }
  const std::size_t open = log.rfind('(', end);
  const std::size_t dot = log.find('.', open);
  return std::stoll(log.substr(open + 1, dot - open - 1)) * 1'000'000'000 +
         std::stoll(log.substr(dot + 1, 6)) * 1000;
}

// --summary: a JSON line per bus and identifier for an interval (here a minute, so that the one
// written as -n ends the dump holds everything), with the frames' exact time stamps; error
// frames counted per bus.
TEST(CliDump, SummaryGivesALinePerBusAndIdentifier) {
  Daemon d;
  Cli dump(d, {"dump", "can0", "can1", "--summary", "60000", "-n", "5"});
  std::string err = Cli::read_until(dump.err, "listening on can1");
  ASSERT_NE(err.find("listening on can1"), std::string::npos) << err;
  const std::string sent0 =
      output_of(d, {"send", "can0", "123#1122", "7FF#R2", "123#1133", "--step", "1ms"});
  const std::string sent1 = output_of(d, {"send", "can1", "00000456#01", "--step", "1ms"});
  // At a bit rate nobody else has: the dump's node detects errors, and its first error frame is
  // the dump's fifth line (-n 5), the last it counts.
  refusal_of(d, {"send", "can1", "456#01", "--bitrate", "250000", "--step", "2ms"});
  const std::string out = Cli::read_all(dump.out);
  EXPECT_EQ(dump.wait(), 0);
  const std::string expected = fmt::format(
      "{{\"bus\":\"can0\",\"id\":\"123\",\"count\":2,\"first_ns\":{},\"last_ns\":{},"
      "\"data\":\"1133\",\"changed\":2}}\n"
      "{{\"bus\":\"can0\",\"id\":\"7FF\",\"count\":1,\"first_ns\":{},\"last_ns\":{},"
      "\"data\":\"R\",\"changed\":0}}\n"
      "{{\"bus\":\"can1\",\"id\":\"00000456\",\"count\":1,\"first_ns\":{},\"last_ns\":{},"
      "\"data\":\"01\",\"changed\":0}}\n",
      stamp_of(sent0, "123#1122"), stamp_of(sent0, "123#1133"), stamp_of(sent0, "7FF#R2"),
      stamp_of(sent0, "7FF#R2"), stamp_of(sent1, "00000456#01"), stamp_of(sent1, "00000456#01"));
  EXPECT_EQ(out, expected + "{\"bus\":\"can1\",\"error_frames\":1}\n");
}

// What a dump cannot do is refused before it listens, saying why.
TEST(CliDump, RefusesWhatItCannotDoSayingWhy) {
  Daemon d;
  for (const auto& [args, says] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"dump", "can0,123"}, "'123' is not <id>:<mask>, <id>~<mask>, #<error mask> or j"},
           {{"dump", "can9,123:7FF"}, "no bus named \"can9\" (buses: can0, can1, lin0)"},
           {{"dump", "can0", "can1", "--format", "pcap"}, "one bus per pcap capture"},
           {{"dump", "lin0,123:7FF"}, "lin0 is a LIN bus"},
           {{"dump", "can0", "lin0"}, "lin0 is a LIN bus"},
           {{"dump", "can0", "-l", "-o", "x.log"}, "-l"},
           {{"dump", "can0", "--summary", "100", "-l"},
            "--summary writes JSON lines, not a pcap capture or a candump log"},
           {{"dump", "can0", "--summary", "0"}, "--summary"}}) {
    Cli dump(d, args);
    const std::string err = Cli::read_all(dump.err);
    EXPECT_NE(err.find(says), std::string::npos) << says << ": " << err;
    EXPECT_EQ(dump.wait(), 1) << says;
  }
}

// canemu dump (also --summary) and record (on a CAN and a LIN bus) end when canemud goes away,
// here stopped by SIGTERM: exit code 1 and the reason, naming the socket, instead of listening
// on forever.
TEST(CliDump, DumpAndRecordEndWithTheReasonWhenCanemudStops) {
  Daemon d;
  const std::string file = d.dir() + "/recorded.log";
  Cli dump(d, {"dump", "can0"});
  Cli record(d, {"record", "can0", "-o", file});
  Cli lin(d, {"dump", "lin0"});
  Cli summary(d, {"dump", "can1", "--summary", "50"});  // reads its rings without waiting on them
  for (Cli* c : {&dump, &record, &lin, &summary}) {
    ASSERT_NE(Cli::read_until(c->err, "listening on").find("listening on"), std::string::npos);
  }
  EXPECT_EQ(d.terminate(10'000), 0);
  for (Cli* c : {&dump, &record, &lin, &summary}) {
    EXPECT_EQ(c->wait_for(10'000), 1);
    const std::string err = Cli::read_all(c->err, 1000);
    EXPECT_NE(err.find("canemu: canemud went away: the connection to " + d.socket() + " closed"),
              std::string::npos)
        << err;
    if (c == &record) {  // what it wrote is said too
      EXPECT_NE(err.find("0 frame(s) recorded in " + file), std::string::npos) << err;
    }
  }
  ::unlink(file.c_str());
}

// canemu dump and record run by a user whom a reload no longer allows end with canemud's
// reason (its answer queued before it closed the connection) and exit code 1.
TEST(CliDump, DumpAndRecordEndWithTheReasonWhenAReloadRevokesTheirUser) {
  if (::geteuid() != 0) {
    GTEST_SKIP() << "needs root to run canemu as another user";
  }
  const group* users = ::getgrnam("users");
  ASSERT_NE(users, nullptr) << "the machine has no group \"users\"";
  TempDir dir;
  const std::string file = (dir.path / "canemud.toml").string();
  const auto configure = [&](const std::string& groups) {
    FILE* f = std::fopen(file.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs(("[[bus]]\nname = \"can0\"\n\n[security]\nallowed_groups = " + groups +
                "\nsocket_mode = 0o666\nsocket_group = \"\"\n")
                   .c_str(),
               f);
    std::fclose(f);
  };
  configure("[\"users\"]");
  Daemon d("stepped", {"--config=" + file});
  ::chmod(d.dir().c_str(), 0755);  // the socket's folder: reachable by the other user
  const Credentials member{65534, 65534, {users->gr_gid}};
  Cli dump(d, {"dump", "can0"}, &member);
  Cli record(d, {"record", "can0", "-o", "-"}, &member);
  for (Cli* c : {&dump, &record}) {
    ASSERT_NE(Cli::read_until(c->err, "listening on").find("listening on"), std::string::npos);
  }
  configure("[]");
  d.signal(SIGHUP);
  for (Cli* c : {&dump, &record}) {
    EXPECT_EQ(c->wait_for(10'000), 1);
    const std::string err = Cli::read_all(c->err, 1000);
    EXPECT_NE(err.find("canemu: canemud closed the connection: permission_denied: uid 65534 is "
                       "no longer allowed by the [security] configuration"),
              std::string::npos)
        << err;
  }
}

// canemu gen in stepped time moves time itself: -n frames, one per gap, each at the end of its
// EOF; identifiers and data incrementing, lengths fixed, the summary on stderr.
TEST(CliGen, SendsCountFramesAtExactInstantsInSteppedTime) {
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  Cli gen(d, {"gen", "can0", "-n", "3", "-g", "1ms", "-I", "i", "-L", "2", "-D", "i", "-v"});
  // Frame k is queued at k ms (after k steps of 1 ms) and ends its EOF one frame later at 2 us a
  // bit: 000#0001 and 001#0102 are 67 bits with their stuff bits (134 us), 002#0203 is 66
  // (132 us); `canemu calc frame` gives the same counts.
  const std::string out = Cli::read_all(gen.out);
  EXPECT_EQ(out,
            "(0000000000.000134) can0 000#0001\n"
            "(0000000000.001134) can0 001#0102\n"
            "(0000000000.002132) can0 002#0203\n")
      << out;
  EXPECT_EQ(Cli::read_all(gen.err),
            "canemu: generating on can0 as eph2 (500000 bit/s, a frame every 1ms)\n"
            "canemu: 3 frame(s) sent on can0\n");
  EXPECT_EQ(gen.wait(), 0);
}

// In real and scaled time gen's waits are simulated time: a simulation far behind the wall clock
// (scaled:0.001, a frame of 8 bytes takes about 0.23 s of wall time) makes the confirmations
// late, and gen waits for them instead of counting its frames as not sent after --timeout ms of
// wall time.
TEST(CliGen, ASimulationBehindTheWallClockCountsNoFrameAsNotSent) {
  Daemon d("scaled:0.001");
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  Cli gen(d, {"gen", "can0", "-n", "3", "-g", "0", "-L", "8", "--timeout", "100"});
  EXPECT_EQ(Cli::read_all(gen.err, 30'000),
            "canemu: generating on can0 as eph2 (500000 bit/s, a frame every 0)\n"
            "canemu: 3 frame(s) sent on can0\n");
  EXPECT_EQ(gen.wait(), 0);
}

// A frame nobody acknowledges is still counted as not sent, after --timeout ms of simulated time.
TEST(CliGen, AFrameNobodyAcknowledgesIsNotSentAfterTheTimeout) {
  Daemon d("realtime");
  EXPECT_EQ(refusal_of(d, {"gen", "can0", "-n", "1", "-g", "0", "--timeout", "50"}),
            "canemu: generating on can0 as eph1 (500000 bit/s, a frame every 0)\n"
            "canemu: 0 frame(s) sent on can0, 1 not sent: is a node on can0 acknowledging at "
            "500000 bit/s?\n");
}

// A line of a candump log with a classic DLC above 8 (`_X`, as candump and canemu write it) is
// sent again as it was: 8 bytes, the DLC 14 on the wire.
TEST(CliSend, ALoggedFrameWithADlcAboveEightIsSentAgainAsItWas) {
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  const std::string out =
      output_of(d, {"send", "can0", "123#1122334455667788_E", "123#R8_9", "--step", "1ms"});
  model::FrameSpec data;
  data.id = 0x123;
  data.dlc = 14;
  const std::vector<uint8_t> bytes{0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
  data.data = bytes;
  model::FrameSpec remote;
  remote.id = 0x123;
  remote.remote = true;
  remote.dlc = 9;
  const model::BitTiming nominal{5'000'000, 1, 7, 2, 1, 1};
  const int64_t first =
      model::frame_duration(model::encode(*model::Frame::create(data)), nominal).ns();
  const int64_t second =
      first + 3 * 2000 +
      model::frame_duration(model::encode(*model::Frame::create(remote)), nominal).ns();
  EXPECT_EQ(out, fmt::format("(0000000000.{:06}) can0 123#1122334455667788_E\n"
                             "(0000000000.{:06}) can0 123#R8_9\n",
                             first / 1000, second / 1000));
  for (const auto& [text, says] : std::vector<std::pair<std::string, std::string>>{
           {"123#112233_E", "'123#112233_E': '_E' follows 8 data bytes only, not 3"},
           {"123#1122334455667788_7", "'123#1122334455667788_7': '_7': a classic DLC above 8"}}) {
    Cli bad(d, {"send", "can0", text, "--step", "1ms"});
    EXPECT_NE(Cli::read_all(bad.err).find(says), std::string::npos) << says;
    EXPECT_EQ(bad.wait(), 1) << says;
  }
}

TEST(CliGen, RefusesOptionsThatMakeNoFrame) {
  Daemon d;
  for (const auto& [args, says] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"gen", "can0", "-I", "800"}, "-I '800': r, i or a hex identifier up to 7FF"},
           {{"gen", "can0", "-L", "9"}, "-L '9': r, i or a classic CAN length in bytes"},
           {{"gen", "can0", "-D", "123"}, "-D '123': r, i or the payload in hex pairs"},
           {{"gen", "can0", "-g", "soon"}, "-g 'soon' is not a duration"},
           {{"gen", "can0", "-b"}, "-b (bit-rate switch) needs -f"}}) {
    Cli gen(d, args);
    EXPECT_NE(Cli::read_all(gen.err).find(says), std::string::npos) << says;
    EXPECT_EQ(gen.wait(), 1) << says;
  }
}

// Every argument error is exit 1 with the user's own words, never a parser's internals or
// CLI11's exit codes.
TEST(CliErrors, BadArgumentsExitOneAndSayWhatIsWrong) {
  Daemon d;
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  for (const Case& c : std::vector<Case>{
           {{"calc", "bittiming", "ZZ", "1C"}, "'ZZ' is not a register value"},
           {{"calc", "frame", "123#11", "--bitrate", "7"}, "--bitrate: Value 7 not in range"},
           {{"send", "can0"}, "FRAME is required"},
           {{"dump"}, "BUS is required"},
           {{"status", "--frobnicate"}, "--frobnicate"},
           {{"fault", "load", "/nonexistent.toml"},
            "/nonexistent.toml: cannot be read (No such file or directory)"}}) {
    Cli cli(d, c.args);
    const std::string err = Cli::read_all(cli.err);
    EXPECT_NE(err.find(c.says), std::string::npos) << err;
    EXPECT_EQ(err.find("stoul"), std::string::npos) << err;
    EXPECT_EQ(cli.wait(), 1) << c.says;
  }
}

// `canemu --socket DIR`: the path is a directory, not a canemud that is not running.
TEST(CliErrors, ASocketPathThatIsADirectoryIsNamedSo) {
  Daemon d;
  EXPECT_EQ(refusal_of(d, {"--socket", d.dir(), "status"}),
            "canemu: " + d.dir() + " is a directory, not canemud's socket: did you mean " +
                d.socket() + "?\n");
}

}  // namespace
}  // namespace canemu

namespace canemu {
namespace {

// The habits a user of can-utils brings: cangen's -g is milliseconds, so a bare number is a gap
// in ms (units still work: CliGen.SendsCountFramesAtExactInstantsInSteppedTime).
TEST(CliHabits, AGenGapWithoutAUnitIsMilliseconds) {
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  Cli gen(d, {"gen", "can0", "-n", "2", "-g", "1", "-I", "i", "-L", "2", "-D", "i", "-v"});
  EXPECT_EQ(Cli::read_all(gen.out),
            "(0000000000.000134) can0 000#0001\n"
            "(0000000000.001134) can0 001#0102\n");
  EXPECT_EQ(Cli::read_all(gen.err),
            "canemu: generating on can0 as eph2 (500000 bit/s, a frame every 1ms)\n"
            "canemu: 2 frame(s) sent on can0\n");
  EXPECT_EQ(gen.wait(), 0);
  Cli half(d, {"gen", "can0", "-n", "1", "-g", "0.5"});
  EXPECT_NE(Cli::read_all(half.err).find("a frame every 0.5ms"), std::string::npos);
  EXPECT_EQ(half.wait(), 0);
}

// Identifiers on the command line are hex, as candump writes them and as send and gen -I read
// them: fault inject's --id and --mask too, with or without 0x.
TEST(CliHabits, FaultIdentifiersAndMasksAreHex) {
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  // --mask 700 is 0x700: 0x123 matches 0x100 in the top three bits (decimal 700, 0x2BC, would
  // not let it match).
  // The faults hit once each, one after the other.
  const auto hit_once = [&d] {
    const std::string j = output_of(d, {"status", "--json"});
    std::size_t n = 0;
    for (std::size_t at = j.find("\"hits\" : 1,"); at != std::string::npos;
         at = j.find("\"hits\" : 1,", at + 1)) {
      ++n;
    }
    return n;
  };
  for (const std::vector<std::string>& match : std::vector<std::vector<std::string>>{
           {"--id", "100", "--mask", "700"}, {"--id", "0x123", "--mask", "0x7FF"}}) {
    std::vector<std::string> args{"fault", "inject", "--effect", "bit_error",
                                  "--bus", "can0",   "--count",  "1"};
    args.insert(args.end(), match.begin(), match.end());
    Cli inject(d, args);
    EXPECT_EQ(inject.wait(), 0) << Cli::read_all(inject.err);
    Cli send(d, {"send", "can0", "123#11", "--step", "5ms"});
    EXPECT_EQ(send.wait(), 0) << Cli::read_all(send.err);
  }
  EXPECT_EQ(hit_once(), 2u);
  EXPECT_EQ(
      refusal_of(d, {"fault", "inject", "--effect", "bit_error", "--bus", "can0", "--id", "12G"}),
      "canemu: --id '12G': not a hex identifier (123 or 0x123, as candump writes it)\n");
  EXPECT_NE(
      output_of(d, {"gen", "can0", "-n", "1", "-I", "0x123", "-L", "0", "-v"}).find(" can0 123#\n"),
      std::string::npos);
}

// fault list shows what each fault matches, so that a rule that never hits says why.
TEST(CliHabits, FaultListShowsEachFaultsMatch) {
  Daemon d;
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"--effect", "bit_error", "--bus", "can0", "--id", "7B"},
           {"--effect", "crc_error", "--bus", "can0", "--id", "100", "--mask", "7F0", "--ext",
            "--from", "ixxat0:0"},
           {"--effect", "ack_error", "--bus", "can1", "--rtr"},
           {"--effect", "lin_checksum_error", "--bus", "lin0", "--id", "20"},
           {"--effect", "node_off", "--node", "ixxat0:1"},
           {"--effect", "babble", "--node", "ixxat0:0", "--id", "1AB", "--duration", "1ms"}}) {
    std::vector<std::string> all{"fault", "inject"};
    all.insert(all.end(), args.begin(), args.end());
    Cli inject(d, all);
    EXPECT_EQ(inject.wait(), 0) << Cli::read_all(inject.err);
  }
  const std::string listed = output_of(d, {"fault", "list"});
  std::vector<std::string> lines;
  for (std::size_t at = 0; at < listed.size();) {
    const std::size_t end = listed.find('\n', at);
    lines.push_back(listed.substr(at, end - at));
    at = end == std::string::npos ? listed.size() : end + 1;
  }
  ASSERT_EQ(lines.size(), 7u) << listed;
  // The last column, after the state.
  EXPECT_TRUE(lines[0].ends_with(" STATE   MATCH")) << listed;
  const std::vector<std::string> matches{
      "id 0x7B", "id 0x100 mask 0x7F0 ext from ixxat0:0", "rtr", "id 0x20", "-", "sends 0x1AB"};
  for (std::size_t k = 0; k < matches.size(); ++k) {
    EXPECT_TRUE(lines[k + 1].ends_with("  " + matches[k])) << matches[k] << "\n" << listed;
  }
  const std::string j = output_of(d, {"status", "--json"});
  EXPECT_NE(j.find("\"match\" : {\"ext\" : true,\"from\" : \"ixxat0:0\",\"id\" : 256,"
                   "\"mask\" : 2032}"),
            std::string::npos)
      << j;
}

TEST(CliHabits, CanemuAndCanemudSayTheirVersionAndBadArgumentsExitOne) {
  Cli canemu(CANEMU_PATH, {"--version"});
  EXPECT_EQ(Cli::read_all(canemu.out), "canemu " CANEMU_PROJECT_VERSION "\n");
  EXPECT_EQ(canemu.wait(), 0);
  Cli canemud(CANEMUD_PATH, {"--version"});
  EXPECT_EQ(Cli::read_all(canemud.out), "canemud " CANEMU_PROJECT_VERSION "\n");
  EXPECT_EQ(canemud.wait(), 0);
  Cli bogus(CANEMUD_PATH, {"--bogus"});
  EXPECT_NE(Cli::read_all(bogus.err).find("--bogus"), std::string::npos);
  EXPECT_EQ(bogus.wait(), 1);
  Cli help(CANEMUD_PATH, {"--help"});
  EXPECT_NE(Cli::read_all(help.out).find("--version"), std::string::npos);
  EXPECT_EQ(help.wait(), 0);
}

// canemud's hint names the canemu beside it when it runs from a build tree, else `canemu` as
// installed.
TEST(CliHabits, CanemudSuggestsTheCanemuOfItsOwnTree) {
  {
    Daemon d;
    // This build's canemu, written as canemud was started (here by its full path).
    const std::string hint = fmt::format("try: CANEMU_SOCKET={} ", d.socket());
    ASSERT_TRUE(d.read_log_until(" status\n", 10'000)) << d.log();
    const std::size_t at = d.log().find(hint);
    ASSERT_NE(at, std::string::npos) << d.log();
    const std::size_t end = d.log().find(" status\n", at);
    const std::string named = d.log().substr(at + hint.size(), end - at - hint.size());
    EXPECT_EQ(std::filesystem::canonical(named), std::filesystem::canonical(CANEMU_PATH));
  }
  TempDir dir;
  const std::string bin = (dir.path / "canemud").string();
  std::filesystem::copy_file(CANEMUD_PATH, bin);
  {
    testing::CanemudProcess installed(bin, {"--time=stepped"});
    ASSERT_TRUE(installed.ready()) << installed.log();
    const std::string line =
        fmt::format("try: CANEMU_SOCKET={} canemu status\n", installed.socket());
    EXPECT_TRUE(installed.read_log_until(line, 10'000)) << installed.log();
  }
}

// CAN FD frames on a classic bus: the cause said as it is, before anything is sent.
TEST(CliHabits, CanFdOnAClassicBusIsRefusedForThatReason) {
  Daemon d;
  EXPECT_EQ(refusal_of(d, {"send", "can0", "123##1AA", "--step", "1ms"}),
            "canemu: '123##1AA': a CAN FD frame, and can0 is a classic CAN bus (CAN FD needs a "
            "bus of kind can-fd)\n");
  EXPECT_EQ(refusal_of(d, {"gen", "can0", "-f", "-n", "1"}),
            "canemu: -f: can0 is a classic CAN bus (CAN FD needs a bus of kind can-fd)\n");
}

// Column widths follow their content: a long scenario name and effect, and the long state
// names of a timeline, keep every column in its place.
TEST(CliHabits, FaultListAndTimelineColumnsFitTheirContent) {
  Daemon d;
  const std::string name(63, 'n');
  TempDir dir;
  const std::string file = (dir.path / "long.toml").string();
  FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fprintf(f,
               "[scenario]\nname = \"%s\"\n[[fault]]\neffect = \"error_counters\"\nat = \"0s\"\n"
               "node = \"ixxat0:0\"\ntec = 130\nrec = 0\n[[fault]]\n"
               "effect = \"lin_checksum_error\"\nat = \"0s\"\nbus = \"lin0\"\n",
               name.c_str());
  std::fclose(f);
  Cli load(d, {"fault", "load", file});
  EXPECT_EQ(load.wait(), 0) << Cli::read_all(load.err);
  Cli step(d, {"time", "step", "1ms"});
  EXPECT_EQ(step.wait(), 0);
  // Each header's column starts where its values start (names left, numbers right-aligned).
  const auto lines_of = [](const std::string& text) {
    std::vector<std::string> lines;
    for (std::size_t at = 0; at < text.size();) {
      const std::size_t end = text.find('\n', at);
      lines.push_back(text.substr(at, end - at));
      at = end == std::string::npos ? text.size() : end + 1;
    }
    return lines;
  };
  const auto rows = lines_of(output_of(d, {"fault", "list"}));
  ASSERT_EQ(rows.size(), 3u);
  const std::string& header = rows[0];
  const std::string& row = rows[2];
  EXPECT_EQ(row.find("lin_checksum_error"), header.find("EFFECT")) << header << "\n" << row;
  EXPECT_EQ(row.find(" lin0 ") + 1, header.find("TARGET")) << header << "\n" << row;
  EXPECT_EQ(row.find(" 9 ") + 1, header.find("LINE") + 3) << header << "\n" << row;
  EXPECT_EQ(row.find("pending"), std::string::npos);
  EXPECT_EQ(row.find("active"), header.find("STATE")) << header << "\n" << row;

  const auto t = lines_of(output_of(d, {"timeline", "can0", "ixxat0:0"}));
  ASSERT_GE(t.size(), 4u);
  const std::string& th = t[t.size() - 2];
  const std::string& tr = t[t.size() - 1];
  EXPECT_NE(tr.find("error-passive"), std::string::npos) << th << "\n" << tr;
  EXPECT_EQ(tr.find("error-passive"), th.find("state")) << th << "\n" << tr;
  EXPECT_EQ(tr.find("counters written"), th.find("cause")) << th << "\n" << tr;
}

// A configured adapter's controller that no program started is in its init mode: status says
// init, not error-active; a started one (an ephemeral node) is error-active.
TEST(CliHabits, StatusShowsControllersNotStartedAsInit) {
  Daemon d;
  auto holder = connect(d, "holder");
  auto partner = partner_on(holder, "can0");
  const std::string t = output_of(d, {"status"});
  EXPECT_NE(t.find("ixxat0:0       can0         init              0    0"), std::string::npos) << t;
  EXPECT_NE(t.find("eph1:0         can0         error-active      0    0"), std::string::npos) << t;
  const std::string j = output_of(d, {"status", "--json"});
  EXPECT_NE(j.find("\"name\" : \"ixxat0:1\",\"rec\" : 0,\"state\" : \"init\""), std::string::npos)
      << j;
}

}  // namespace
}  // namespace canemu
