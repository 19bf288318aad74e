// What every bridge (SocketCAN, LCM, DDS) does, written once and run through each transport:
// frames from the transport go on the bus back to back from their instant, the bus's frames
// reach the transport (the bridge's own only where the transport marks them), what is no frame
// of the bus is counted and not sent, CAN FD both ways, the restart after bus-off, the listing
// and counters, and the settings refused. Each transport's test file gives an adapter and
// instantiates the suites: socketcan_bridge_test.cpp, lcm_bridge_test.cpp, dds_bridge_test.cpp.
//
// An adapter T has:
//   static constexpr TransportTraits kTraits   what the contract needs to know of the transport
//   void configure(BridgeConfig&, channels_of)
//                                              the transport's settings of a bridge (kind, bus
//                                              and restart_ms are set), on the channels (the
//                                              interface, the topics or LCM channels) it would
//                                              have as the bridge of `channels_of`
//   ipc::UniqueFd port()                       if the bridge is given its socket: a new one
//   void attach(Bridge&)                       if the test's side needs the first bridge added
//   bool remove(Simulation&, bus)              removes the bridge of `bus`
//   void inject(cansend)                       a frame written on the transport for the bus
//   std::size_t inject_what_is_no_frame()      writes what the transport can carry that is no
//                                              frame of the bus; how many reads that makes
//   void deliver(Bridge&, std::size_t count)   the bridge takes what was written, as canemud's
//                                              loop has it do, until it has `count` in all
//   std::vector<std::string> seen(Bridge&, std::size_t count)
//                                              what the bridge wrote on the transport (at least
//                                              `count` once there), candump's text, with "@ns"
//                                              where stamped and " own" for the bridge's own
//   std::vector<std::string> states(Bridge&, std::size_t count)
//                                              the node's states the bridge told the transport
//                                              ("bus-off", "restarted", "error-active", ...),
//                                              with "@ns" where stamped
//   std::string loop_error()                   the refusal of a second bridge on can0's channels
//   std::string listing()                      the names the bridge list gives the bridge of
//                                              can0 (as listed() writes them)
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge_test_support.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"

namespace canemu::daemon::bridge_test {

// What the contract needs to know of a transport besides how to reach it.
struct TransportTraits {
  const char* kind;       // the bridge's kind in the configuration
  uint8_t list_kind;      // the bridge list's kind (ipc::kBridge*)
  bool messages;          // frames reach it as messages (LCM, DDS), with their instant, the
                          // bridge's own too, marked; or as SocketCAN's, without either
  const char* name;       // how messages name the bridge of can0
  const char* node_name;  // the bridge of can0's node in the status
};

// The names a bridge's listing gives: its interface, URL (or DDS locator) and channel prefix.
inline std::string listed(const ipc::BridgeEntry& e) {
  return "interface=" + ipc::name_of(e.interface) + " url=" + ipc::name_of(e.url) +
         " prefix=" + ipc::name_of(e.channel_prefix);
}

template <class T>
class BridgeContract : public ::testing::Test {
 protected:
  std::unique_ptr<Simulation> simulation;
  T transport;
  Bridge* opened = nullptr;
  std::unique_ptr<BusNode> beside;  // a node on the bus beside the bridge's, unless it is alone
  bool attached = false;            // the transport to the first bridge added

  // A simulation of `config` with the bridge of `bus` open.
  void open(const char* config, const std::string& bus, uint32_t restart_ms = 0,
            bool alone = false) {
    simulation = world(config);
    auto b = add(*simulation, bus, restart_ms);
    ASSERT_TRUE(b) << error_text(b);
    opened = *b;
    if (!alone) {
      beside = std::make_unique<BusNode>(*simulation, 0);
    }
  }
  // Adds the bridge of `bus` to `sim`, on the channels it would have as the bridge of
  // `channels_of`.
  Result<Bridge*> add(Simulation& sim, const std::string& bus, uint32_t restart_ms = 0,
                      const std::string& channels_of = "") {
    BridgeConfig b;
    b.kind = T::kTraits.kind;
    b.bus = bus;
    b.restart_ms = restart_ms;
    transport.configure(b, channels_of.empty() ? bus : channels_of);
    Result<Bridge*> added;
    if constexpr (requires { transport.port(); }) {
      added = sim.add_bridge(b, transport.port());
    } else {
      added = sim.add_bridge(b);
    }
    if constexpr (requires { transport.attach(**added); }) {
      if (added && !attached) {
        transport.attach(**added);
        attached = true;
      }
    }
    return added;
  }
  void run_to(int64_t ns) { bridge_test::run_to(*simulation, ns); }
  // A state as states() gives it.
  static std::string stamped(int64_t at_ns, const std::string& text) {
    return text + (T::kTraits.messages ? "@" + std::to_string(at_ns) : "");
  }
  // A frame as seen() gives it: the bridge's own only where the transport carries them.
  void expect_seen(std::vector<std::string>& out, int64_t at_ns, const std::string& text,
                   bool own) {
    if (own && !T::kTraits.messages) {
      return;
    }
    out.push_back(stamped(at_ns, text) + (own ? " own" : ""));
  }
};

TYPED_TEST_SUITE_P(BridgeContract);

TYPED_TEST_P(BridgeContract, FramesFromTheTransportGoOnTheBusBackToBackWithTheirExactTimes) {
  this->open(kClassic, "can0");
  Bridge& bridge = *this->opened;
  BusNode& ecu = *this->beside;
  this->transport.inject("123#1122");
  this->transport.inject("12345678#R4");
  this->transport.inject("7FF#");
  this->transport.deliver(bridge, 3);
  this->run_to(1'000'000);
  EXPECT_EQ(ecu.texts, (std::vector<std::string>{"123#1122", "12345678#R4", "7FF#"}));
  // Back to back from t = 0: 62 bits (124 us), then 3 + 64 bits, then 3 + 47 bits (canemu calc
  // frame 123#1122, 12345678#R4, 7FF#).
  EXPECT_EQ(ecu.at_ns, (std::vector<int64_t>{124'000, 258'000, 358'000}));
  EXPECT_EQ(bridge.stats().received, 3u);
  EXPECT_EQ(bridge.stats().from_interface, 3u);
  EXPECT_EQ(bridge.stats().rejected, 0u);
  // Nothing came back to the bridge as a frame to send: its own frames reach the transport
  // only where it marks them as the bridge's own.
  std::vector<std::string> expected;
  for (std::size_t i = 0; i < ecu.texts.size(); ++i) {
    this->expect_seen(expected, ecu.at_ns[i], ecu.texts[i], true);
  }
  EXPECT_EQ(this->transport.seen(bridge, expected.size()), expected);
  EXPECT_EQ(bridge.stats().to_interface, expected.size());
  EXPECT_EQ(bridge.stats().received, 3u);
}

TYPED_TEST_P(BridgeContract, FramesOfTheBusReachTheTransportWithTheirTimesAndAreCounted) {
  this->open(kClassic, "can0");
  Bridge& bridge = *this->opened;
  BusNode& ecu = *this->beside;
  this->transport.inject("123#1122");
  this->transport.deliver(bridge, 1);
  this->run_to(1'000'000);
  // From t = 1 ms: 73 bits at 500 kbit/s (canemu calc frame 321#010203), then 3 + 71 bits.
  ecu.send("321#010203");
  ecu.send("1FFFFFFF#R");
  this->run_to(2'000'000);
  std::vector<std::string> expected;
  this->expect_seen(expected, 124'000, "123#1122", true);
  this->expect_seen(expected, 1'000'000 + 146'000, "321#010203", false);
  this->expect_seen(expected, 1'000'000 + 146'000 + 148'000, "1FFFFFFF#R", false);
  EXPECT_EQ(this->transport.seen(bridge, expected.size()), expected);

  const BridgeStats& st = bridge.stats();
  EXPECT_EQ(st.received, 1u);
  EXPECT_EQ(st.from_interface, 1u);
  EXPECT_EQ(st.to_interface, expected.size());
  EXPECT_EQ(st.rejected, 0u);
  ipc::BridgeListReply list{};
  fill_bridge_list(*this->simulation, list);
  ASSERT_EQ(list.count, 1);
  EXPECT_EQ(list.bridges[0].kind, TypeParam::kTraits.list_kind);
  EXPECT_EQ(listed(list.bridges[0]), this->transport.listing());
  EXPECT_EQ(list.bridges[0].received, 1u);
  EXPECT_EQ(list.bridges[0].from_interface, 1u);
  EXPECT_EQ(list.bridges[0].to_interface, expected.size());
  // The bridge's node is in the NODE table, named by what it joins, with its counts.
  auto status = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>());
  fill_status(*this->simulation, *status);
  ASSERT_EQ(status->node_count, 1u);
  EXPECT_EQ(ipc::name_of(status->nodes[0].name), TypeParam::kTraits.node_name);
  EXPECT_EQ(status->nodes[0].bus, 0u);
  EXPECT_EQ(status->nodes[0].mode, static_cast<uint8_t>(ipc::WireNodeMode::running));
  EXPECT_EQ(status->nodes[0].frames_sent, 1u);
  EXPECT_EQ(status->nodes[0].frames_received, 2u);
}

TYPED_TEST_P(BridgeContract, WhatIsNoFrameOfTheBusIsCountedNotSent) {
  this->open(kClassic, "can0");
  Bridge& bridge = *this->opened;
  BusNode& ecu = *this->beside;
  this->transport.inject("100##10102");  // a CAN FD frame on a classic bus
  const std::size_t reads = 1 + this->transport.inject_what_is_no_frame();
  this->transport.deliver(bridge, reads);
  this->run_to(1'000'000);
  EXPECT_EQ(bridge.stats().received, reads);
  EXPECT_EQ(bridge.stats().rejected, reads);
  EXPECT_EQ(bridge.stats().from_interface, 0u);
  EXPECT_TRUE(ecu.at_ns.empty());
}

TYPED_TEST_P(BridgeContract, CanFdFramesBothWaysOnACanFdBus) {
  this->open(kFd, "fd0");
  Bridge& bridge = *this->opened;
  BusNode& ecu = *this->beside;
  this->transport.inject("7AB##1A0A1A2A3A4A5A6A7A8A9AAAB");  // BRS, 12 bytes (DLC 9)
  this->transport.deliver(bridge, 1);
  this->run_to(1'000'000);
  ecu.send("456##3AABB");  // BRS, and ESI asked for
  this->run_to(2'000'000);
  EXPECT_EQ(ecu.texts, (std::vector<std::string>{"7AB##1A0A1A2A3A4A5A6A7A8A9AAAB"}));
  ASSERT_EQ(ecu.at_ns.size(), 1u);
  std::vector<std::string> expected;
  this->expect_seen(expected, ecu.at_ns[0], "7AB##1A0A1A2A3A4A5A6A7A8A9AAAB", true);
  // ESI is what the wire carried: the transmitter's error state (error-active: dominant). The
  // frame ends 76.5 us after 1 ms, its 27 nominal and 48 data-phase bits (canemu calc frame
  // 456##3AABB).
  this->expect_seen(expected, 1'000'000 + 76'500, "456##1AABB", false);
  EXPECT_EQ(this->transport.seen(bridge, expected.size()), expected);
  EXPECT_EQ(bridge.stats().to_interface, expected.size());
}

TYPED_TEST_P(BridgeContract, RestartsRestartMsAfterBusOffThenWaitsForTheRecessiveBits) {
  this->open(kClassic, "can0", 5);
  Bridge& bridge = *this->opened;
  BusNode& ecu = *this->beside;
  const model::FaultConfinement& fc = bridge.node().controller().confinement();
  EXPECT_EQ(error_text(bridge.restart()), std::string(TypeParam::kTraits.name) +
                                              " is error-active, not bus-off: nothing to restart");
  bus_off_at(*this->simulation, bridge.node(), 1'000'000);
  this->run_to(2'000'000);
  ASSERT_TRUE(fc.bus_off());
  this->transport.inject("123#1122");  // waits for the node
  this->transport.deliver(bridge, 1);
  this->run_to(1'000'000 + 5'000'000 - 1);
  EXPECT_EQ(bridge.stats().restarts, 0u);
  EXPECT_FALSE(fc.recovering());
  this->run_to(6'000'000);  // exactly restart_ms after the bus-off instant
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_TRUE(fc.recovering());
  EXPECT_EQ(error_text(bridge.restart()),
            std::string(TypeParam::kTraits.name) +
                " restarts already (waits for 128 x 11 recessive bits, 128 left)");
  this->run_to(6'000'000 + kRecoveryNs - 1);
  EXPECT_TRUE(fc.bus_off());
  this->run_to(6'000'000 + kRecoveryNs);
  EXPECT_FALSE(fc.bus_off());
  EXPECT_EQ(fc.tec(), 0);
  // Then the queued frame goes: 62 bits from the recovery's end.
  this->run_to(10'000'000);
  EXPECT_EQ(ecu.texts, (std::vector<std::string>{"123#1122"}));
  EXPECT_EQ(ecu.at_ns, (std::vector<int64_t>{6'000'000 + kRecoveryNs + 124'000}));
  EXPECT_EQ(bridge.stats().from_interface, 1u);
  EXPECT_EQ(bridge.stats().restarts, 1u);
  // What the transport was told: bus-off, the restart, error-active again.
  const std::vector<std::string> told{this->stamped(1'000'000, "bus-off"),
                                      this->stamped(6'000'000, "restarted"),
                                      this->stamped(6'000'000 + kRecoveryNs, "error-active")};
  EXPECT_EQ(this->transport.states(bridge, told.size()), told);
  EXPECT_EQ(bridge.stats().error_frames, told.size());
}

TYPED_TEST_P(BridgeContract, OneBridgeOnTheSameChannelsAndNoneOnAnUnknownBus) {
  this->simulation = world(kTwoBuses);
  Simulation& sim = *this->simulation;
  ASSERT_TRUE(this->add(sim, "can0"));
  // can1's bridge on the channels can0's uses: what one sends, the other would take in.
  EXPECT_EQ(error_text(this->add(sim, "can1", 0, "can0")), this->transport.loop_error());
  EXPECT_EQ(error_text(this->add(sim, "can7")), "no bus is named \"can7\"");
  EXPECT_EQ(sim.bridges().size(), 1u);
  ASSERT_TRUE(this->add(sim, "can1"));
  EXPECT_EQ(sim.bridges().size(), 2u);
  EXPECT_TRUE(this->transport.remove(sim, "can0"));
  EXPECT_FALSE(this->transport.remove(sim, "can0"));
  EXPECT_EQ(sim.bridges().size(), 1u);
}

REGISTER_TYPED_TEST_SUITE_P(BridgeContract,
                            FramesFromTheTransportGoOnTheBusBackToBackWithTheirExactTimes,
                            FramesOfTheBusReachTheTransportWithTheirTimesAndAreCounted,
                            WhatIsNoFrameOfTheBusIsCountedNotSent, CanFdFramesBothWaysOnACanFdBus,
                            RestartsRestartMsAfterBusOffThenWaitsForTheRecessiveBits,
                            OneBridgeOnTheSameChannelsAndNoneOnAnUnknownBus);

}  // namespace canemu::daemon::bridge_test
