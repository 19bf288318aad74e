// [[lin_node]]: every key read, and every mistake named with its place.
#include <gtest/gtest.h>

#include "canemu/daemon/config/config.hpp"
#include "daemon_test_support.hpp"

namespace canemu::daemon {
namespace {

constexpr std::string_view kBuses = R"(
[[bus]]
name = "lin0"
kind = "lin"
bitrate = 19200

[[bus]]
name = "can0"
kind = "can"
)";

std::vector<std::string> errors_of(const std::string& text) {
  return daemon_test::config_errors(std::string(kBuses) + text);
}

TEST(LinConfig, ReadsACommanderAndAResponder) {
  const Config c = daemon_test::config_of(std::string(kBuses) + R"(
[[lin_node]]
name = "master"
bus = "lin0"
schedule = "normal"

[[lin_node.response]]
id = 0x20
data = [0xC1]

[[lin_node.schedules]]
name = "normal"
slots = [
  { frame = 0x10, delay = "10ms" },
  { event_triggered = 0x30, frames = [0x31, 0x32], delay = "15ms" },
  { sporadic = [0x28, 0x29], delay = "5ms" },
]

[[lin_node.schedules]]
name = "diag"
slots = [{ frame = 0x3C, delay = "20ms" }]

[[lin_node]]
name = "door"
bus = "lin0"
bitrate = 19000
powered = false

[[lin_node.response]]
id = 0x10
data = [1, 2, 3]
checksum = "classic"

[[lin_node.response]]
id = 0x31
data = [0, 0x22]
event_triggered = 0x30
)");
  ASSERT_EQ(c.lin_nodes.size(), 2u);
  const LinNodeConfig& m = c.lin_nodes[0];
  EXPECT_EQ(m.name, "master");
  EXPECT_EQ(m.bus, "lin0");
  EXPECT_EQ(m.bitrate, 0u);
  EXPECT_TRUE(m.powered);
  EXPECT_EQ(m.schedule, "normal");
  ASSERT_EQ(m.responses.size(), 1u);
  EXPECT_EQ(m.responses[0].id, 0x20);
  EXPECT_EQ(m.responses[0].data, (std::vector<uint8_t>{0xC1}));
  EXPECT_TRUE(m.responses[0].enhanced);
  ASSERT_EQ(m.schedules.size(), 2u);
  const auto& slots = m.schedules[0].slots;
  ASSERT_EQ(slots.size(), 3u);
  EXPECT_EQ(slots[0].kind, LinSlotConfig::Kind::unconditional);
  EXPECT_EQ(slots[0].id, 0x10);
  EXPECT_EQ(slots[0].delay_ns, 10'000'000);
  EXPECT_EQ(slots[1].kind, LinSlotConfig::Kind::event_triggered);
  EXPECT_EQ(slots[1].id, 0x30);
  EXPECT_EQ(slots[1].frames, (std::vector<uint8_t>{0x31, 0x32}));
  EXPECT_EQ(slots[1].delay_ns, 15'000'000);
  EXPECT_EQ(slots[2].kind, LinSlotConfig::Kind::sporadic);
  EXPECT_EQ(slots[2].frames, (std::vector<uint8_t>{0x28, 0x29}));
  EXPECT_EQ(m.schedules[1].name, "diag");
  const LinNodeConfig& d = c.lin_nodes[1];
  EXPECT_EQ(d.bitrate, 19000u);
  EXPECT_FALSE(d.powered);
  EXPECT_FALSE(d.responses[0].enhanced);
  EXPECT_EQ(d.responses[1].event_triggered, std::optional<uint8_t>(0x30));
  EXPECT_NE(summary(c).find("lin node master on lin0 (commander, schedule normal)"),
            std::string::npos)
      << summary(c);
  EXPECT_NE(summary(c).find("lin node door on lin0 (responder, switched off)"), std::string::npos);
}

TEST(LinConfig, MistakesAreNamedWithTheirPlace) {
  const auto e = errors_of(R"(
[[lin_node]]
name = "Bad Name"
bus = "can0"
bitrate = 30000
schedule = "missing"
colour = "red"

[[lin_node.response]]
id = 64
data = [1, 2, 3, 4, 5, 6, 7, 8, 9]

[[lin_node.response]]
id = 1
data = [256]
checksum = "strong"

[[lin_node.schedules]]
name = "s"
slots = [
  { frame = 1, sporadic = [2], delay = "10ms" },
  { frame = 70, delay = "soon" },
  { event_triggered = 3, frames = [], delay = "10ms" },
  { frame = 1, frames = [2], delay = "0ns" },
]
)");
  const std::vector<std::string> expected{
      "t.toml:16:1: lin_node[0].colour: unknown key (known here: name, bus, bitrate, powered, "
      "schedule, response, schedules)",
      "t.toml:12:8: lin_node[0].name: must be 1 to 28 characters of a-z, 0-9, '_' and '-'",
      "t.toml:13:7: lin_node[0].bus: \"can0\" is a can bus; a LIN node needs a LIN bus",
      "t.toml:14:11: lin_node[0].bitrate: 30000 is outside 1000..20000",
      "t.toml:19:6: lin_node[0].response[0].id: 64 is outside 0..63",
      "t.toml:20:8: lin_node[0].response[0].data: must be an array of 1 to 8 bytes (0 to 255)",
      "t.toml:24:9: lin_node[0].response[1].data: a byte is an integer from 0 to 255",
      "t.toml:25:12: lin_node[0].response[1].checksum: \"strong\" is not a checksum kind "
      "(enhanced, classic)",
      "t.toml:30:3: lin_node[0].schedules[0].slots[0]: a slot has exactly one of frame, "
      "event_triggered (with frames) and sporadic",
      "t.toml:31:13: lin_node[0].schedules[0].slots[1].frame: 70 is outside 0..63",
      "t.toml:31:25: lin_node[0].schedules[0].slots[1].delay: \"soon\" is not a slot time from "
      "1ns to 10s (examples: 10ms, 5ms)",
      "t.toml:32:35: lin_node[0].schedules[0].slots[2].frames: must be an array of 1 or more LIN "
      "identifiers (0 to 63)",
      "t.toml:33:25: lin_node[0].schedules[0].slots[3].frames: only an event_triggered slot has "
      "frames",
      "t.toml:33:38: lin_node[0].schedules[0].slots[3].delay: \"0ns\" is not a slot time from 1ns "
      "to 10s (examples: 10ms, 5ms)",
      "t.toml:15:12: lin_node[0].schedule: the node has no schedule named \"missing\"",
  };
  EXPECT_EQ(e, expected);
}

TEST(LinConfig, OneCommanderPerBusAndUniqueNames) {
  const auto e = errors_of(R"(
[[lin_node]]
name = "a"
bus = "lin0"
schedule = "s"
[[lin_node.schedules]]
name = "s"
slots = [{ frame = 1, delay = "10ms" }]

[[lin_node]]
name = "a"
bus = "lin0"
schedule = "s"
[[lin_node.schedules]]
name = "s"
slots = [{ frame = 1, delay = "10ms" }]
[[lin_node.schedules]]
name = "s"
slots = [{ frame = 2, delay = "10ms" }]
[[lin_node.response]]
id = 5
data = [1]
[[lin_node.response]]
id = 5
data = [2]

[[lin_node]]
name = "c"
bus = "nowhere"
)");
  const std::vector<std::string> expected{
      "t.toml:20:8: lin_node[1].name: a LIN node named \"a\" exists on \"lin0\" already",
      "t.toml:33:6: lin_node[1].response[1].id: the node has a response for 0x05 already",
      "t.toml:27:8: lin_node[1].schedules[1].name: the node has a schedule named \"s\" already",
      "t.toml:22:12: lin_node[1].schedule: another LIN node runs a schedule on \"lin0\" already; "
      "a LIN bus has one commander",
      "t.toml:38:7: lin_node[2].bus: no bus is named \"nowhere\"",
  };
  EXPECT_EQ(e, expected);
}

TEST(LinConfig, NamesAreScopedByBusSoTwoClustersMayShareANodeName) {
  const Config c = daemon_test::config_of(std::string(kBuses) + R"(
[[bus]]
name = "lin1"
kind = "lin"
bitrate = 19200

[[lin_node]]
name = "bcm"
bus = "lin0"

[[lin_node]]
name = "bcm"
bus = "lin1"
)");
  ASSERT_EQ(c.lin_nodes.size(), 2u);
  EXPECT_EQ(c.lin_nodes[0].bus, "lin0");
  EXPECT_EQ(c.lin_nodes[1].bus, "lin1");
}

}  // namespace
}  // namespace canemu::daemon
