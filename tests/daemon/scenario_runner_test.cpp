// The scenario runner on the world of the default configuration: names resolved against the
// running simulation, all or nothing; every effect with its consequence on the wire; the fault
// log with simulated times.
#include "canemu/daemon/world/scenario_runner.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

namespace canemu::daemon {
namespace {

using namespace canemu::model;

// The default configuration (can0 and can1 at 500 kbit/s, ixxat0 with a controller on each,
// both started at 500 kbit/s as a VCI application would) and an ephemeral SJA1000 "tester" on
// can0 that always has a frame to send.
struct World {
  std::unique_ptr<Simulation> sim;
  HostedNode* tester = nullptr;
  Simulation::DeviceLease lease;
  World() {
    sim = std::move(*Simulation::build(*load_default_config()));
    for (uint32_t k = 0; k < 2; ++k) {
      auto line = sim->devices().vci_line("ixxat0", k);
      ixxat::LineInit init;
      init.op_mode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED;
      init.btr0 = 0x00;
      init.btr1 = 0x1C;
      EXPECT_EQ(line->open_control(), VCI_OK);
      EXPECT_EQ(line->init_line(init), VCI_OK);
      EXPECT_EQ(line->start_line(), VCI_OK);
    }
    tester = &sim->spare_node(0);
    HostedNodeSettings s;
    s.btr0 = 0x00;
    s.btr1 = 0x1C;
    tester->start(s, nullptr, [] { return TxFrame{*Frame::classic(0x123, {}), false, false}; });
    lease = sim->add_ephemeral("tester", 0, *tester, 0);
  }
  void apply(std::string_view text) {
    auto s = parse_scenario(text, "s.toml");
    ASSERT_TRUE(s) << s.error().front();
    auto applied = sim->scenarios().apply(*s, sim->scheduler().now());
    ASSERT_TRUE(applied) << applied.error().front();
  }
  void run_until(int64_t ns) { sim->scheduler().run_until(SimTime::from_ns(ns)); }
  const FaultConfinement& fc() { return tester->controller().confinement(); }
  const NodeStats& stats() { return sim->bus(0).stats(tester->node()); }
};

TEST(ScenarioEffects, ThirtyTwoBitErrorsTakeTheSenderFromZeroToBusOff) {
  World w;
  w.apply(R"([[fault]]
at = "0s"
bus = "can0"
match = { from = "tester" }
effect = "bit_error"
count = 32
)");
  w.run_until(100'000'000);
  EXPECT_EQ(w.stats().errors_as_transmitter.bit, 32u);
  EXPECT_EQ(w.fc().tec(), kBusOffLimit);
  EXPECT_TRUE(w.fc().bus_off());
  EXPECT_EQ(w.stats().frames_sent, 0u);
}

TEST(ScenarioEffects, NobodyAcknowledgingLeavesALoneSenderErrorPassiveAt128) {
  World w;
  w.apply(R"([[fault]]
at = "0s"
bus = "can0"
effect = "ack_suppress"
duration = "1s"
)");
  w.run_until(500'000'000);
  EXPECT_EQ(w.fc().tec(), 128);
  EXPECT_EQ(w.fc().state(), ErrorState::passive);
  EXPECT_EQ(w.stats().frames_sent, 0u);
  w.run_until(1'100'000'000);  // acknowledged again: every success takes one off
  EXPECT_GT(w.stats().frames_sent, 128u);
  EXPECT_EQ(w.fc().tec(), 0);
  EXPECT_EQ(w.fc().state(), ErrorState::active);
}

TEST(ScenarioEffects, AckErrorsHitOnlyTheMatchingFrames) {
  World w;
  w.apply(R"([[fault]]
at = "0s"
bus = "can0"
match = { id = 0x7FF }
effect = "ack_error"
)");
  w.run_until(10'000'000);  // the tester's 0x123 frames do not match
  EXPECT_EQ(w.fc().tec(), 0);
  EXPECT_GT(w.stats().frames_sent, 0u);

  World hit;
  hit.apply(R"([[fault]]
at = "0s"
bus = "can0"
match = { id = 0x123 }
effect = "ack_error"
count = 3
)");
  hit.run_until(1'000'000);  // the first three attempts go unacknowledged: TEC 3 x 8
  EXPECT_EQ(hit.stats().errors_as_transmitter.ack, 3u);
  EXPECT_EQ(hit.fc().tec(), 24 - hit.stats().frames_sent);
  hit.run_until(10'000'000);  // then acknowledged, one off per success
  EXPECT_EQ(hit.stats().errors_as_transmitter.ack, 3u);
  EXPECT_EQ(hit.fc().tec(), 0);
}

TEST(ScenarioEffects, UnpluggingTheOnlyOtherNodeLeavesTheSenderUnacknowledged) {
  World w;
  w.apply(R"([[fault]]
at = "0s"
until = "100ms"
node = "ixxat0:0"
effect = "node_off"
)");
  w.run_until(50'000'000);
  EXPECT_EQ(w.fc().tec(), 128);
  EXPECT_EQ(w.sim->bus(0).stats(0).frames_received, 0u);
  w.run_until(200'000'000);  // plugged in again at 100 ms
  EXPECT_GT(w.sim->bus(0).stats(0).frames_received, 0u);
  EXPECT_LT(w.fc().tec(), 128);
}

TEST(ScenarioEffects, CountersAndBusOffAreSetAtTheirInstant) {
  World w;
  w.apply(R"([[fault]]
at = "1ms"
node = "ixxat0:1"
effect = "error_counters"
tec = 100
rec = 5

[[fault]]
at = "2ms"
node = "tester"
effect = "bus_off"
)");
  auto s = ipc::make_message<ipc::StatusReply>();
  w.run_until(999'999);
  fill_status(*w.sim, s);
  EXPECT_EQ(s.nodes[1].tec, 0);
  w.run_until(1'000'000);
  fill_status(*w.sim, s);
  EXPECT_EQ(ipc::name_of(s.nodes[1].name), "ixxat0:1");
  EXPECT_EQ(s.nodes[1].tec, 100);
  EXPECT_EQ(s.nodes[1].rec, 5);
  EXPECT_EQ(s.nodes[1].state, static_cast<uint8_t>(ErrorState::warning));
  EXPECT_FALSE(w.fc().bus_off());
  w.run_until(2'000'000);
  EXPECT_TRUE(w.fc().bus_off());
}

TEST(ScenarioEffects, AnOscillatorFarOffStopsTheNodeFromBeingUnderstood) {
  World w;
  w.apply(R"([[fault]]
at = "0s"
until = "20ms"
node = "tester"
effect = "oscillator"
ppm = 30000
)");
  w.run_until(20'000'000);
  EXPECT_EQ(w.sim->bus(0).stats(0).frames_received, 0u);
  EXPECT_GT(w.stats().errors_as_transmitter.total(), 0u);
  const uint64_t received = w.sim->bus(0).stats(0).frames_received;
  w.run_until(40'000'000);
  EXPECT_GT(w.sim->bus(0).stats(0).frames_received, received);
}

TEST(ScenarioEffects, AStuckDominantBusMakesEveryoneSeeErrors) {
  World w;
  w.run_until(1'000'000);
  const uint64_t before = w.sim->bus(0).error_frames_on_bus();
  w.apply(R"([[fault]]
at = "1ms"
bus = "can0"
effect = "stuck_dominant"
duration = "1ms"
)");
  w.run_until(3'000'000);
  EXPECT_GT(w.sim->bus(0).error_frames_on_bus(), before);
  EXPECT_GT(w.stats().errors_as_transmitter.total() + w.stats().errors_as_receiver.total(), 0u);
}

// Random bit errors: each bit hit with the given rate, the first hit of a frame a bit error
// there. At 1e-3 and 50-bit frames about 5 % of the tester's frames are hit.
TEST(ScenarioEffects, RandomErrorsHitFramesAtTheirBitErrorRate) {
  auto run = [] {
    World w;
    w.apply(R"([[fault]]
at = "0s"
until = "200ms"
bus = "can0"
effect = "random_errors"
bit_error_rate = 0.001
)");
    w.run_until(200'000'000);
    return std::make_pair(w.stats().errors_as_transmitter.bit, w.stats().frames_sent);
  };
  const auto [errors, sent] = run();
  EXPECT_EQ(run(), std::make_pair(errors, sent));  // the same seed, the same hits
  const double share = static_cast<double>(errors) / static_cast<double>(errors + sent);
  EXPECT_GT(share, 0.03);
  EXPECT_LT(share, 0.07);
}

TEST(ScenarioEffects, UnknownNamesRejectTheWholeScenario) {
  World w;
  auto s = parse_scenario(R"([[fault]]
at = "0s"
bus = "can0"
effect = "ack_suppress"
duration = "1s"

[[fault]]
at = "0s"
bus = "can9"
effect = "bit_error"

[[fault]]
at = "0s"
node = "ghost:0"
effect = "bus_off"

[[fault]]
at = "0s"
bus = "can1"
match = { from = "tester" }
effect = "crc_error"
)",
                          "s.toml");
  ASSERT_TRUE(s);
  auto applied = w.sim->scenarios().apply(*s, SimTime{});
  ASSERT_FALSE(applied);
  EXPECT_EQ(applied.error(),
            (std::vector<std::string>{
                "s.toml:7: bit_error: no bus named \"can9\"",
                "s.toml:12: bus_off: no node named \"ghost:0\" (configured nodes are DEVICE:N; "
                "simulated CAN nodes NAME, or BUS/NAME where several buses have that NAME)",
                "s.toml:17: crc_error: node tester is not on bus can1",
            }));
  w.run_until(500'000'000);  // the valid first fault was not applied either
  EXPECT_EQ(w.fc().tec(), 0);
}

// The shipped examples run as they are against the embedded default configuration.
TEST(ScenarioExamples, EveryShippedExampleAppliesToTheDefaultConfiguration) {
  int seen = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(CANEMU_SOURCE_DIR "/config/faults")) {
    if (entry.path().extension() != ".toml") {
      continue;
    }
    ++seen;
    auto scenario = load_scenario_file(entry.path().string());
    ASSERT_TRUE(scenario) << scenario.error().front();
    auto sim = std::move(*Simulation::build(*load_default_config()));
    auto applied = sim->scenarios().apply(*scenario, model::SimTime{});
    EXPECT_TRUE(applied) << entry.path() << ": " << applied.error().front();
  }
  EXPECT_GE(seen, 6);
}

// The log tells a scenario's life with simulated times: applied, a frame fault's first hit and
// the hit that completes its count, a bus effect firing and ending, the clearing.
TEST(ScenarioLog, TellsAppliedFirstHitDoneWindowOverAndCleared) {
  World w;
  log::Capture capture;
  const std::vector<std::string>& log = capture.lines();
  w.apply(R"([scenario]
name = "life"

[[fault]]
at = "1ms"
bus = "can0"
match = { from = "tester" }
effect = "stuff_error"
count = 2

[[fault]]
at = "0s"
until = "2ms"
bus = "can0"
match = { id = 0x7FF, mask = 0x7FF }
effect = "crc_error"
)");
  w.run_until(3'000'000);
  ASSERT_EQ(log.size(), 4u);
  EXPECT_EQ(
      log[0],
      "<6>canemud: fault: t=0.000000000 s: scenario \"life\" (s.toml) applied: 2 faults, seed 1");
  // The tester sends 0x123 (no data) back to back: 48 bit times (96 us) a frame with one stuff
  // bit and intermission, so the first frame from 1 ms on starts at 1.056 ms; its repetition
  // starts 35 bit times later (the frame up to the error, the error flags, their delimiter and
  // intermission), and is hit too.
  EXPECT_EQ(log[1],
            "<6>canemud: fault: t=0.001056000 s: scenario \"life\" line 4: stuff_error: first hit, "
            "frame 123 from "
            "tester:0");
  EXPECT_EQ(
      log[2],
      "<6>canemud: fault: t=0.001126000 s: scenario \"life\" line 4: stuff_error: done, 2 hits");
  EXPECT_EQ(log[3],
            "<6>canemud: fault: t=0.002000000 s: scenario \"life\" line 11: crc_error: window "
            "over, 0 hits");
  EXPECT_EQ(w.sim->scenarios().clear("life"), 1u);
  EXPECT_EQ(log.back(), "<6>canemud: fault: t=0.003000000 s: scenario \"life\" cleared");
}

// Faults that name an ephemeral device end when it goes; its node comes back plugged in and on
// its nominal clock for the next device, which no fault of the old one touches.
TEST(ScenarioEffects, FaultsOfADeviceThatGoesEndWithIt) {
  World w;
  log::Capture capture;
  const std::vector<std::string>& log = capture.lines();
  w.apply(R"([[fault]]
at = "0s"
until = "1s"
node = "tester"
effect = "node_off"

[[fault]]
at = "0s"
node = "tester:0"
effect = "oscillator"
ppm = 100000

[[fault]]
at = "0s"
bus = "can0"
match = { from = "tester" }
effect = "bit_error"

[[fault]]
at = "500ms"
node = "tester"
effect = "bus_off"
)");
  w.run_until(1'000'000);
  model::HostedNode& node = *w.tester;
  EXPECT_FALSE(w.sim->bus(0).connected(node.node()));
  node.stop();
  w.lease = {};  // the device goes
  EXPECT_TRUE(w.sim->bus(0).connected(node.node()));
  using State = ScenarioRunner::FaultStatus::State;
  std::vector<State> states;
  for (const ScenarioRunner::FaultStatus& f : w.sim->scenarios().status()) {
    states.push_back(f.state);
  }
  // The oscillator offset had fired (a one-time effect, done); the others stop.
  EXPECT_EQ(states,
            (std::vector<State>{State::cleared, State::done, State::cleared, State::cleared}));
  EXPECT_EQ(w.sim->bus(0).stats(node.node()).errors_as_transmitter.total(), 0u);
  ASSERT_GE(log.size(), 4u);
  EXPECT_EQ(log[log.size() - 4],
            "<6>canemud: fault: t=0.001000000 s: scenario \"s.toml\" line 1: node_off: ends, "
            "device tester is gone");
  // The same node for a new device: it talks with ixxat0:0, nobody breaks its frames, and the
  // bus_off due at 500 ms does not come.
  ASSERT_EQ(&w.sim->spare_node(0), &node);
  model::HostedNodeSettings s;
  s.btr0 = 0x00;
  s.btr1 = 0x1C;
  node.start(s, nullptr, [] {
    return model::TxFrame{*model::Frame::classic(0x100, {}), false, false};
  });
  w.lease = w.sim->add_ephemeral("next", 0, node, 0);
  w.run_until(600'000'000);
  EXPECT_GT(w.stats().frames_sent, 1000u);
  EXPECT_EQ(w.stats().errors_as_transmitter.total(), 0u);
  EXPECT_EQ(w.fc().state(), model::ErrorState::active);
}

// A user has at most kMaxRulesPerUser frame rules in force, over all its scenarios and buses;
// the configuration and other users are not counted against it.
TEST(ScenarioOwnership, AUserHasAtMost256FrameRules) {
  World w;
  const auto rules = [](const char* name, std::size_t n) {
    std::string text = std::string("[scenario]\nname = \"") + name + "\"\n";
    for (std::size_t k = 0; k < n; ++k) {
      text += "\n[[fault]]\nat = \"0s\"\nbus = \"can1\"\neffect = \"crc_error\"\n";
    }
    return parse_scenario(text, std::string(name) + ".toml");
  };
  const SimTime now = w.sim->scheduler().now();
  auto two_hundred = rules("a", 200);
  auto fifty_six = rules("b", 56);
  auto one = rules("c", 1);
  ASSERT_TRUE(two_hundred && fifty_six && one);
  ASSERT_TRUE(w.sim->scenarios().apply(*two_hundred, now, 1000));
  ASSERT_TRUE(w.sim->scenarios().apply(*fifty_six, now, 1000));  // 256: the share
  auto over = w.sim->scenarios().apply(*one, now, 1000);
  ASSERT_FALSE(over);
  EXPECT_EQ(over.error(), std::vector<std::string>{"c.toml: uid 1000 would have 257 frame fault "
                                                   "rules in force; one user may have 256"});
  EXPECT_TRUE(w.sim->scenarios().apply(*one, now, 1001));
  EXPECT_TRUE(w.sim->scenarios().apply(*two_hundred, now));  // the configuration's
  EXPECT_EQ(w.sim->scenarios().clear("b", [](const auto& o) { return o && *o == 1000; }), 1u);
  EXPECT_TRUE(w.sim->scenarios().apply(*one, now, 1000));  // cleared rules are given back
}

}  // namespace
}  // namespace canemu::daemon

namespace canemu::daemon {
namespace {

constexpr std::string_view kOneRule = R"([scenario]
name = "cycle"

[[fault]]
at = "0s"
bus = "can0"
match = { id = 0x7FF, mask = 0x7FF }
effect = "crc_error"
)";

// Loading and clearing again and again leaves nothing behind: the cleared rules leave their
// bus's plan, at most kKeptCleared cleared scenarios stay listed, and the counts of a cleared
// fault are kept in its listing.
TEST(ScenarioBounds, TenThousandLoadAndClearCyclesLeaveNothingBehind) {
  World w;
  auto s = parse_scenario(kOneRule, "s.toml");
  ASSERT_TRUE(s);
  for (int k = 0; k < 10'000; ++k) {
    ASSERT_TRUE(w.sim->scenarios().apply(*s, w.sim->scheduler().now()));
    ASSERT_EQ(w.sim->scenarios().clear("cycle"), 1u);
  }
  const auto listed = w.sim->scenarios().status();
  EXPECT_EQ(listed.size(), ScenarioRunner::kKeptCleared);
  for (const auto& f : listed) {
    EXPECT_EQ(f.state, ScenarioRunner::FaultStatus::State::cleared);
  }
  // Still working: a new scenario's rule hits as before.
  w.apply(R"([scenario]
name = "after"

[[fault]]
at = "0s"
bus = "can0"
match = { from = "tester" }
effect = "stuff_error"
count = 3
)");
  w.run_until(2'000'000);
  const auto after = w.sim->scenarios().status();
  ASSERT_EQ(after.size(), ScenarioRunner::kKeptCleared + 1);
  EXPECT_EQ(after.back().hits, 3u);
  EXPECT_EQ(w.sim->scenarios().clear("after"), 1u);
  const auto kept = w.sim->scenarios().status();
  EXPECT_EQ(kept.size(), ScenarioRunner::kKeptCleared);
  EXPECT_EQ(kept.back().scenario, "after");
  EXPECT_EQ(kept.back().hits, 3u);  // counted when it left the plan
  EXPECT_EQ(kept.back().state, ScenarioRunner::FaultStatus::State::done);
}

// The fault list's generation (paged readers start over when it changes) moves when cleared
// scenarios are forgotten, the faults after them moving down, and not when a load adds faults
// at the end or a clear keeps what it cleared.
TEST(ScenarioBounds, TheGenerationChangesWhenFaultsMoveOnly) {
  World w;
  auto s = parse_scenario(kOneRule, "s.toml");
  ASSERT_TRUE(s);
  ScenarioRunner& r = w.sim->scenarios();
  const uint32_t start = r.generation();
  for (std::size_t k = 0; k < ScenarioRunner::kKeptCleared; ++k) {
    ASSERT_TRUE(r.apply(*s, w.sim->scheduler().now()));
    ASSERT_EQ(r.clear("cycle"), 1u);
  }
  EXPECT_EQ(r.generation(), start);  // every cleared one kept
  ASSERT_TRUE(r.apply(*s, w.sim->scheduler().now()));
  EXPECT_EQ(r.generation(), start);  // added at the end
  ASSERT_EQ(r.clear("cycle"), 1u);   // the oldest cleared is forgotten
  EXPECT_NE(r.generation(), start);
  EXPECT_EQ(r.status().size(), ScenarioRunner::kKeptCleared);
}

TEST(ScenarioBounds, ScenariosInForceAndRulesPerBusAreBounded) {
  World w;
  auto s = parse_scenario(kOneRule, "s.toml");
  ASSERT_TRUE(s);
  for (std::size_t k = 0; k < ScenarioRunner::kMaxScenarios; ++k) {
    ASSERT_TRUE(w.sim->scenarios().apply(*s, w.sim->scheduler().now()));
  }
  auto refused = w.sim->scenarios().apply(*s, w.sim->scheduler().now());
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error(),
            std::vector<std::string>{"s.toml: 64 scenarios are in force already, the most "
                                     "canemud holds; clear one first (canemu fault clear NAME)"});
  EXPECT_EQ(w.sim->scenarios().clear(""), ScenarioRunner::kMaxScenarios);
  // One scenario with more rules on a bus than the bound: refused whole.
  std::string many = "[scenario]\nname = \"many\"\n";
  for (std::size_t k = 0; k <= ScenarioRunner::kMaxRulesPerBus; ++k) {
    many += "\n[[fault]]\nat = \"0s\"\nbus = \"can1\"\neffect = \"crc_error\"\n";
  }
  auto big = parse_scenario(many, "many.toml");
  ASSERT_TRUE(big);
  auto too_many = w.sim->scenarios().apply(*big, w.sim->scheduler().now());
  ASSERT_FALSE(too_many);
  EXPECT_EQ(too_many.error(),
            std::vector<std::string>{"many.toml: bus can1 would have 1025 frame fault rules; at "
                                     "most 1024 are in force on a bus"});
}

// A scenario belongs to the user who loaded it (or to the configuration): a clear that may only
// touch one user's scenarios leaves the others in force and counts them; a user has at most
// kMaxScenariosPerUser in force, others still may load.
TEST(ScenarioOwnership, AUserClearsItsOwnAndHasItsShare) {
  World w;
  auto s = parse_scenario(kOneRule, "s.toml");
  ASSERT_TRUE(s);
  const SimTime now = w.sim->scheduler().now();
  ASSERT_TRUE(w.sim->scenarios().apply(*s, now, 1000));
  ASSERT_TRUE(w.sim->scenarios().apply(*s, now, 1001));
  ASSERT_TRUE(w.sim->scenarios().apply(*s, now));  // the configuration's
  const auto only_1000 = [](const ScenarioRunner::Owner& o) { return o && *o == 1000; };
  std::size_t refused = 0;
  EXPECT_EQ(w.sim->scenarios().clear("cycle", only_1000, &refused), 1u);
  EXPECT_EQ(refused, 2u);
  refused = 0;
  EXPECT_EQ(w.sim->scenarios().clear("", only_1000, &refused), 0u);
  EXPECT_EQ(refused, 2u);
  const auto listed = w.sim->scenarios().status();
  ASSERT_EQ(listed.size(), 3u);
  EXPECT_EQ(listed[0].state, ScenarioRunner::FaultStatus::State::cleared);
  EXPECT_NE(listed[1].state, ScenarioRunner::FaultStatus::State::cleared);
  EXPECT_NE(listed[2].state, ScenarioRunner::FaultStatus::State::cleared);

  for (std::size_t k = 1; k < ScenarioRunner::kMaxScenariosPerUser; ++k) {
    ASSERT_TRUE(w.sim->scenarios().apply(*s, now, 1001));
  }
  auto over = w.sim->scenarios().apply(*s, now, 1001);
  ASSERT_FALSE(over);
  EXPECT_EQ(over.error(),
            std::vector<std::string>{"s.toml: uid 1001 has 16 scenarios in force, the most one "
                                     "user may; clear one first (canemu fault clear NAME)"});
  EXPECT_TRUE(w.sim->scenarios().apply(*s, now, 1000));
  EXPECT_EQ(w.sim->scenarios().clear(""), 18u);  // no limit given: every scenario
}

}  // namespace
}  // namespace canemu::daemon
