// [[recorder]]: canemud's recorders write what their bus carries, with error frames, at the
// simulated instants, and never lose frames silently.
#include "canemu/daemon/recorder.hpp"

#include <deque>
#include <filesystem>

#include <gtest/gtest.h>

#include "../support/temp_dir.hpp"

#include "canemu/daemon/simulation.hpp"
#include "canemu/daemon/status.hpp"
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
    const auto timing = controller_timing(false, 500'000, 500'000, 875);
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
  const auto timing = controller_timing(false, 500'000, 500'000, 875);
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

TEST(RecorderConfig, ReadsEveryKeyAndNamesEveryMistake) {
  const std::string base = std::string(embedded_default_config());
  auto cfg = parse_config(base +
                              "[[recorder]]\nbus = \"can1\"\npath = \"logs/can1.pcap\"\n"
                              "max_size = \"10MiB\"\nmax_files = 3\nerrors = false\n",
                          "/etc/canemu/canemu.toml");
  ASSERT_TRUE(cfg) << cfg.error().front();
  ASSERT_EQ(cfg->recorders.size(), 1u);
  const RecorderConfig& r = cfg->recorders[0];
  EXPECT_EQ(r.bus, "can1");
  EXPECT_EQ(r.path, "/etc/canemu/logs/can1.pcap");
  EXPECT_TRUE(r.pcap);
  EXPECT_EQ(r.max_size, 10u << 20);
  EXPECT_EQ(r.max_files, 3u);
  EXPECT_FALSE(r.errors);

  auto bad = parse_config(
      "[[bus]]\nname = \"can0\"\n[[bus]]\nname = \"can1\"\n"
      "[[recorder]]\nbus = \"can9\"\npath = \"a.log\"\n"
      "format = \"asc\"\nmax_size = \"10MB\"\ncolour = 1\n"
      "[[recorder]]\nbus = \"can0\"\npath = \"a.log\"\nmax_size = 5\n",
      "t.toml");
  ASSERT_FALSE(bad);
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
  EXPECT_EQ(bad.error(), expected);
}

}  // namespace
}  // namespace canemu::daemon
