// Simulated CAN nodes ([[can_node]]) on a bus in stepped time: the exact instants their frames
// are queued and go on the wire, their bytes, counters, checksums, send kinds, arbitration
// between two nodes, and bus-off.
#include "canemu/daemon/restbus/can_ecu.hpp"

#include <gtest/gtest.h>

#include "can_ecu_world.hpp"
#include "canemu/daemon/restbus/signal_codec.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace canemu::daemon {
namespace {

using namespace canemu::model;

constexpr std::string_view kMotor = R"(
[[can_node]]
name = "MOTOR"
bus = "can0"

[[can_node.message]]
name = "MOTOR_STATUS"
id = 0x190
length = 8
cycle = "10ms"
delay = "5ms"

[[can_node.message.signal]]
name = "torque"
start = 0
length = 8
byte_order = "little_endian"
signed = true
scale = 0.5
initial = -2.0

[[can_node.message.signal]]
name = "speed"
start = 8
length = 16
byte_order = "little_endian"
scale = 0.001
minimum = 0.0
maximum = 65.535
initial = 1.234
unit = "kph"

[[can_node.message.signal]]
name = "angle"
start = 39
length = 12
byte_order = "big_endian"
signed = true
initial = -3

[[can_node.message.signal]]
name = "temperature"
start = 48
length = 8
byte_order = "little_endian"
offset = -40
initial = 20
)";

TEST(CanEcu, QueuesTheFirstFrameAtItsDelayThenEveryCycleToTheNanosecond) {
  World w(kMotor);
  w.run_until(ms(95) + SimDuration(1'000'000));
  std::vector<SimTime> expected;
  for (int k = 0; k < 10; ++k) {
    expected.push_back(ms(5 + 10 * k));
  }
  // The bus is idle at each instant: the frame starts on the wire as it is queued.
  EXPECT_EQ(w.starts(0x190), expected);
  const auto c = *w.ecu("MOTOR").counters("MOTOR_STATUS");
  EXPECT_EQ(c.queued, 10u);
  EXPECT_EQ(c.sent, 10u);
  EXPECT_EQ(c.replaced, 0u);
  EXPECT_EQ(w.ecu("MOTOR").frames_sent(), 10u);
  EXPECT_EQ(c.last_queued, ms(95));
}

TEST(CanEcu, EncodesLittleAndBigEndianSignedScaledAndOffsetSignals) {
  World w(kMotor);
  w.run_until(ms(6));
  // torque -2 / 0.5 = -4: 0xFC; speed 1234: D2 04; angle -3 in 12 bits from bit 39 (Motorola):
  // FF D0; temperature 20 + 40 = 60: 3C.
  const std::vector<uint8_t> first{0xFC, 0xD2, 0x04, 0x00, 0xFF, 0xD0, 0x3C, 0x00};
  ASSERT_EQ(w.payloads(0x190).size(), 1u);
  EXPECT_EQ(w.payloads(0x190)[0], first);
  restbus::CanEcu& ecu = w.ecu("MOTOR");
  ASSERT_TRUE(ecu.set_signal("MOTOR_STATUS", "speed", 65.535));
  ASSERT_TRUE(ecu.set_signal("MOTOR_STATUS", "angle", 2047));
  ASSERT_TRUE(ecu.set_signal("MOTOR_STATUS", "torque", 63.5));
  EXPECT_EQ(*ecu.get_signal("MOTOR_STATUS", "speed"), 65.535);
  EXPECT_EQ(*ecu.get_signal("MOTOR_STATUS", "angle"), 2047.0);
  w.run_until(ms(16));
  ASSERT_EQ(w.payloads(0x190).size(), 2u);
  EXPECT_EQ(w.payloads(0x190)[1],
            (std::vector<uint8_t>{0x7F, 0xFF, 0xFF, 0x00, 0x7F, 0xF0, 0x3C, 0x00}));
}

TEST(CanEcu, RefusesUnknownNamesAndValuesOutOfRangeAndChangesNothing) {
  World w(kMotor);
  restbus::CanEcu& ecu = w.ecu("MOTOR");
  const auto before = *ecu.payload("MOTOR_STATUS");
  EXPECT_EQ(ecu.set_signal("ENGINE", "speed", 1).error(),
            "CAN node MOTOR sends no message named \"ENGINE\"");
  EXPECT_EQ(ecu.set_signal("MOTOR_STATUS", "rpm", 1).error(),
            "message MOTOR_STATUS has no signal named \"rpm\"");
  EXPECT_EQ(ecu.set_signal("MOTOR_STATUS", "speed", 65.536).error(),
            "65.536 is outside the range of MOTOR_STATUS.speed: 0..65.535 kph");
  EXPECT_EQ(ecu.set_signal("MOTOR_STATUS", "speed", -1).error(),
            "-1 is outside the range of MOTOR_STATUS.speed: 0..65.535 kph");
  EXPECT_FALSE(ecu.set_signal("MOTOR_STATUS", "angle", 2048));  // 12 signed bits: -2048..2047
  EXPECT_FALSE(ecu.set_signal("MOTOR_STATUS", "torque", 64));   // 8 signed bits * 0.5
  EXPECT_EQ(ecu.get_signal("MOTOR_STATUS", "rpm").error(),
            "message MOTOR_STATUS has no signal named \"rpm\"");
  EXPECT_EQ(*ecu.payload("MOTOR_STATUS"), before);
  EXPECT_EQ(*ecu.get_signal("MOTOR_STATUS", "angle"), -3.0);
}

constexpr std::string_view kChecked = R"(
[[can_node]]
name = "BRAKE"
bus = "can0"

[[can_node.message]]
name = "BRAKE_XOR"
id = 0x100
length = 4
cycle = "10ms"

[[can_node.message.signal]]
name = "alive"
start = 0
length = 4
byte_order = "little_endian"
counter = true
initial = 14

[[can_node.message.signal]]
name = "pressure"
start = 8
length = 8
byte_order = "little_endian"
initial = 85

[[can_node.message.signal]]
name = "check"
start = 24
length = 8
byte_order = "little_endian"
checksum = "xor8"

[[can_node.message]]
name = "BRAKE_CRC"
id = 0x101
length = 8
cycle = "10ms"
delay = "1ms"

[[can_node.message.signal]]
name = "crc"
start = 7
length = 8
byte_order = "big_endian"
checksum = "crc8_sae_j1850"
data_id = 0x1234

[[can_node.message.signal]]
name = "alive"
start = 8
length = 8
byte_order = "little_endian"
counter = true
initial = 254
)";

TEST(CanEcu, CountersWrapAtTheirWidthAndChecksumsCoverTheFinalPayload) {
  World w(kChecked);
  w.run_until(ms(31) + SimDuration(500'000));
  const auto xor_frames = w.payloads(0x100);
  ASSERT_EQ(xor_frames.size(), 4u);
  const uint8_t alive[] = {14, 15, 0, 1};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(xor_frames[i],
              (std::vector<uint8_t>{alive[i], 0x55, 0x00, static_cast<uint8_t>(alive[i] ^ 0x55)}))
        << i;
  }
  const auto crc_frames = w.payloads(0x101);
  ASSERT_EQ(crc_frames.size(), 4u);
  const uint8_t alive8[] = {254, 255, 0, 1};
  for (std::size_t i = 0; i < 4; ++i) {
    std::vector<uint8_t> p{0, alive8[i], 0, 0, 0, 0, 0, 0};
    // CRC-8/SAE-J1850 over the data ID (low byte, high byte) and the other seven bytes.
    const std::vector<uint8_t> covered{0x34, 0x12, alive8[i], 0, 0, 0, 0, 0, 0};
    p[0] = restbus::crc8_sae_j1850(covered);
    EXPECT_EQ(crc_frames[i], p) << i;
  }
  EXPECT_EQ(w.ecu("BRAKE").set_signal("BRAKE_XOR", "check", 1).error(),
            "BRAKE_XOR.check is a checksum: it is computed as each frame goes out");
}

constexpr std::string_view kKinds = R"(
[[can_node]]
name = "DOOR"
bus = "can0"

[[can_node.message]]
name = "DOOR_EVENT"
id = 0x300
length = 1
send = "on_change"

[[can_node.message.signal]]
name = "open"
start = 0
length = 1
byte_order = "little_endian"

[[can_node.message]]
name = "DOOR_STATE"
id = 0x301
length = 1
send = "cyclic_and_on_change"
cycle = "100ms"
delay = "10ms"

[[can_node.message.signal]]
name = "lock"
start = 0
length = 2
byte_order = "little_endian"

[[can_node.message]]
name = "DOOR_ALARM"
id = 0x302
length = 1
send = "cyclic_if_active"
cycle = "20ms"

[[can_node.message.signal]]
name = "alarm"
start = 0
length = 8
byte_order = "little_endian"
inactive = 0
)";

TEST(CanEcu, OnChangeMessagesGoAtOnceAndOnlyWhenTheirBitsChange) {
  World w(kKinds);
  w.run_until(ms(50));
  EXPECT_TRUE(w.starts(0x300).empty());
  restbus::CanEcu& ecu = w.ecu("DOOR");
  ASSERT_TRUE(ecu.set_signal("DOOR_EVENT", "open", 1));
  ASSERT_TRUE(ecu.set_signal("DOOR_STATE", "lock", 2));
  w.run_until(ms(60));
  ASSERT_TRUE(ecu.set_signal("DOOR_EVENT", "open", 1));  // the same bits: nothing to send
  w.run_until(ms(250));
  EXPECT_EQ(w.starts(0x300), std::vector<SimTime>{ms(50)});
  EXPECT_EQ(w.payloads(0x300), (std::vector<std::vector<uint8_t>>{{1}}));
  // DOOR_STATE: cyclic from 10 ms, once more at the change (after DOOR_EVENT, which has the lower
  // identifier), and its cycle stays where it was.
  const BitTiming nominal = w.sim->bus_timing(0)->nominal;
  const auto event = *Frame::classic(0x300, std::vector<uint8_t>{1});
  const SimDuration after_event =
      frame_duration(encode(event), nominal) + intermission_duration(nominal);
  EXPECT_EQ(w.starts(0x301),
            (std::vector<SimTime>{ms(10), ms(50) + after_event, ms(110), ms(210)}));
  EXPECT_EQ(w.ecu("DOOR").counters("DOOR_STATE")->last_queued, ms(210));
}

TEST(CanEcu, AnOnChangeMessageChangedBeforeItsDelayGoesAtTheDelay) {
  std::string delayed(kKinds);
  delayed.replace(delayed.find("send = \"on_change\""), 18,
                  "send = \"on_change\"\ndelay = \"20ms\"");
  World w(delayed);
  restbus::CanEcu& ecu = w.ecu("DOOR");
  w.run_until(ms(5));
  ASSERT_TRUE(ecu.set_signal("DOOR_EVENT", "open", 1));
  w.run_until(ms(30));
  ASSERT_TRUE(ecu.set_signal("DOOR_EVENT", "open", 0));
  w.run_until(ms(40));
  EXPECT_EQ(w.starts(0x300), (std::vector<SimTime>{ms(20), ms(30)}));
  EXPECT_EQ(w.payloads(0x300), (std::vector<std::vector<uint8_t>>{{1}, {0}}));
}

TEST(CanEcu, CyclicIfActiveSendsOnItsCycleOnlyWhileASignalIsNotInactive) {
  World w(kKinds);
  restbus::CanEcu& ecu = w.ecu("DOOR");
  w.run_until(ms(30));
  ASSERT_TRUE(ecu.set_signal("DOOR_ALARM", "alarm", 3));
  w.run_until(ms(70));
  ASSERT_TRUE(ecu.set_signal("DOOR_ALARM", "alarm", 0));
  w.run_until(ms(120));
  // Inactive at 0, 20 ms; active from 30 ms: 40, 60 ms; inactive again from 70 ms.
  EXPECT_EQ(w.starts(0x302), (std::vector<SimTime>{ms(40), ms(60)}));
  const auto c = *ecu.counters("DOOR_ALARM");
  EXPECT_EQ(c.sent, 2u);
  EXPECT_EQ(c.skipped, 5u);  // 0, 20, 80, 100, 120 ms
}

constexpr std::string_view kTwo = R"(
[[can_node]]
name = "LOW"
bus = "can0"

[[can_node.message]]
name = "LOW_PRIO"
id = 0x200
length = 8
cycle = "10ms"
delay = "1ms"

[[can_node]]
name = "HIGH"
bus = "can0"

[[can_node.message]]
name = "HIGH_PRIO"
id = 0x100
length = 8
cycle = "10ms"
delay = "1ms"
)";

TEST(CanEcu, TwoNodesArbitrateTheLowerIdentifierFirstTheOtherOneFrameLater) {
  World w(kTwo);
  w.run_until(ms(25));
  const BitTiming nominal = w.sim->bus_timing(0)->nominal;
  const auto high = *Frame::classic(0x100, std::vector<uint8_t>(8, 0));
  const SimDuration later = frame_duration(encode(high), nominal) + intermission_duration(nominal);
  EXPECT_EQ(w.starts(0x100), (std::vector<SimTime>{ms(1), ms(11), ms(21)}));
  EXPECT_EQ(w.starts(0x200), (std::vector<SimTime>{ms(1) + later, ms(11) + later, ms(21) + later}));
  // Both were queued at the same instants.
  EXPECT_EQ(w.ecu("LOW").counters("LOW_PRIO")->last_queued, ms(21));
  EXPECT_EQ(w.ecu("HIGH").counters("HIGH_PRIO")->last_queued, ms(21));
}

TEST(CanEcu, BusOffStopsItsFramesUntilItIsPoweredAgain) {
  World w(kTwo);
  restbus::CanEcu& low = w.ecu("LOW");
  // Its TEC past 255 at 15 ms, as the bus_off fault effect does it.
  w.sim->scheduler().schedule_at(ms(15), [&low](SimTime) {
    FaultConfinement& fc = low.node().controller().confinement();
    fc.set_counters(kBusOffLimit, fc.rec());
    low.node().bus().counters_changed(low.node().node());
  });
  w.run_until(ms(40));
  EXPECT_TRUE(low.node().controller().confinement().bus_off());
  const auto c = *low.counters("LOW_PRIO");
  EXPECT_EQ(c.sent, 2u);     // 1 and 11 ms
  EXPECT_EQ(c.skipped, 2u);  // 21 and 31 ms: bus-off
  EXPECT_EQ(w.starts(0x200).size(), 2u);
  EXPECT_EQ(w.starts(0x100).size(), 4u);  // the other node goes on
  low.power(false);
  w.run_until(ms(50));
  low.power(true);  // a reset controller, its schedule from now: 51 ms, 61 ms
  w.run_until(ms(65));
  EXPECT_FALSE(low.node().controller().confinement().bus_off());
  EXPECT_EQ(low.counters("LOW_PRIO")->last_queued, ms(61));
  EXPECT_EQ(w.starts(0x200).size(), 4u);
}

constexpr std::string_view kMux = R"(
[[can_node]]
name = "GW"
bus = "can0"

[[can_node.message]]
name = "GW_MUX"
id = 0x400
length = 2
cycle = "10ms"

[[can_node.message.signal]]
name = "page"
start = 0
length = 8
byte_order = "little_endian"
multiplexer = true

[[can_node.message.signal]]
name = "a"
start = 8
length = 8
byte_order = "little_endian"
multiplexer_ids = [0]
initial = 17

[[can_node.message.signal]]
name = "b"
start = 8
length = 8
byte_order = "little_endian"
multiplexer_ids = [1, 2]
initial = 34
)";

TEST(CanEcu, TheMultiplexorDecidesWhichSignalsTheFrameCarries) {
  World w(kMux);
  restbus::CanEcu& ecu = w.ecu("GW");
  EXPECT_EQ(*ecu.payload("GW_MUX"), (std::vector<uint8_t>{0, 17}));
  ASSERT_TRUE(ecu.set_signal("GW_MUX", "page", 2));
  EXPECT_EQ(*ecu.payload("GW_MUX"), (std::vector<uint8_t>{2, 34}));
  ASSERT_TRUE(ecu.set_signal("GW_MUX", "page", 3));
  EXPECT_EQ(*ecu.payload("GW_MUX"), (std::vector<uint8_t>{3, 0}));
}

TEST(CanEcu, AFrameStillWaitingIsReplacedByTheNextCyclesOne) {
  World w(kTwo);
  w.run_until(ms(5));
  // A node sends identifier 1 back to back from 5 to 35 ms: the frames wait.
  HostedNode& babbler = w.sim->spare_node(0);
  babbler.start(*w.sim->bus_timing(0), nullptr, [] { return std::optional<TxFrame>{}; });
  ASSERT_TRUE(babbler.babble(*Frame::classic(0x001, std::vector<uint8_t>(8, 0)), ms(35)));
  w.run_until(ms(45));
  const auto c = *w.ecu("LOW").counters("LOW_PRIO");
  // Queued at 1, 11, 21, 31, 41 ms: the frame of 11 ms went into the controller's buffer, the
  // one of 21 ms waited and the one of 31 ms replaced it.
  EXPECT_EQ(c.queued, 5u);
  EXPECT_EQ(c.replaced, 1u);
  EXPECT_EQ(c.sent, 4u);
  EXPECT_EQ(w.starts(0x200).size(), 4u);
}

}  // namespace
}  // namespace canemu::daemon

namespace canemu::daemon {
namespace {

using namespace canemu::model;

constexpr std::string_view kLoaded = R"(
[[can_node]]
name = "MOTOR"
bus = "can0"
powered = false

[[can_node.message]]
name = "MOTOR_STATUS"
id = 0x190
length = 1
cycle = "10ms"
)";

TEST(SimulationCanNodes, AreListedInStatusByNameAndLoadedReplacedAndRemovedAtRunTime) {
  World w(kTwo);
  auto r = std::make_unique<ipc::StatusReply>();
  fill_status(*w.sim, *r);
  ASSERT_EQ(r->node_count, 2u);  // (the acknowledging node is nobody's: not listed)
  EXPECT_EQ(ipc::name_of(r->nodes[0].name), "LOW");
  EXPECT_EQ(ipc::name_of(r->nodes[1].name), "HIGH");
  EXPECT_EQ(r->nodes[1].mode, static_cast<uint8_t>(ipc::WireNodeMode::running));

  auto loaded = w.sim->load_can_nodes(kLoaded, "more.toml");
  ASSERT_TRUE(loaded) << loaded.error().front();
  EXPECT_EQ(*loaded, std::vector<std::string>{"can0/MOTOR"});
  ASSERT_TRUE(w.sim->can_node("can0/MOTOR"));
  EXPECT_FALSE(w.ecu("MOTOR").powered());
  fill_status(*w.sim, *r);
  ASSERT_EQ(r->node_count, 3u);
  EXPECT_EQ(ipc::name_of(r->nodes[2].name), "MOTOR");
  EXPECT_EQ(r->nodes[2].mode, static_cast<uint8_t>(ipc::WireNodeMode::init));
  w.ecu("MOTOR").power(true);
  w.run_until(ms(1));
  EXPECT_EQ(w.starts(0x190).size(), 1u);

  // The same name on the same bus: replaced (its node leaves the bus first).
  std::string again(kLoaded);
  again.replace(again.find("id = 0x190"), 10, "id = 0x191");
  ASSERT_TRUE(w.sim->load_can_nodes(again, "more.toml"));
  EXPECT_EQ(w.sim->can_nodes().size(), 3u);
  EXPECT_EQ(w.ecu("MOTOR").config().messages[0].id, 0x191u);

  EXPECT_EQ(w.sim->load_can_nodes("[[can_node]]\nname = \"X\"\nbus = \"can1\"\n", "bad.toml")
                .error()
                .front(),
            "bad.toml:3:7: can_node[0].bus: no bus is named \"can1\"");
  // Another node of the bus sends that identifier already.
  std::string clash(kLoaded);
  clash.replace(clash.find("MOTOR\""), 6, "PUMP\"");
  clash.replace(clash.find("MOTOR_STATUS"), 12, "PUMP_STATUS");
  clash.replace(clash.find("id = 0x190"), 10, "id = 0x100");
  EXPECT_EQ(w.sim->load_can_nodes(clash, "clash.toml").error(),
            std::vector<std::string>{"clash.toml:2: can_node PUMP: node HIGH sends identifier "
                                     "0x100 on \"can0\" already (two senders of one identifier "
                                     "collide on the wire)"});
  EXPECT_EQ(*w.sim->can_message("can0", "HIGH_PRIO"), &w.ecu("HIGH"));
  EXPECT_EQ(w.sim->can_message("can0", "NONE").error(),
            "no simulated CAN node sends a message named \"NONE\" on can0");
  EXPECT_EQ(w.sim->remove_can_node("can1/MOTOR").error(),
            "no simulated CAN node named \"can1/MOTOR\"");
  ASSERT_TRUE(w.sim->remove_can_node("MOTOR"));
  EXPECT_EQ(w.sim->can_node("MOTOR").error(), "no simulated CAN node named \"MOTOR\"");
  EXPECT_EQ(w.sim->can_nodes().size(), 2u);
}

TEST(SimulationCanNodes, StayAsTheyAreOnAReload) {
  World w(kTwo);
  Config fresh = w.sim->config();
  fresh.can_nodes.pop_back();
  const ReloadReport r = w.sim->reload(fresh);
  EXPECT_EQ(r.refused, std::vector<std::string>{
                           "can_node: the simulated CAN nodes stay as they are (a restart "
                           "changes them)"});
  EXPECT_EQ(w.sim->can_nodes().size(), 2u);
}

}  // namespace
}  // namespace canemu::daemon
