// [[can_node]]: every key read, and every mistake named with its place.
#include <gtest/gtest.h>

#include "canemu/daemon/config/config.hpp"

namespace canemu::daemon {
namespace {

// Lines 1 to 12; a test's tables begin on line 13.
constexpr std::string_view kBuses = R"([[bus]]
name = "can0"
[[bus]]
name = "fd0"
kind = "can-fd"
data_bitrate = 2000000
[[bus]]
name = "lin0"
kind = "lin"
bitrate = 19200
[simulation]
time = "stepped"
)";

std::vector<std::string> errors_of(std::string_view text) {
  auto c = parse_config(std::string(kBuses) + std::string(text), "t.toml");
  EXPECT_FALSE(c.has_value());
  return c ? std::vector<std::string>{} : c.error();
}

TEST(CanNodeConfig, ReadsANodeItsMessagesAndTheirSignals) {
  auto c = parse_config(std::string(kBuses) + R"(
[[can_node]]
name = "MOTOR"
bus = "fd0"
powered = false

[[can_node.message]]
name = "MOTOR_STATUS"
id = 0x12345
extended = true
fd = true
brs = true
length = 12
send = "cyclic_and_on_change"
cycle = "100ms"
delay = "2.5ms"

[[can_node.message.signal]]
name = "speed"
start = 23
length = 16
byte_order = "big_endian"
signed = true
scale = 0.001
offset = -1
minimum = -30
maximum = 30
initial = 1.5
inactive = 0
unit = "kph"

[[can_node.message.signal]]
name = "mode"
start = 0
length = 4
byte_order = "little_endian"
multiplexer = true

[[can_node.message.signal]]
name = "ratio"
start = 32
length = 32
byte_order = "little_endian"
type = "float32"
multiplexer_ids = [1, 3]

[[can_node.message.signal]]
name = "alive"
start = 4
length = 4
byte_order = "little_endian"
counter = true

[[can_node.message.signal]]
name = "crc"
start = 88
length = 8
byte_order = "little_endian"
checksum = "crc8_sae_j1850"
data_id = 18
)",
                        "t.toml");
  ASSERT_TRUE(c.has_value()) << c.error().front();
  ASSERT_EQ(c->can_nodes.size(), 1u);
  const CanNodeConfig& n = c->can_nodes[0];
  EXPECT_EQ(n.name, "MOTOR");
  EXPECT_EQ(n.bus, "fd0");
  EXPECT_FALSE(n.powered);
  EXPECT_EQ(n.line, 14u);
  ASSERT_EQ(n.messages.size(), 1u);
  const CanMessageConfig& m = n.messages[0];
  EXPECT_EQ(m.name, "MOTOR_STATUS");
  EXPECT_EQ(m.id, 0x12345u);
  EXPECT_TRUE(m.extended);
  EXPECT_TRUE(m.fd);
  EXPECT_TRUE(m.brs);
  EXPECT_EQ(m.length, 12u);
  EXPECT_EQ(m.send, CanMessageConfig::Send::cyclic_and_on_change);
  EXPECT_EQ(m.cycle_ns, 100'000'000);
  EXPECT_EQ(m.delay_ns, 2'500'000);
  ASSERT_EQ(m.signals.size(), 5u);
  const CanSignalConfig& s = m.signals[0];
  EXPECT_EQ(s.name, "speed");
  EXPECT_EQ(s.layout.start, 23u);
  EXPECT_EQ(s.layout.length, 16u);
  EXPECT_EQ(s.layout.byte_order, SignalLayout::ByteOrder::big_endian);
  EXPECT_TRUE(s.layout.is_signed);
  EXPECT_EQ(s.layout.scale, 0.001);
  EXPECT_EQ(s.layout.offset, -1.0);
  EXPECT_EQ(s.minimum, -30.0);
  EXPECT_EQ(s.maximum, 30.0);
  EXPECT_EQ(s.initial, 1.5);
  EXPECT_EQ(s.inactive, 0.0);
  EXPECT_EQ(s.unit, "kph");
  EXPECT_TRUE(m.signals[1].multiplexer);
  EXPECT_EQ(m.signals[2].layout.type, SignalLayout::Type::float32);
  EXPECT_EQ(m.signals[2].multiplexer_ids, (std::vector<uint64_t>{1, 3}));
  EXPECT_TRUE(m.signals[3].counter);
  EXPECT_EQ(m.signals[4].checksum, ChecksumKind::crc8_sae_j1850);
  EXPECT_EQ(m.signals[4].data_id, 18u);
}

TEST(CanNodeConfig, AppliesTheDefaults) {
  auto c = parse_config(std::string(kBuses) + R"(
[[can_node]]
name = "gw"
bus = "can0"
[[can_node.message]]
name = "M"
id = 1
cycle = "1ms"
[[can_node.message.signal]]
name = "S"
start = 0
length = 1
)",
                        "t.toml");
  ASSERT_TRUE(c.has_value()) << c.error().front();
  const CanNodeConfig& n = c->can_nodes[0];
  EXPECT_TRUE(n.powered);
  const CanMessageConfig& m = n.messages[0];
  EXPECT_FALSE(m.extended || m.fd || m.brs);
  EXPECT_EQ(m.send, CanMessageConfig::Send::cyclic);
  EXPECT_EQ(m.delay_ns, 0);
  EXPECT_EQ(m.length, 8u);
  EXPECT_EQ(m.signals[0].layout.byte_order, SignalLayout::ByteOrder::little_endian);
}

// A node on can0 with one message whose keys are `message` and whose one signal is `signal`.
std::string one(std::string_view message, std::string_view signal = "") {
  std::string text = "[[can_node]]\nname = \"N\"\nbus = \"can0\"\n[[can_node.message]]\n";
  text += message;
  if (!signal.empty()) {
    text += "[[can_node.message.signal]]\n";
    text += signal;
  }
  return text;
}
// Line 13: [[can_node]]; 16: [[can_node.message]]; its keys from 17 on.
constexpr std::string_view kMessage = "name = \"M\"\nid = 0x10\nlength = 8\ncycle = \"10ms\"\n";
// The signal's table on line 21: its name on 22, byte_order on 23, the keys of sig() from 24 on.
std::string sig(std::string_view keys) {
  return std::string("name = \"S\"\nbyte_order = \"little_endian\"\n") + std::string(keys);
}

TEST(CanNodeConfig, TakesAStartValueOutsideTheRangeAndANodeWithoutMessages) {
  // DBC files start signals at codes outside their range ("init"); a node that sends nothing
  // stands for an ECU that only acknowledges.
  auto c = parse_config(std::string(kBuses) +
                            one(kMessage, sig("start = 0\nlength = 8\nminimum = "
                                              "0\nmaximum = 10\ninitial = 11\n")) +
                            "[[can_node]]\nname = \"Q\"\nbus = \"can0\"\n",
                        "t.toml");
  ASSERT_TRUE(c.has_value()) << c.error().front();
  EXPECT_EQ(c->can_nodes[0].messages[0].signals[0].initial, 11.0);
  EXPECT_TRUE(c->can_nodes[1].messages.empty());
}

struct Case {
  std::string text;
  std::string error;
};

TEST(CanNodeConfig, RefusesEachMistakeWithItsPlace) {
  const std::vector<Case> cases = {
      {"[[can_node]]\nname = \"N\"\nbus = \"lin0\"\n[[can_node.message]]\n" + std::string(kMessage),
       "t.toml:15:7: can_node[0].bus: \"lin0\" is a LIN bus; a CAN node needs a CAN or CAN FD "
       "bus ([[lin_node]] simulates LIN nodes)"},
      {"[[can_node]]\nname = \"N\"\nbus = \"can9\"\n[[can_node.message]]\n" + std::string(kMessage),
       "t.toml:15:7: can_node[0].bus: no bus is named \"can9\""},
      {"[[can_node]]\nname = \"N N\"\nbus = \"can0\"\n[[can_node.message]]\n" +
           std::string(kMessage),
       "t.toml:14:8: can_node[0].name: must be 1 to 28 letters, digits, '_' and '-' (a DBC node "
       "name)"},
      {one(kMessage) + one(kMessage),
       "t.toml:22:8: can_node[1].name: a CAN node named \"N\" exists on \"can0\" already"},
      {one(std::string(kMessage) + "speed = 1\n"),
       "t.toml:21:1: can_node[0].message[0].speed: unknown key (known here: name, id, extended, "
       "fd, brs, length, send, cycle, delay, signal)"},
      {one(kMessage) + "[[can_node.message]]\nname = \"M2\"\nid = 16\nlength = 1\ncycle = \"1s\"\n",
       "t.toml:23:6: can_node[0].message[1].id: the node sends message M with standard "
       "identifier 0x10 already"},
      {one("name = \"M\"\nid = 0x800\nlength = 8\ncycle = \"10ms\"\n"),
       "t.toml:18:6: can_node[0].message[0].id: 2048 is outside 0..2047"},
      {one("name = \"M\"\nid = 1\nlength = 9\ncycle = \"10ms\"\n"),
       "t.toml:19:10: can_node[0].message[0].length: 9 bytes: a classic frame has 0 to 8 (fd = "
       "true for more)"},
      {one("name = \"M\"\nid = 1\nlength = 12\nfd = true\ncycle = \"10ms\"\n"),
       "t.toml:20:6: can_node[0].message[0].fd: \"can0\" is a classic CAN bus; a CAN FD message "
       "needs a can-fd bus"},
      {"[[can_node]]\nname = \"N\"\nbus = \"fd0\"\n[[can_node.message]]\nname = \"M\"\nid = "
       "1\nlength = 13\nfd = true\ncycle = \"10ms\"\n",
       "t.toml:19:10: can_node[0].message[0].length: 13 is not a CAN FD length (0 to 8, 12, 16, "
       "20, 24, 32, 48, 64)"},
      {one("name = \"M\"\nid = 1\nlength = 8\nbrs = true\ncycle = \"10ms\"\n"),
       "t.toml:20:7: can_node[0].message[0].brs: only a CAN FD message (fd = true) switches bit "
       "rate"},
      {one("name = \"M\"\nid = 1\nlength = 8\n"),
       "t.toml:16:1: can_node[0].message[0].cycle: missing (a cyclic message needs its cycle, "
       "e.g. \"100ms\")"},
      {one("name = \"M\"\nid = 1\nlength = 8\ncycle = \"0.5ms\"\n"),
       "t.toml:20:9: can_node[0].message[0].cycle: \"0.5ms\" is not a duration from 1ms to 1h "
       "(examples: 10ms, 1s)"},
      {one("name = \"M\"\nid = 1\nlength = 8\nsend = \"on_change\"\ncycle = \"10ms\"\n"),
       "t.toml:21:9: can_node[0].message[0].cycle: an on_change message has no cycle"},
      {one("name = \"M\"\nid = 1\nlength = 8\nsend = \"sometimes\"\ncycle = \"10ms\"\n"),
       "t.toml:20:8: can_node[0].message[0].send: \"sometimes\" is not a send kind (cyclic, "
       "on_change, cyclic_if_active, cyclic_and_on_change)"},
      {one("name = \"M\"\nid = 1\nlength = 8\nsend = \"cyclic_if_active\"\ncycle = \"10ms\"\n"),
       "t.toml:20:8: can_node[0].message[0].send: a cyclic_if_active message needs a signal "
       "with an inactive value (inactive = ...)"},
      {one(kMessage, sig("start = 60\nlength = 8\n")),
       "t.toml:21:1: can_node[0].message[0].signal[0]: signal S (8 bits from bit 60, "
       "little_endian) does not fit the message's 8 bytes"},
      {one(kMessage, "name = \"S\"\nbyte_order = \"big_endian\"\nstart = 3\nlength = 61\n"),
       "t.toml:21:1: can_node[0].message[0].signal[0]: signal S (61 bits from bit 3, "
       "big_endian) does not fit the message's 8 bytes"},
      {one(kMessage, sig("start = 0\nlength = 8\n") +
                         "[[can_node.message.signal]]\nname = \"T\"\nbyte_order = "
                         "\"big_endian\"\nstart = 7\nlength = 1\n"),
       "t.toml:26:1: can_node[0].message[0].signal[1]: signal T shares bits with signal S "
       "(can_node[0].message[0].signal[0]) in the same frames"},
      {one(kMessage, sig("start = 0\nlength = 8\nchecksum = \"xor8\"\n") +
                         "[[can_node.message.signal]]\nname = \"S\"\nbyte_order = "
                         "\"little_endian\"\nstart = 8\nlength = 8\n"),
       "t.toml:28:8: can_node[0].message[0].signal[1].name: the message has a signal named "
       "\"S\" already"},
      {one(kMessage, sig("start = 4\nlength = 8\nchecksum = \"xor8\"\n")),
       "t.toml:21:1: can_node[0].message[0].signal[0]: a checksum is one whole byte: length = 8 "
       "and start a multiple of 8"},
      {one(kMessage, sig("start = 0\nlength = 8\nchecksum = \"md5\"\n")),
       "t.toml:26:12: can_node[0].message[0].signal[0].checksum: \"md5\" is not a checksum kind "
       "(crc8_sae_j1850, xor8, sum8)"},
      {one(kMessage, sig("start = 0\nlength = 8\nchecksum = \"xor8\"\ndata_id = 3\n")),
       "t.toml:27:11: can_node[0].message[0].signal[0].data_id: only a checksum = "
       "\"crc8_sae_j1850\" signal has a data ID"},
      {one(kMessage, sig("start = 0\nlength = 8\ninitial = 256\n")),
       "t.toml:26:11: can_node[0].message[0].signal[0].initial: 256 does not fit the signal's 8 "
       "bits"},
      {one(kMessage, sig("start = 0\nlength = 8\nminimum = 0\n")),
       "t.toml:21:1: can_node[0].message[0].signal[0]: minimum and maximum go together (the "
       "range signal set checks)"},
      {one(kMessage, sig("start = 0\nlength = 8\nscale = 0\n")),
       "t.toml:26:9: can_node[0].message[0].signal[0].scale: must be a finite number other "
       "than 0"},
      {one(kMessage, sig("start = 0\nlength = 16\ntype = \"float32\"\n")),
       "t.toml:25:10: can_node[0].message[0].signal[0].length: a float32 signal has 32 bits"},
      {one(kMessage, sig("start = 0\nlength = 8\nmultiplexer_ids = [1]\n")),
       "t.toml:16:1: can_node[0].message[0].signal[0].multiplexer_ids: the message has no "
       "multiplexer (multiplexer = true on one signal)"},
      {one(kMessage, sig("start = 0\nlength = 8\ncounter = true\nsigned = true\n")),
       "t.toml:21:1: can_node[0].message[0].signal[0]: a multiplexer, counter or checksum is an "
       "unsigned integer signal (signed = false, type = \"integer\")"},
      {one(kMessage, sig("start = 0\nlength = 8\nbits = 8\n")),
       "t.toml:26:1: can_node[0].message[0].signal[0].bits: unknown key (known here: name, "
       "start, length, byte_order, signed, type, scale, offset, minimum, maximum, initial, "
       "inactive, unit, multiplexer, multiplexer_ids, counter, checksum, data_id)"},
  };
  for (const Case& c : cases) {
    const auto errors = errors_of(c.text);
    ASSERT_FALSE(errors.empty()) << c.text;
    EXPECT_EQ(errors.front(), c.error) << c.text;
  }
}

TEST(CanNodeConfig, MultiplexedSignalsShareBitsOnlyUnderDifferentMultiplexorValues) {
  const std::string mux =
      one(kMessage, sig("start = 0\nlength = 8\nmultiplexer = true\n")) +
      "[[can_node.message.signal]]\nname = \"A\"\nbyte_order = \"little_endian\"\nstart = "
      "8\nlength = 8\nmultiplexer_ids = [0, 1]\n"
      "[[can_node.message.signal]]\nname = \"B\"\nbyte_order = \"little_endian\"\nstart = "
      "8\nlength = 8\nmultiplexer_ids = [2]\n";
  EXPECT_TRUE(parse_config(std::string(kBuses) + mux, "t.toml").has_value());
  EXPECT_EQ(errors_of(mux + "[[can_node.message.signal]]\nname = \"C\"\nbyte_order = "
                            "\"little_endian\"\nstart = 12\nlength = 8\nmultiplexer_ids = [1]\n")
                .front(),
            "t.toml:39:1: can_node[0].message[0].signal[3]: signal C shares bits with signal A "
            "(can_node[0].message[0].signal[1]) in the same frames");
}

TEST(CanNodeConfig, ABussMessagesHaveOneSenderEach) {
  const std::string other = "[[can_node]]\nname = \"O\"\nbus = \"can0\"\n[[can_node.message]]\n";
  EXPECT_EQ(
      errors_of(one(kMessage) + other + "name = \"M\"\nid = 0x11\nlength = 8\ncycle = \"1s\"\n")
          .front(),
      "t.toml:25:8: can_node[1].message[0].name: node N sends a message named \"M\" on "
      "\"can0\" already");
  EXPECT_EQ(
      errors_of(one(kMessage) + other + "name = \"M2\"\nid = 16\nlength = 8\ncycle = \"1s\"\n")
          .front(),
      "t.toml:26:6: can_node[1].message[0].id: node N sends identifier 0x10 on \"can0\" "
      "already (two senders of one identifier collide on the wire)");
  // On another bus they are other messages.
  std::string fd = other + "name = \"M\"\nid = 0x10\nlength = 8\ncycle = \"1s\"\n";
  fd.replace(fd.find("can0"), 4, "fd0");
  EXPECT_TRUE(parse_config(std::string(kBuses) + one(kMessage) + fd, "t.toml").has_value());
}

TEST(CanNodeConfig, RunTimeLoadsAreCheckedAgainstTheBuses) {
  auto c = parse_config(kBuses, "t.toml");
  ASSERT_TRUE(c);
  auto nodes = parse_can_nodes(one(kMessage), "more.toml", c->buses);
  ASSERT_TRUE(nodes) << nodes.error().front();
  EXPECT_EQ(nodes->size(), 1u);
  EXPECT_EQ(parse_can_nodes("[[lin_node]]\n", "more.toml", c->buses).error().front(),
            "more.toml:1:3: lin_node: unknown key (known here: can_node)");
  EXPECT_EQ(parse_can_nodes("", "more.toml", c->buses).error().front(),
            "more.toml: no [[can_node]] tables");
}

}  // namespace
}  // namespace canemu::daemon
