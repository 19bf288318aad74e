// A simulated CAN node ([[can_node]]) of canemud's configuration file, in stepped time: its
// frames reach a client's channel with their bytes and their exact instants; faults on its
// signals listed whole, however many and however long their names.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "../support/temp_dir.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/ipc/can_node_messages.hpp"
#include "cli_run_support.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

using testing::connect;
using testing::Daemon;
using testing::status;
using testing::TempDir;
using testing::write_file;

constexpr int64_t kBit = 2000;  // ns at 500 kbit/s

constexpr const char* kConfig = R"([[bus]]
name = "can0"
bitrate = 500000

[[can_node]]
name = "MOTOR"
bus = "can0"

[[can_node.message]]
name = "MOTOR_STATUS"
id = 0x190
length = 3
cycle = "10ms"
delay = "5ms"

[[can_node.message.signal]]
name = "speed"
start = 8
length = 16
byte_order = "little_endian"
scale = 0.01
initial = 12.34

[[can_node.message.signal]]
name = "alive"
start = 0
length = 4
byte_order = "little_endian"
counter = true
)";

TEST(Restbus, ANodeOfTheConfigurationSendsItsFramesToAChannelAtTheirInstants) {
  TempDir dir;
  const std::string file = (dir.path / "restbus.toml").string();
  FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs(kConfig, f);
  std::fclose(f);
  Daemon d("stepped", {"--config=" + file});
  auto c = connect(d);
  client::ChannelOptions o;
  o.bus = "can0";
  auto ch = client::Channel::open(c, o);
  ASSERT_TRUE(ch) << ch.error().message;
  auto step = ipc::make_message<ipc::TimeStepRequest>();
  step.step_ns = 30'000'000;
  ASSERT_TRUE((c.call<ipc::TimeStepRequest, ipc::TimeStepReply>(step)));
  std::vector<ipc::ChannelMessage> rx;
  while (auto m = ch->receive(0)) {
    rx.push_back(*m);
  }
  // Queued at 5, 15 and 25 ms on an idle bus: each is received at the end of its EOF.
  ASSERT_EQ(rx.size(), 3u);
  for (std::size_t i = 0; i < rx.size(); ++i) {
    const std::vector<uint8_t> data{static_cast<uint8_t>(i), 0xD2, 0x04};  // 1234 = 0x04D2
    const auto frame = *model::Frame::classic(0x190, data);
    const int64_t start = 5'000'000 + 10'000'000 * static_cast<int64_t>(i);
    EXPECT_EQ(rx[i].timestamp_ns, start + model::encode(frame).length * kBit) << i;
    EXPECT_EQ(rx[i].id, 0x190u);
    EXPECT_EQ(rx[i].dlc, 3);
    EXPECT_EQ(std::vector<uint8_t>(rx[i].data, rx[i].data + 3), data) << i;
  }
  // canemu status lists the node by its name, with what it sent.
  const ipc::StatusReply s = status(c);
  bool listed = false;
  for (uint16_t i = 0; i < s.node_count; ++i) {
    if (ipc::name_of(s.nodes[i].name) == "MOTOR") {
      listed = true;
      EXPECT_EQ(s.nodes[i].frames_sent, 3u);
    }
  }
  EXPECT_TRUE(listed);
}

}  // namespace
// A load gathers at most kMaxCanNodeLoad bytes over its parts: one part beyond is refused with
// the reason, what came before is dropped, and nothing starts.
TEST(Restbus, ALoadLongerThanOneMebibyteIsRefusedAndNothingStarts) {
  Daemon d("stepped");
  auto c = connect(d);
  auto part = ipc::make_message<ipc::CanNodeRequest>();
  part.op = static_cast<uint8_t>(ipc::CanNodeOp::load_part);
  const std::string comment = "# " + std::string(sizeof part.text - 3, 'x') + "\n";
  std::memcpy(part.text, comment.data(), comment.size());
  part.length = static_cast<uint32_t>(comment.size());
  std::size_t sent = 0;
  std::string refused;
  while (refused.empty() && sent <= ipc::kMaxCanNodeLoad) {
    auto r = c.call<ipc::CanNodeRequest, ipc::CanNodeReply>(part);
    ASSERT_TRUE(r);
    sent += comment.size();
    refused = r->ok ? "" : ipc::name_of(r->errors);
  }
  EXPECT_EQ(sent, (ipc::kMaxCanNodeLoad / comment.size() + 1) * comment.size());
  EXPECT_EQ(refused, "the tables are longer than 1048576 bytes");
  auto list = ipc::make_message<ipc::CanNodeRequest>();
  list.op = static_cast<uint8_t>(ipc::CanNodeOp::list);
  auto r = c.call<ipc::CanNodeRequest, ipc::CanNodeReply>(list);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->total, 0u);
}

// kConfig with its message MOTOR_STATUS and signal speed renamed.
std::string renamed(const std::string& message, const std::string& signal) {
  std::string config = kConfig;
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"\"MOTOR_STATUS\"", '"' + message + '"'},
        {"\"speed\"", '"' + signal + '"'}}) {
    config.replace(config.find(from), from.size(), to);
  }
  return config;
}

// `canemu fault list` (and the client's fetch_fault_list) gives every fault, more than fit one
// reply (kFaultPage), each target as long as the message's and signal's names make it.
TEST(Restbus, EveryFaultIsListedWithItsWholeTarget) {
  const std::string message = "MOTOR_STATUS_OF_THE_LEFT_REAR_WHEEL_DRIVE_UNIT";
  const std::string signal = "speed_of_the_wheel_in_kilometres_per_hour";
  TempDir dir;
  const std::string file = (dir.path / "restbus.toml").string();
  ASSERT_TRUE(write_file(file, renamed(message, signal)));
  // Two scenarios (a scenario's text is at most 12 KiB), loaded one after the other.
  constexpr int kFaults = 2 * static_cast<int>(ipc::kFaultPage) + 5;
  constexpr int kFirst = kFaults / 2;
  Daemon d("stepped", {"--config=" + file});
  for (const int part : {0, 1}) {
    std::ostringstream scenario;
    scenario << "[scenario]\nname = \"part" << part << "\"\n";
    for (int k = part == 0 ? 0 : kFirst; k < (part == 0 ? kFirst : kFaults); ++k) {
      scenario << "[[fault]]\neffect = \"signal_step\"\nat = \"" << k + 1
               << "ms\"\nbus = \"can0\"\nsignal = \"" << message << '.' << signal
               << "\"\nvalue = " << k << "\n";
    }
    const std::string scenario_file = (dir.path / fmt::format("part{}.toml", part)).string();
    ASSERT_TRUE(write_file(scenario_file, scenario.str()));
    output_of(d, {"fault", "load", scenario_file});
  }

  const std::string target = "can0/" + message + '.' + signal;
  ASSERT_GT(target.size(), ipc::kNameSize);
  auto c = connect(d);
  const auto listed = client::fetch_fault_list(c);
  ASSERT_TRUE(listed) << listed.error().message;
  ASSERT_EQ(listed->size(), static_cast<std::size_t>(kFaults));
  for (int k = 0; k < kFaults; ++k) {
    const ipc::FaultEntry& e = (*listed)[static_cast<std::size_t>(k)];
    EXPECT_EQ(ipc::name_of(e.target), target) << k;
    // In the order they were applied.
    EXPECT_EQ(ipc::name_of(e.scenario), k < kFirst ? "part0" : "part1") << k;
    EXPECT_EQ(e.at_ns, (k + 1) * 1'000'000) << k;
    EXPECT_EQ(e.line, static_cast<uint32_t>(3 + 6 * (k < kFirst ? k : k - kFirst))) << k;
  }
  // The table: a header and a row for each, the target whole.
  const std::string table = output_of(d, {"fault", "list"});
  std::size_t rows = 0;
  for (std::size_t at = table.find(target); at != std::string::npos;
       at = table.find(target, at + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, static_cast<std::size_t>(kFaults)) << table;
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), kFaults + 1) << table;
  EXPECT_EQ(table.find("more not shown"), std::string::npos);
}

// A target longer than a fault entry holds (127 characters) is cut, and ends in "..." to say so.
TEST(Restbus, ATargetTooLongForTheListEndsInDots) {
  const std::string message = "MOTOR_STATUS_OF_THE_LEFT_REAR_WHEEL_DRIVE_UNIT_ON_THE_SECOND_AXLE";
  const std::string signal = "speed_of_the_wheel_in_kilometres_per_hour_as_the_controller_reckons";
  TempDir dir;
  const std::string file = (dir.path / "restbus.toml").string();
  ASSERT_TRUE(write_file(file, renamed(message, signal)));
  Daemon d("stepped", {"--config=" + file});
  const std::string scenario_file = (dir.path / "long.toml").string();
  ASSERT_TRUE(write_file(scenario_file,
                         fmt::format("[scenario]\nname = \"long\"\n[[fault]]\n"
                                     "effect = \"signal_step\"\nat = \"1ms\"\nbus = \"can0\"\n"
                                     "signal = \"{}.{}\"\nvalue = 1\n",
                                     message, signal)));
  output_of(d, {"fault", "load", scenario_file});
  const std::string target = "can0/" + message + '.' + signal;
  ASSERT_GE(target.size(), ipc::kFaultTargetSize);
  auto c = connect(d);
  const auto listed = client::fetch_fault_list(c);
  ASSERT_TRUE(listed) << listed.error().message;
  ASSERT_EQ(listed->size(), 1u);
  EXPECT_EQ(ipc::name_of((*listed)[0].target), target.substr(0, 124) + "...");
}

}  // namespace canemu
