// A simulated CAN node ([[can_node]]) of canemud's configuration file, in stepped time: its
// frames reach a client's channel with their bytes and their exact instants.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/ipc/can_node_messages.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

using testing::connect;
using testing::Daemon;
using testing::status;
using testing::TempDir;

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

}  // namespace canemu
