// Faults of scenarios on simulated CAN nodes (docs/faults.md, "Simulated CAN nodes"), in
// stepped time on a 500 kbit/s bus: what each puts on the wire at which instant, which is what
// every receiver takes (each frame is acknowledged and received whole), and what is refused.
#include <gtest/gtest.h>

#include "can_ecu_world.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/restbus/signal_codec.hpp"

namespace canemu::daemon {
namespace {

// ENGINE and BRAKE (tests/data/restbus/engine_and_brake.toml, which says what they send).
std::string nodes() {
  auto text = read_text_file(CANEMU_SOURCE_DIR "/tests/data/restbus/engine_and_brake.toml");
  if (!text) {
    ADD_FAILURE() << text.error();
  }
  return text.value_or("");
}

constexpr uint32_t kEngine = 0x100;
constexpr uint32_t kBrake = 0x200;

// The scenario `faults` ([[fault]] tables) applied now; its errors, if any.
std::vector<std::string> apply(World& w, std::string_view faults) {
  auto s = parse_scenario(faults, "s.toml");
  if (!s) {
    return s.error();
  }
  auto applied = w.sim->scenarios().apply(*s, w.sim->scheduler().now());
  return applied ? std::vector<std::string>{} : applied.error();
}

std::vector<SimTime> every_10ms(int64_t first, int64_t last) {
  std::vector<SimTime> out;
  for (int64_t t = first; t <= last; t += 10) {
    out.push_back(ms(t));
  }
  return out;
}

// What receivers read of ENGINE_DATA's frames: speed (rpm), the alive counter, and whether the
// CRC checks.
std::vector<double> speeds(const World& w) {
  std::vector<double> out;
  for (const auto& p : w.payloads(kEngine)) {
    out.push_back(static_cast<double>(p[0] | (p[1] << 8)) * 0.25);
  }
  return out;
}
std::vector<int> alive(const World& w) {
  std::vector<int> out;
  for (const auto& p : w.payloads(kEngine)) {
    out.push_back(p[4] & 0x0F);
  }
  return out;
}
std::vector<bool> crc_ok(const World& w) {
  std::vector<bool> out;
  for (const auto& p : w.payloads(kEngine)) {
    out.push_back(restbus::checksum(ChecksumKind::crc8_sae_j1850, 0x12, p, 7) == p[7]);
  }
  return out;
}

TEST(RestbusFaults, AMessageTimeoutSkipsItsCycleInstantsUntilItEnds) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "25ms"
until = "55ms"
bus = "can0"
message = "ENGINE_DATA"
effect = "message_timeout"
)"),
            std::vector<std::string>{});
  w.run_until(ms(75) + SimDuration(1));
  // 30, 40 and 50 ms are missing; the cycle goes on on its grid; BRAKE does not notice.
  EXPECT_EQ(w.starts(kEngine), (std::vector<SimTime>{ms(0), ms(10), ms(20), ms(60), ms(70)}));
  EXPECT_EQ(w.starts(kBrake), every_10ms(5, 75));
  EXPECT_EQ(alive(w), (std::vector<int>{0, 1, 2, 3, 4}));  // it counts frames sent
  EXPECT_EQ(w.ecu("ENGINE").counters("ENGINE_DATA")->skipped, 3u);
  const auto st = w.sim->scenarios().status();
  ASSERT_EQ(st.size(), 1u);
  EXPECT_EQ(st[0].target, "can0/ENGINE_DATA");
  EXPECT_EQ(st[0].frames, ScenarioRunner::FaultStatus::Frames::can);
  EXPECT_EQ(st[0].match.id, kEngine);
  EXPECT_EQ(st[0].state, ScenarioRunner::FaultStatus::State::done);
}

TEST(RestbusFaults, AFrozenCounterRepeatsItsValueAndCountsOnAfterwards) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "15ms"
until = "45ms"
bus = "can0"
signal = "ENGINE_DATA.alive"
effect = "counter_freeze"
)"),
            std::vector<std::string>{});
  w.run_until(ms(60) + SimDuration(1));
  EXPECT_EQ(w.starts(kEngine), every_10ms(0, 60));
  // Frozen from 15 ms at the next frame's value; the frame at 50 ms still carries it (the
  // freeze ended at 45), the next one counts on.
  EXPECT_EQ(alive(w), (std::vector<int>{0, 1, 2, 2, 2, 2, 3}));
  EXPECT_EQ(crc_ok(w), std::vector<bool>(7, true));  // over the frozen value
}

TEST(RestbusFaults, ACounterJumpSkipsValuesOnceAndWrapsAtItsWidth) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "25ms"
bus = "can0"
signal = "ENGINE_DATA.alive"
effect = "counter_jump"
by = 14
)"),
            std::vector<std::string>{});
  w.run_until(ms(50) + SimDuration(1));
  // 0, 1, 2, then 3 + 14 = 17, which is 1 in four bits; then it counts from there.
  EXPECT_EQ(alive(w), (std::vector<int>{0, 1, 2, 1, 2, 3}));
  EXPECT_EQ(crc_ok(w), std::vector<bool>(6, true));
}

TEST(RestbusFaults, AChecksumErrorMakesCountFramesCarryAWrongChecksum) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "15ms"
bus = "can0"
message = "ENGINE_DATA"
effect = "checksum_error"
count = 2
)"),
            std::vector<std::string>{});
  w.run_until(ms(50) + SimDuration(1));
  EXPECT_EQ(w.starts(kEngine), every_10ms(0, 50));  // the frames go as before
  EXPECT_EQ(crc_ok(w), (std::vector<bool>{true, true, false, false, true, true}));
  // Wrong in every bit: the frames at 20 and 30 ms carry the inverted CRC.
  const auto p = w.payloads(kEngine);
  EXPECT_EQ(p[2][7],
            static_cast<uint8_t>(~restbus::checksum(ChecksumKind::crc8_sae_j1850, 0x12, p[2], 7)));
  const auto st = w.sim->scenarios().status();
  ASSERT_EQ(st.size(), 1u);
  EXPECT_EQ(st[0].hits, 2u);
  EXPECT_EQ(st[0].state, ScenarioRunner::FaultStatus::State::done);
}

TEST(RestbusFaults, AnInvalidValueGoesOutBeyondTheRangeAndTheValueBeforeComesBack) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "15ms"
until = "35ms"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "signal_invalid"
value = 9000

[[fault]]
at = "25ms"
bus = "can0"
signal = "ENGINE_DATA.temp"
effect = "signal_invalid"
raw = 0xFF
)"),
            std::vector<std::string>{});
  w.run_until(ms(40) + SimDuration(1));
  // 9000 rpm is above the DBC's 8000, and goes out all the same: that is the fault.
  EXPECT_EQ(speeds(w), (std::vector<double>{1000, 1000, 9000, 9000, 1000}));
  std::vector<int> temps;
  for (const auto& p : w.payloads(kEngine)) {
    temps.push_back(p[2]);
  }
  EXPECT_EQ(temps, (std::vector<int>{130, 130, 130, 0xFF, 0xFF}));  // 90 C is raw 130
  EXPECT_EQ(crc_ok(w), std::vector<bool>(5, true));
}

TEST(RestbusFaults, AStepChangesTheNextFrameAndAnOnChangeMessageGoesAtOnce) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "25ms"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "signal_step"
value = 3000

[[fault]]
at = "32ms"
bus = "can0"
signal = "ENGINE_EVENT.state"
effect = "signal_step"
value = 7
)"),
            std::vector<std::string>{});
  w.run_until(ms(40) + SimDuration(1));
  EXPECT_EQ(speeds(w), (std::vector<double>{1000, 1000, 1000, 3000, 3000}));
  EXPECT_EQ(*w.ecu("ENGINE").get_signal("ENGINE_DATA", "speed"), 3000.0);
  EXPECT_EQ(w.starts(0x101), std::vector<SimTime>{ms(32)});
  EXPECT_EQ(w.payloads(0x101), std::vector<std::vector<uint8_t>>{{7}});
}

TEST(RestbusFaults, ARampCarriesTheValueOnTheLineAtEachFramesInstant) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "20ms"
until = "60ms"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "signal_ramp"
to = 2000
)"),
            std::vector<std::string>{});
  w.run_until(ms(35));
  EXPECT_EQ(*w.ecu("ENGINE").get_signal("ENGINE_DATA", "speed"), 1375.0);  // 15 of 40 ms
  w.run_until(ms(70) + SimDuration(1));
  EXPECT_EQ(speeds(w), (std::vector<double>{1000, 1000, 1000, 1250, 1500, 1750, 2000, 2000}));
  EXPECT_EQ(*w.ecu("ENGINE").get_signal("ENGINE_DATA", "speed"), 2000.0);
}

TEST(RestbusFaults, ASimulatedNodeGoesBusOffOrIsUnpluggedByItsName) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "25ms"
node = "ENGINE"
effect = "bus_off"

[[fault]]
at = "12ms"
until = "32ms"
node = "can0/BRAKE"
effect = "node_off"
)"),
            std::vector<std::string>{});
  w.run_until(ms(60) + SimDuration(1));
  // Bus-off: ENGINE stops for good (it is not powered again); nobody else notices.
  EXPECT_EQ(w.starts(kEngine), (std::vector<SimTime>{ms(0), ms(10), ms(20)}));
  EXPECT_TRUE(w.ecu("ENGINE").node().controller().confinement().bus_off());
  // Unplugged, BRAKE cannot send its frames of 15 and 25 ms: back at 32 ms, the one its
  // controller held goes at once and the one that waited in the node right after it (68 bit
  // times of 2 us: the frame with its stuff bits and the intermission); then its cycle goes on.
  EXPECT_EQ(w.starts(kBrake), (std::vector<SimTime>{ms(5), ms(32), ms(32) + SimDuration(136'000),
                                                    ms(35), ms(45), ms(55)}));
}

TEST(RestbusFaults, AMessageTimeoutDropsTheFrameWaitingInTheNodeAndCountsIt) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "12ms"
until = "40ms"
node = "BRAKE"
effect = "node_off"

[[fault]]
at = "28ms"
until = "33ms"
bus = "can0"
message = "BRAKE_DATA"
effect = "message_timeout"
)"),
            std::vector<std::string>{});
  w.run_until(ms(50) + SimDuration(1));
  // Unplugged, the frame of 15 ms stays in the controller and the one of 25 ms waits in the
  // node until the timeout drops it; the one of 35 ms waits again. Back at 40 ms, both go, after
  // ENGINE_DATA's frame of 40 ms (lower identifier: 244 us with the intermission), back to back.
  EXPECT_EQ(w.starts(kBrake), (std::vector<SimTime>{ms(5), ms(40) + SimDuration(244'000),
                                                    ms(40) + SimDuration(380'000), ms(45)}));
  const auto c = *w.ecu("BRAKE").counters("BRAKE_DATA");
  EXPECT_EQ(c.dropped, 1u);
  EXPECT_EQ(c.skipped, 0u);
  EXPECT_EQ(c.queued, 5u);  // 5, 15, 25, 35, 45 ms
  EXPECT_EQ(c.sent, 4u);
}

TEST(RestbusFaults, AreRefusedWithTheReasonAndNothingApplies) {
  World w(nodes());
  EXPECT_EQ(
      apply(w, R"([[fault]]
at = "0s"
bus = "can0"
message = "ENGINE_DATA"
effect = "message_timeout"

[[fault]]
at = "0s"
bus = "can0"
message = "NO_SUCH"
effect = "message_timeout"

[[fault]]
at = "0s"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "counter_freeze"

[[fault]]
at = "0s"
bus = "can0"
signal = "ENGINE_DATA.alive"
effect = "counter_jump"
by = 16

[[fault]]
at = "0s"
bus = "can0"
message = "BRAKE_DATA"
effect = "checksum_error"

[[fault]]
at = "0s"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "signal_step"
value = 8000.25

[[fault]]
at = "0s"
until = "1s"
bus = "can0"
signal = "ENGINE_EVENT.state"
effect = "signal_ramp"
to = 3

[[fault]]
at = "0s"
bus = "can0"
signal = "ENGINE_DATA.speed"
effect = "signal_invalid"
raw = 0x10000

[[fault]]
at = "0s"
bus = "can0"
signal = "ENGINE_DATA.crc"
effect = "signal_invalid"
value = 1

[[fault]]
at = "0s"
bus = "can0"
signal = "ENGINE_DATA.nothing"
effect = "signal_step"
value = 1
)"),
      (std::vector<std::string>{
          "s.toml:7: message_timeout: no simulated CAN node sends a message named \"NO_SUCH\" on "
          "can0",
          "s.toml:13: counter_freeze: ENGINE_DATA.speed is not a counter",
          "s.toml:19: counter_jump: by = 16 is not below 2^4: the 4-bit counter would skip a "
          "whole turn or more",
          "s.toml:26: checksum_error: message BRAKE_DATA has no checksum signal",
          "s.toml:32: signal_step: 8000.25 is outside the range of ENGINE_DATA.speed: 0..8000 rpm",
          "s.toml:39: signal_ramp: message ENGINE_EVENT is sent on change only: a ramp needs a "
          "cyclic message",
          "s.toml:47: signal_invalid: raw value 65536 does not fit the 16 bits of "
          "ENGINE_DATA.speed",
          "s.toml:54: signal_invalid: ENGINE_DATA.crc is a checksum: it is computed as each frame "
          "goes out",
          "s.toml:61: signal_step: message ENGINE_DATA has no signal named \"nothing\"",
      }));
  EXPECT_TRUE(w.sim->scenarios().status().empty());
  w.run_until(ms(20) + SimDuration(1));
  EXPECT_EQ(w.starts(kEngine), every_10ms(0, 20));  // the valid first fault was not applied
}

TEST(RestbusFaults, EndWhenTheirNodeIsRemovedAndANewNodeOfTheNameInheritsNone) {
  World w(nodes());
  EXPECT_EQ(apply(w, R"([[fault]]
at = "25ms"
until = "1s"
bus = "can0"
message = "ENGINE_DATA"
effect = "message_timeout"
)"),
            std::vector<std::string>{});
  w.run_until(ms(30));
  ASSERT_TRUE(w.sim->remove_can_node("ENGINE"));
  EXPECT_EQ(w.sim->scenarios().status()[0].state, ScenarioRunner::FaultStatus::State::cleared);
  // A new ENGINE loaded at 40 ms sends from then on, every 10 ms.
  w.run_until(ms(40));
  const std::string_view again = R"(
[[can_node]]
name = "ENGINE"
bus = "can0"

[[can_node.message]]
name = "ENGINE_DATA"
id = 0x100
length = 1
cycle = "10ms"
)";
  ASSERT_TRUE(w.sim->load_can_nodes(again, "again.toml"));
  w.run_until(ms(60) + SimDuration(1));
  EXPECT_EQ(w.starts(kEngine),
            (std::vector<SimTime>{ms(0), ms(10), ms(20), ms(40), ms(50), ms(60)}));
}

}  // namespace
}  // namespace canemu::daemon
