// Fault scenario files: checked whole, every problem with file, line and key.
#include "canemu/daemon/config/scenario.hpp"

#include <gtest/gtest.h>

#include "daemon_test_support.hpp"

namespace canemu::daemon {
namespace {

using daemon_test::scenario_errors;

TEST(Scenario, ReadsEveryKeyOfAFrameFault) {
  auto s = parse_scenario(R"([scenario]
name = "demo"
seed = 7

[[fault]]
at = "2s"
until = "5s"
bus = "can0"
match = { id = 0x100, mask = 0x7F0, ext = false, rtr = false, from = "ixxat0:0" }
effect = "bit_error"
bit = 24
count = 32
probability = 0.5
)",
                          "s.toml");
  ASSERT_TRUE(s) << s.error().front();
  EXPECT_EQ(s->name, "demo");
  EXPECT_EQ(s->seed, 7u);
  ASSERT_EQ(s->faults.size(), 1u);
  const FaultSpec& f = s->faults[0];
  EXPECT_EQ(f.line, 5u);
  EXPECT_EQ(f.effect, FaultEffect::bit_error);
  EXPECT_EQ(f.at_ns, 2'000'000'000);
  EXPECT_EQ(f.until_ns, 5'000'000'000);
  EXPECT_EQ(f.bus, "can0");
  EXPECT_EQ(f.match.id, 0x100u);
  EXPECT_EQ(f.match.mask, 0x7F0u);
  EXPECT_EQ(f.match.ext, false);
  EXPECT_EQ(f.match.from, "ixxat0:0");
  EXPECT_EQ(f.bit, 24);
  EXPECT_EQ(f.count, 32u);
  EXPECT_EQ(f.probability, 0.5);
}

TEST(Scenario, NamesEveryProblemWithItsLine) {
  const auto e = scenario_errors(R"([[fault]]
at = "soon"
bus = "can0"
effect = "bit_error"

[[fault]]
at = "1s"
until = "2s"
bus = "can0"
effect = "ack_suppress"

[[fault]]
at = "1s"
effect = "teleport"

[[fault]]
at = "1s"
node = "x:0"
effect = "lin_wakeup"
pulse = "10ms"

[[fault]]
at = "1s"
bus = "can0"
effect = "crc_error"
probability = 2

[[fault]]
at = "1s"
node = "ixxat0:0"
effect = "error_counters"
tec = 300
)");
  EXPECT_EQ(e,
            (std::vector<std::string>{
                "s.toml:2:6: fault[0].at: \"soon\" is not a duration (examples: 2s, 150ms, "
                "20us, 10ns)",
                "s.toml:8:1: fault[1].until: not a key of ack_suppress (known: at, effect, bus, "
                "duration)",
                "s.toml:6:1: fault[1].duration: missing (a string is required)",
                "s.toml:14:10: fault[2].effect: \"teleport\" is not a fault effect (bit_error, "
                "stuff_error, form_error, crc_error, ack_error, ack_suppress, stuck_dominant, "
                "random_errors, node_off, node_on, bus_off, error_counters, oscillator, "
                "babble, line_error, lin_bit_error, lin_checksum_error, lin_parity_error, "
                "lin_sync_error, lin_no_response, lin_short_break, lin_responder_off, "
                "lin_wakeup, message_timeout, checksum_error, counter_freeze, counter_jump, "
                "signal_step, signal_ramp, signal_invalid)",
                "s.toml:20:9: fault[3].pulse: a LIN wake-up pulse lasts 250 us to 5 ms (LIN 2.x)",
                "s.toml:26:15: fault[4].probability: must be above 0 and at most 1",
                "s.toml:32:7: fault[5].tec: 300 is outside 0..255",
                "s.toml:28:1: fault[5].rec: missing (an integer is required)",
            }));
  EXPECT_EQ(
      scenario_errors("[scenario]\nname = \"empty\"\n"),
      (std::vector<std::string>{"s.toml: no [[fault]] tables: a scenario needs at least one"}));
}

// Names a scenario gives are shown in `fault list`, `status` and the log: printable ASCII only.
TEST(Scenario, NamesWithControlCharactersAreRefused) {
  const auto e = scenario_errors(
      "[scenario]\nname = \"evil\\u001b[31m\\nforged\"\n"
      "[[fault]]\nat = \"0s\"\nnode = \"a\\u0007b\"\neffect = \"node_off\"\n");
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0],
            "s.toml:2:8: scenario.name: \"evil?[31m?forged\" has byte 0x1b at 4: names are "
            "printable ASCII");
  EXPECT_EQ(e[1],
            "s.toml:5:8: fault[0].node: \"a?b\" has byte 0x07 at 1: names are printable ASCII");
  // Without [scenario] name, the file's name serves, made printable.
  auto s = parse_scenario("[[fault]]\nat = \"0s\"\nnode = \"x:0\"\neffect = \"node_off\"\n",
                          "dir/bad\x1b.toml");
  ASSERT_TRUE(s) << s.error().front();
  EXPECT_EQ(s->name, "bad?.toml");
}

TEST(Scenario, BabbleNeedsItsFrameAndDuration) {
  auto s = parse_scenario(R"([[fault]]
at = "1s"
node = "ixxat0:0"
effect = "babble"
id = 0x1ABCDEF
ext = true
data = [0xDE, 0xAD]
duration = "10ms"
)",
                          "s.toml");
  ASSERT_TRUE(s) << s.error().front();
  const FaultSpec& f = s->faults.at(0);
  EXPECT_EQ(f.effect, FaultEffect::babble);
  EXPECT_EQ(f.node, "ixxat0:0");
  EXPECT_EQ(f.id, 0x1ABCDEFu);
  EXPECT_TRUE(f.ext);
  EXPECT_EQ(f.data, (std::vector<uint8_t>{0xDE, 0xAD}));
  EXPECT_EQ(f.duration_ns, 10'000'000);

  const auto e = scenario_errors(R"([[fault]]
at = "1s"
node = "ixxat0:0"
effect = "babble"
id = 0x800
data = [1, 2, 3, 4, 5, 6, 7, 8, 9]
count = 3

[[fault]]
at = "1s"
node = "ixxat0:0"
effect = "babble"
id = 0x10
data = [256]
duration = "1ms"
)");
  EXPECT_EQ(e, (std::vector<std::string>{
                   "s.toml:7:1: fault[0].count: not a key of babble (known: at, effect, node, id, "
                   "ext, data, duration)",
                   "s.toml:1:1: fault[0].duration: missing (a string is required)",
                   "s.toml:5:6: fault[0].id: 2048 is outside 0..2047",
                   "s.toml:6:8: fault[0].data: must be an array of at most 8 bytes, e.g. [0x11, "
                   "0x22]",
                   "s.toml:14:9: fault[1].data: each element must be a byte (0..255)",
               }));
}

TEST(Scenario, RandomErrorsNeedABitErrorRateInRange) {
  EXPECT_EQ(scenario_errors("[[fault]]\nat = \"0s\"\nbus = \"can0\"\neffect = \"random_errors\"\n"),
            (std::vector<std::string>{
                "s.toml:1:1: fault[0].bit_error_rate: missing (a number is required)"}));
  EXPECT_EQ(scenario_errors("[[fault]]\nat = \"0s\"\nbus = \"can0\"\neffect = \"random_errors\"\n"
                            "bit_error_rate = 0.5\n"),
            (std::vector<std::string>{
                "s.toml:5:18: fault[0].bit_error_rate: must be above 0 and at most 0.1"}));
}

TEST(Scenario, ReadsTheKeysOfTheFaultsOnSimulatedNodesMessagesAndSignals) {
  auto s = parse_scenario(R"([[fault]]
at = "1s"
until = "2s"
bus = "can0"
message = "ENGINE_DATA"
effect = "checksum_error"
count = 3

[[fault]]
at = "1s"
bus = "can0"
signal = "ENGINE_DATA.alive"
effect = "counter_jump"
by = 5

[[fault]]
at = "1s"
until = "3s"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "signal_ramp"
to = 2500.5

[[fault]]
at = "1s"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "signal_invalid"
raw = 0xFFFF
)",
                          "s.toml");
  ASSERT_TRUE(s) << s.error().front();
  ASSERT_EQ(s->faults.size(), 4u);
  const FaultSpec& sum = s->faults[0];
  EXPECT_EQ(sum.effect, FaultEffect::checksum_error);
  EXPECT_EQ(sum.bus, "can0");
  EXPECT_EQ(sum.message, "ENGINE_DATA");
  EXPECT_EQ(sum.signal, "");
  EXPECT_EQ(sum.count, 3u);
  EXPECT_EQ(sum.until_ns, 2'000'000'000);
  EXPECT_EQ(s->faults[1].message, "ENGINE_DATA");
  EXPECT_EQ(s->faults[1].signal, "alive");
  EXPECT_EQ(s->faults[1].by, 5u);
  EXPECT_EQ(s->faults[2].value, 2500.5);
  EXPECT_EQ(s->faults[3].raw, 0xFFFFu);
  EXPECT_EQ(s->faults[3].value, std::nullopt);
}

TEST(Scenario, FaultsOnSignalsNeedMessageDotSignalAndTheirValues) {
  EXPECT_EQ(scenario_errors(R"([[fault]]
at = "0s"
bus = "can0"
signal = "speed"
effect = "signal_step"

[[fault]]
at = "0s"
bus = "can0"
signal = "A.b"
effect = "signal_ramp"
to = 1

[[fault]]
at = "0s"
bus = "can0"
signal = "A.b"
effect = "signal_invalid"
value = 1
raw = 1

[[fault]]
at = "0s"
bus = "can0"
message = "A"
effect = "counter_freeze"
)"),
            (std::vector<std::string>{
                "s.toml:4:10: fault[0].signal: \"speed\" is not MESSAGE.SIGNAL (e.g. "
                "\"ENGINE_DATA.ENGINE_SPEED\")",
                "s.toml:1:1: fault[0].value: missing (the physical value the signal takes)",
                "s.toml:7:1: fault[1].until: missing (the instant the ramp reaches its value)",
                "s.toml:14:1: fault[2]: needs either value (a physical value) or raw (the "
                "signal's bits), not both",
                "s.toml:25:1: fault[3].message: not a key of counter_freeze (known: at, effect, "
                "bus, signal, until)",
                "s.toml:22:1: fault[3].signal: missing (a string is required)",
            }));
}

// `fault list` and `fault clear` use the whole name: one that would not fit is refused.
TEST(Scenario, ANameLongerThan63BytesIsRefused) {
  const std::string fault = "\n[[fault]]\nat = \"0s\"\nbus = \"can0\"\neffect = \"bit_error\"\n";
  const std::string fits(63, 'n');
  auto ok = parse_scenario("[scenario]\nname = \"" + fits + "\"\n" + fault, "s.toml");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->name, fits);
  auto long_name = parse_scenario("[scenario]\nname = \"" + fits + "x\"\n" + fault, "s.toml");
  ASSERT_FALSE(long_name);
  EXPECT_EQ(long_name.error(),
            (std::vector<std::string>{"s.toml: scenario name \"" + fits +
                                      "x\": 64 bytes; at most 63 (the file name serves when "
                                      "[scenario] has no name)"}));
}

}  // namespace
}  // namespace canemu::daemon