// [[recorder]]: canemud's recorders write what their bus carries, with error frames, at the
// simulated instants, and never lose frames silently.
#include "canemu/daemon/bridges/recorder.hpp"

#include <cstdio>
#include <deque>
#include <filesystem>
#include <map>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "../support/lin_reference.hpp"
#include "../support/many_buses.hpp"
#include "../support/temp_dir.hpp"
#include "daemon_test_support.hpp"

#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::daemon {
namespace {

namespace fs = std::filesystem;

using testing::read_file;
using testing::TempDir;

std::unique_ptr<Simulation> world(const std::string& recorders) {
  const std::string text = std::string(embedded_default_config()) + recorders;
  auto cfg = parse_config(text, "/etc/canemu/test.toml");
  EXPECT_TRUE(cfg) << (cfg ? "" : cfg.error().front());
  auto sim = Simulation::build(*cfg);
  EXPECT_TRUE(sim) << (sim ? "" : sim.error().front());
  return std::move(*sim);
}

model::Frame frame(uint32_t id, std::vector<uint8_t> data, bool extended = false) {
  model::FrameSpec spec;
  spec.id = id;
  spec.extended = extended;
  spec.data = data;
  return *model::Frame::create(spec);
}

// Where each frame ended, as an acknowledging receiver saw it.
struct Receiver : model::ControllerEvents {
  std::vector<int64_t> at_ns;
  void frame_received(model::SimTime at, const model::Frame&, bool) override {
    at_ns.push_back(at.ns());
  }
};

// Two nodes of can0 (500 kbit/s): one sends `frames`, the other acknowledges.
struct Traffic {
  std::deque<model::Frame> queue;
  Receiver receiver;
  model::HostedNode* tx = nullptr;
  Traffic(Simulation& sim, std::vector<model::Frame> frames) : queue(frames.begin(), frames.end()) {
    const auto timing = node_timing(false, {500'000, 0, 875});
    sim.spare_node(0).start(*timing, &receiver, [] { return std::optional<model::TxFrame>(); });
    tx = &sim.spare_node(0);
    tx->start(*timing, nullptr, [this]() -> std::optional<model::TxFrame> {
      if (queue.empty()) {
        return std::nullopt;
      }
      model::TxFrame f{queue.front()};
      queue.pop_front();
      return f;
    });
    tx->kick();
  }
};

std::string stamp(int64_t ns) {
  return ipc::socketcan::candump_line(ns, "", ipc::socketcan::Frame{}).substr(0, 19);
}

TEST(Recorder, WritesEveryFrameOfItsBusAtItsSimulatedInstant) {
  TempDir dir;
  auto sim =
      world("[[recorder]]\nbus = \"can0\"\npath = \"" + (dir.path / "can0.log").string() + "\"\n");
  Traffic t(*sim, {frame(0x123, {0x11, 0x22}), frame(0x1ABCDEF0, {}, true), frame(0x7FF, {1})});
  sim->scheduler().run_until(model::SimTime::from_ns(10'000'000));
  EXPECT_TRUE(sim->flush_recorders().empty());
  ASSERT_EQ(t.receiver.at_ns.size(), 3u);
  EXPECT_EQ(read_file(dir.path / "can0.log"), stamp(t.receiver.at_ns[0]) + " can0 123#1122\n" +
                                                  stamp(t.receiver.at_ns[1]) + " can0 1ABCDEF0#\n" +
                                                  stamp(t.receiver.at_ns[2]) + " can0 7FF#01\n");
  ipc::RecorderListReply list{};
  fill_recorder_list(*sim, list);
  ASSERT_EQ(list.count, 1);
  EXPECT_EQ(ipc::name_of(list.recorders[0].bus), "can0");
  EXPECT_EQ(list.recorders[0].frames, 3u);
  EXPECT_EQ(list.recorders[0].lost, 0u);
}

TEST(Recorder, RecordsErrorFramesAsCandumpEShowsThem) {
  TempDir dir;
  auto sim =
      world("[[recorder]]\nbus = \"can0\"\npath = \"" + (dir.path / "can0.log").string() + "\"\n");
  // Nobody acknowledges: the sender's ACK errors, which the listen-only recorder sees as form
  // errors... or not at all; what it records must be error frames of CAN_ERR_FLAG.
  const auto timing = node_timing(false, {500'000, 0, 875});
  model::HostedNode& tx = sim->spare_node(0);
  bool sent = false;
  tx.start(*timing, nullptr, [&]() -> std::optional<model::TxFrame> {
    if (sent) {
      return std::nullopt;
    }
    sent = true;
    return model::TxFrame{frame(0x100, {0xAA}), true};  // single shot
  });
  tx.kick();
  sim->scheduler().run_until(model::SimTime::from_ns(1'000'000));
  sim->flush_recorders();
  const std::string log = read_file(dir.path / "can0.log");
  ASSERT_FALSE(log.empty());
  EXPECT_EQ(log.find("100#AA"), std::string::npos) << log;
  for (std::size_t at = 0; at < log.size(); at = log.find('\n', at) + 1) {
    EXPECT_EQ(log.substr(at + 25, 3), "200") << log;  // every line an error frame
  }
}

TEST(Recorder, WritesPcapWhenThePathSaysSo) {
  TempDir dir;
  auto sim = world("[[recorder]]\nbus = \"can0\"\npath = \"" + (dir.path / "can0.pcap").string() +
                   "\"\nerrors = false\n");
  Traffic t(*sim, {frame(0x123, {0x11, 0x22})});
  sim->scheduler().run_until(model::SimTime::from_ns(1'000'000));
  sim->flush_recorders();
  const std::string bytes = read_file(dir.path / "can0.pcap");
  ASSERT_EQ(bytes.size(), 24u + 16 + 16);
  EXPECT_EQ(static_cast<uint8_t>(bytes[20]), 227);
  EXPECT_EQ(static_cast<uint32_t>(static_cast<uint8_t>(bytes[28])) |
                static_cast<uint32_t>(static_cast<uint8_t>(bytes[29])) << 8 |
                static_cast<uint32_t>(static_cast<uint8_t>(bytes[30])) << 16,
            static_cast<uint32_t>(t.receiver.at_ns[0]));
  EXPECT_EQ(bytes.substr(40, 6), std::string("\x00\x00\x01\x23\x02\x00", 6));
}

TEST(Recorder, AFullDiskIsReportedOnceWithWhatWasLost) {
  auto sim = world("[[recorder]]\nbus = \"can0\"\npath = \"/dev/full\"\n");
  Traffic t(*sim, {frame(0x1, {}), frame(0x2, {})});
  sim->scheduler().run_until(model::SimTime::from_ns(1'000'000));
  EXPECT_EQ(sim->flush_recorders(),
            (std::vector<std::string>{"recorder of can0: write /dev/full: No space left on device; "
                                      "frames are being lost (2 so far)"}));
  t.queue.push_back(frame(0x3, {}));
  t.tx->kick();
  sim->scheduler().run_until(model::SimTime::from_ns(2'000'000));
  EXPECT_TRUE(sim->flush_recorders().empty());  // still failing: not logged again
  ipc::RecorderListReply list{};
  fill_recorder_list(*sim, list);
  EXPECT_EQ(list.recorders[0].lost, 3u);
  EXPECT_EQ(ipc::name_of(list.recorders[0].error), "write /dev/full: No space left on device");
}

// ---- LIN: lin0 of the embedded default (19200 bit/s, bus 2) into pcap with LINKTYPE_LIN

using test_support::lin::hex;
using test_support::lin::inverted_sum;
using test_support::lin::pid;

// Bit k of a frame starting at `from_ns` at 19200 bit/s, rounded down to the ns.
int64_t at_bits(int64_t from_ns, int64_t bits) {
  return from_ns + bits * 1'000'000'000 / 19200;
}

// A pcap record header (little-endian seconds, nanoseconds, 2 x length) as hex.
std::string record_header(int64_t ns, int size) {
  const auto le = [](uint32_t v) {
    return fmt::format("{:02X}{:02X}{:02X}{:02X}", v & 0xFF, (v >> 8) & 0xFF, (v >> 16) & 0xFF,
                       v >> 24);
  };
  return le(static_cast<uint32_t>(ns / 1'000'000'000)) +
         le(static_cast<uint32_t>(ns % 1'000'000'000)) + le(static_cast<uint32_t>(size)) +
         le(static_cast<uint32_t>(size));
}

struct LinPeer : model::lin::LinNode {
  model::lin::LinBus& bus;
  std::map<uint8_t, model::lin::Response> table;
  model::lin::LinNodeId id;
  explicit LinPeer(model::lin::LinBus& b) : bus(b), id(b.attach(*this)) {}
  ~LinPeer() override { bus.detach(id); }
  std::optional<model::lin::Response> respond(uint8_t frame_id) override {
    const auto it = table.find(frame_id);
    return it == table.end() ? std::nullopt : std::optional(it->second);
  }
  void on_lin_event(const model::lin::Event&) override {}
  uint32_t lin_bitrate() const override { return 19200; }
};

model::lin::Response lin_response(std::vector<uint8_t> data, model::lin::Checksum kind) {
  model::lin::Response r;
  std::copy(data.begin(), data.end(), r.data.begin());
  r.size = static_cast<uint8_t>(data.size());
  r.checksum = kind;
  return r;
}

// A frame, a header nobody answers, two responders whose checksums collide, the go-to-sleep
// command, a wake-up pulse and 4 s of silence.
void lin_traffic(Simulation& sim) {
  using model::lin::Checksum;
  model::lin::LinBus& bus = *sim.lin_bus(2);
  LinPeer commander(bus);
  LinPeer a(bus);
  LinPeer b(bus);
  a.table[0x10] = lin_response({0x01, 0x00}, Checksum::enhanced);
  a.table[0x11] = lin_response({0x01}, Checksum::enhanced);
  b.table[0x11] = lin_response({0x01}, Checksum::classic);
  auto& s = sim.scheduler();
  const auto run_to = [&](int64_t ns) { s.run_until(model::SimTime::from_ns(ns)); };
  bus.send_header(commander.id, 0x10);
  run_to(10'000'000);
  bus.send_header(commander.id, 0x20);
  run_to(20'000'000);
  bus.send_header(commander.id, 0x11);
  run_to(30'000'000);
  bus.send_sleep(commander.id);
  run_to(40'000'000);
  bus.send_wakeup(commander.id, model::microseconds(250));
  run_to(5'000'000'000);
}

TEST(Recorder, RecordsALinBusAsLinktypeLinAtTheExactInstants) {
  TempDir dir;
  auto sim =
      world("[[recorder]]\nbus = \"lin0\"\npath = \"" + (dir.path / "lin0.pcap").string() + "\"\n");
  lin_traffic(*sim);
  EXPECT_TRUE(sim->flush_recorders().empty());
  const std::string file = hex(read_file(dir.path / "lin0.pcap"));
  const std::string header =
      "4D3CB2A1020004000000000000000000"
      "10000000D4000000";
  // The frame: 34 header bits and 3 characters; length 2, enhanced.
  const std::string frame10 =
      record_header(at_bits(0, 64), 12) + fmt::format("0100000022{:02X}{:02X}0001000000", pid(0x10),
                                                      inverted_sum({pid(0x10), 0x01, 0x00}));
  // Nobody answers 20h: the error 160 bits after the break (34 + 14 x 9).
  const std::string none20 = record_header(at_bits(10'000'000, 160), 12) +
                             fmt::format("0100000000{:02X}000100000000", pid(0x20));
  // 11h answered with the same data and both checksum kinds: the wire carries the AND of the
  // two checksum characters, which matches neither.
  const int wired = inverted_sum({pid(0x11), 0x01}) & inverted_sum({0x01});
  const std::string bad11 = record_header(at_bits(20'000'000, 54), 12) +
                            fmt::format("0100000010{:02X}{:02X}0801000000", pid(0x11), wired);
  // The go-to-sleep command (8 bytes, classic) and its event at the same instant.
  const int64_t sleep_at = at_bits(30'000'000, 124);
  const std::string sleep =
      record_header(sleep_at, 16) +
      fmt::format("0100000081{:02X}{:02X}0000FFFFFFFFFFFFFF", pid(0x3C),
                  inverted_sum({0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF})) +
      record_header(sleep_at, 12) + "010000004C000000B0B00001";
  const std::string wakeup = record_header(40'250'000, 12) + "010000004C000000B0B00004";
  const std::string idle = record_header(4'040'250'000, 12) + "010000004C000000B0B00002";
  EXPECT_EQ(file, header + frame10 + none20 + bad11 + sleep + wakeup + idle);
  ipc::RecorderListReply list{};
  fill_recorder_list(*sim, list);
  ASSERT_EQ(list.count, 1);
  EXPECT_EQ(ipc::name_of(list.recorders[0].bus), "lin0");
  EXPECT_EQ(list.recorders[0].format, static_cast<uint8_t>(ipc::CaptureFormat::pcap));
  EXPECT_EQ(list.recorders[0].frames, 7u);
}

TEST(Recorder, ALinRecorderWithoutErrorsKeepsFramesAndEvents) {
  TempDir dir;
  // No format and no .pcap: a LIN bus's recording is pcap all the same.
  auto sim = world("[[recorder]]\nbus = \"lin0\"\npath = \"" + (dir.path / "lin0.rec").string() +
                   "\"\nerrors = false\n");
  lin_traffic(*sim);
  sim->flush_recorders();
  const std::string bytes = read_file(dir.path / "lin0.rec");
  // The frame, the go-to-sleep command and the three events.
  EXPECT_EQ(bytes.size(), 24u + 28 + 32 + 3 * 28);
  EXPECT_EQ(static_cast<uint8_t>(bytes[20]), 212);
}

TEST(Recorder, TheLinRecordOfEachKindOfError) {
  namespace lp = ipc::lin_pcap;
  model::lin::Event e;
  e.kind = model::lin::Event::Kind::error;
  const auto errors_of = [&](model::lin::ErrorKind kind, uint8_t id) {
    e.error = kind;
    e.id = id;
    return lin_pcap_message(e);
  };
  using model::lin::ErrorKind;
  EXPECT_EQ(errors_of(ErrorKind::no_response, 0x20).errors, lp::kErrorNoSlaveResponse);
  EXPECT_EQ(errors_of(ErrorKind::checksum, 0x20).errors, lp::kErrorChecksum);
  EXPECT_EQ(errors_of(ErrorKind::parity, 0xFF).errors, lp::kErrorParity);
  EXPECT_EQ(errors_of(ErrorKind::parity, 0xFF).pid, 0);  // not received
  EXPECT_EQ(errors_of(ErrorKind::sync, 0xFF).errors, lp::kErrorFraming);
  EXPECT_EQ(errors_of(ErrorKind::other, 0xFF).errors, lp::kErrorFraming);
  EXPECT_EQ(errors_of(ErrorKind::bit, 0x10).errors, lp::kErrorFraming);
  EXPECT_EQ(errors_of(ErrorKind::bit, 0x10).pid, pid(0x10));
  EXPECT_EQ(errors_of(ErrorKind::no_response, 0x3F).errors,
            lp::kErrorNoSlaveResponse | lp::kErrorInvalidId);
  EXPECT_EQ(errors_of(ErrorKind::inactive, 0xFF), lp::event(lp::kEventInactivity));
  for (const auto kind : {ErrorKind::no_response, ErrorKind::parity, ErrorKind::sync}) {
    EXPECT_EQ(errors_of(kind, 0x20).checksum_type, lp::ChecksumType::unknown);
    EXPECT_EQ(errors_of(kind, 0x20).length, 0);
  }
}

TEST(RecorderConfig, ALinBusIsRecordedAsPcapOnly) {
  const std::string base = std::string(embedded_default_config());
  const Config cfg = daemon_test::config_of(
      base + "[[recorder]]\nbus = \"lin0\"\npath = \"lin0.log\"\n", "/etc/canemu/canemu.toml");
  EXPECT_TRUE(cfg.recorders.at(0).pcap);
  EXPECT_EQ(
      daemon_test::config_errors(
          "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n"
          "[[recorder]]\nbus = \"lin0\"\npath = \"lin0.log\"\nformat = \"candump\"\n"),
      (std::vector<std::string>{"t.toml:8:10: recorder[0].format: \"lin0\" is a LIN bus; a candump "
                                "log holds CAN frames only, format = \"pcap\" records it "
                                "(LINKTYPE_LIN)"}));
}

TEST(RecorderConfig, ReadsEveryKeyAndNamesEveryMistake) {
  const std::string base = std::string(embedded_default_config());
  const Config cfg =
      daemon_test::config_of(base +
                                 "[[recorder]]\nbus = \"can1\"\npath = \"logs/can1.pcap\"\n"
                                 "max_size = \"10MiB\"\nmax_files = 3\nerrors = false\n",
                             "/etc/canemu/canemu.toml");
  ASSERT_EQ(cfg.recorders.size(), 1u);
  const RecorderConfig& r = cfg.recorders[0];
  EXPECT_EQ(r.bus, "can1");
  EXPECT_EQ(r.path, "/etc/canemu/logs/can1.pcap");
  EXPECT_TRUE(r.pcap);
  EXPECT_EQ(r.max_size, 10u << 20);
  EXPECT_EQ(r.max_files, 3u);
  EXPECT_FALSE(r.errors);

  const std::vector<std::string> errors = daemon_test::config_errors(
      "[[bus]]\nname = \"can0\"\n[[bus]]\nname = \"can1\"\n"
      "[[recorder]]\nbus = \"can9\"\npath = \"a.log\"\n"
      "format = \"asc\"\nmax_size = \"10MB\"\ncolour = 1\n"
      "[[recorder]]\nbus = \"can0\"\npath = \"a.log\"\nmax_size = 5\n");
  const std::vector<std::string> expected = {
      "t.toml:10:1: recorder[0].colour: unknown key (known here: bus, path, format, max_size, "
      "max_files, errors)",
      "t.toml:6:7: recorder[0].bus: no bus is named \"can9\"",
      "t.toml:8:10: recorder[0].format: \"asc\" is not a recording format (candump, pcap)",
      "t.toml:9:12: recorder[0].max_size: \"10MB\" is not a size (bytes, or a number with KiB, "
      "MiB, GiB)",
      "t.toml:13:8: recorder[1].path: another recorder writes \"a.log\" already",
      "t.toml:14:12: recorder[1].max_size: 5 bytes is outside 1024..1099511627776 (or 0: no "
      "rotation)"};
  EXPECT_EQ(errors, expected);
}

// A recorder on each of 33 buses: a page of 32, then the 33rd; a page beyond the end is empty.
TEST(RecorderList, ComesInPages) {
  TempDir dir;
  std::string text = testing::many_buses_config(40, 0);
  for (int b = 0; b < 33; ++b) {
    text += fmt::format("[[recorder]]\nbus = \"bus{}\"\npath = \"{}\"\n", b,
                        (dir.path / fmt::format("bus{}.log", b)).string());
  }
  auto cfg = parse_config(text, "/etc/canemu/test.toml");
  ASSERT_TRUE(cfg) << cfg.error().front();
  auto sim = Simulation::build(*cfg);
  ASSERT_TRUE(sim) << sim.error().front();
  auto first = std::make_unique<ipc::RecorderListReply>();
  fill_recorder_list(**sim, *first);
  EXPECT_EQ(first->total, 33u);
  EXPECT_EQ(first->first, 0u);
  ASSERT_EQ(first->count, ipc::kRecorderPage);
  for (std::size_t i = 0; i < ipc::kRecorderPage; ++i) {
    EXPECT_EQ(ipc::name_of(first->recorders[i].bus), fmt::format("bus{}", i));
  }
  auto second = std::make_unique<ipc::RecorderListReply>();
  fill_recorder_list(**sim, *second, ipc::kRecorderPage);
  EXPECT_EQ(second->total, 33u);
  EXPECT_EQ(second->first, ipc::kRecorderPage);
  ASSERT_EQ(second->count, 1u);
  EXPECT_EQ(ipc::name_of(second->recorders[0].bus), "bus32");
  EXPECT_EQ(ipc::name_of(second->recorders[0].path), (dir.path / "bus32.log").string());
  auto beyond = std::make_unique<ipc::RecorderListReply>();
  fill_recorder_list(**sim, *beyond, 40);
  EXPECT_EQ(beyond->count, 0u);
  EXPECT_EQ(beyond->total, 33u);
}

}  // namespace
}  // namespace canemu::daemon
