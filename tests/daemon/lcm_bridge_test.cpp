// The LCM bridge on LCM's memq:// provider: one LCM instance inside this process, so the test
// publishes on the bridge's TX channel and subscribes to its other channels on the bridge's own
// instance (lcm_instance()); what LCM delivers is handled when the bridge is kicked, as canemud
// does when the instance's descriptor is readable. The same bridge runs over udpm:// between
// processes in tests/python/test_lcm_bridge.py.
#include "canemu/daemon/bridges/lcm_bridge.hpp"

#include <lcm/lcm.h>

#include <deque>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge_test_support.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu_lcm/error_t.hpp"
#include "canemu_lcm/frame_t.hpp"
#include "canemu_lcm/state_t.hpp"

namespace canemu::daemon {
namespace {

using namespace bridge_test;
using Node = BusNode;

BridgeConfig lcm_bridge(const std::string& bus, uint32_t restart_ms = 0) {
  BridgeConfig b;
  b.kind = "lcm";
  b.bus = bus;
  b.url = "memq://";
  b.restart_ms = restart_ms;
  return b;
}

// Everything published on one channel, decoded with the C++ types programs use.
template <class T>
struct Recorded {
  std::vector<T> messages;
  Recorded(lcm_t* lcm, const std::string& channel) {
    lcm_subscribe(lcm, channel.c_str(), &Recorded::handle, this);
  }
  static void handle(const lcm_recv_buf_t* rbuf, const char*, void* user) {
    T m;
    ASSERT_GE(m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)), 0);
    static_cast<Recorded*>(user)->messages.push_back(m);
  }
};

canemu_lcm::frame_t frame(int32_t id, std::vector<uint8_t> data, bool extended = false) {
  canemu_lcm::frame_t f{};
  f.id = id;
  f.extended = extended;
  f.dlc = static_cast<int8_t>(data.size());
  f.len = static_cast<int8_t>(data.size());
  std::copy(data.begin(), data.end(), f.data);
  return f;
}

void publish(lcm_t* lcm, const std::string& channel, const canemu_lcm::frame_t& f) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(f.getEncodedSize()));
  ASSERT_EQ(f.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  ASSERT_EQ(lcm_publish(lcm, channel.c_str(), bytes.data(), static_cast<unsigned>(bytes.size())),
            0);
}

TEST(LcmBridge, ChannelNamesAndTheirChecks) {
  EXPECT_EQ(default_lcm_prefix("can0"), "CANEMU_CAN0_");
  EXPECT_EQ(default_lcm_prefix("fd-1.x"), "CANEMU_FD_1_X_");
  EXPECT_EQ(lcm_prefix_problem("ROBOT/CAN0."), std::nullopt);
  EXPECT_EQ(lcm_prefix_problem("A B"),
            "\"A B\" is not a channel prefix (letters, digits, '_', '-', '.', '/')");
  EXPECT_EQ(lcm_prefix_problem(""), "\"\" is not a channel prefix (1 to 63 characters)");
  EXPECT_EQ(lcm_url_problem("udpm://239.255.76.67:7667?ttl=0"), std::nullopt);
  EXPECT_EQ(lcm_url_problem("239.255.76.67"),
            "\"239.255.76.67\" is not an LCM URL (provider://network?options, up to 127 "
            "characters)");
  EXPECT_TRUE(lcm_available());
}

TEST(LcmBridge, FramesFromTxGoOutOnTheBusAndEveryFrameIsPublishedWithItsExactTime) {
  auto sim = world(kClassic);
  auto b = sim->add_bridge(lcm_bridge("can0"));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  lcm_t* lcm = lcm_instance(bridge.transport());
  ASSERT_NE(lcm, nullptr);
  EXPECT_EQ(bridge.options().channel_prefix, "CANEMU_CAN0_");
  Recorded<canemu_lcm::frame_t> frames(lcm, "CANEMU_CAN0_FRAMES");
  Node ecu(*sim, 0);

  publish(lcm, "CANEMU_CAN0_TX", frame(0x123, {0x11, 0x22}));
  canemu_lcm::frame_t remote{};
  remote.id = 0x12345678;
  remote.extended = true;
  remote.remote = true;
  remote.dlc = 4;
  publish(lcm, "CANEMU_CAN0_TX", remote);
  bridge.kick();  // the instance's descriptor was readable
  run_to(*sim, 1'000'000);
  // As the SocketCAN bridge's frames from the same instant: back to back from t = 0.
  EXPECT_EQ(ecu.at_ns, (std::vector<int64_t>{124'000, 258'000}));

  ecu.send(0x321, {1, 2, 3});
  run_to(*sim, 2'000'000);
  bridge.kick();  // delivers what the bridge published
  ASSERT_EQ(frames.messages.size(), 3u);
  const canemu_lcm::frame_t& a = frames.messages[0];
  EXPECT_EQ(a.timestamp_ns, 124'000);
  EXPECT_EQ(a.id, 0x123);
  EXPECT_FALSE(a.extended);
  EXPECT_EQ(a.dlc, 2);
  EXPECT_EQ(a.len, 2);
  EXPECT_EQ(a.data[0], 0x11);
  EXPECT_EQ(a.data[1], 0x22);
  EXPECT_EQ(a.data[2], 0);
  EXPECT_TRUE(a.from_tx);
  const canemu_lcm::frame_t& r = frames.messages[1];
  EXPECT_EQ(r.timestamp_ns, 258'000);
  EXPECT_EQ(r.id, 0x12345678);
  EXPECT_TRUE(r.extended);
  EXPECT_TRUE(r.remote);
  EXPECT_EQ(r.dlc, 4);
  EXPECT_EQ(r.len, 0);
  const canemu_lcm::frame_t& e = frames.messages[2];
  // From t = 1 ms: 73 bits at 500 kbit/s (canemu calc frame 321#010203).
  EXPECT_EQ(e.timestamp_ns, 1'000'000 + 146'000);
  EXPECT_EQ(e.id, 0x321);
  EXPECT_EQ(e.len, 3);
  EXPECT_EQ(e.data[2], 3);
  EXPECT_FALSE(e.from_tx);

  const BridgeStats& st = bridge.stats();
  EXPECT_EQ(st.received, 2u);
  EXPECT_EQ(st.from_interface, 2u);
  EXPECT_EQ(st.to_interface, 3u);
  EXPECT_EQ(st.rejected, 0u);
  ipc::BridgeListReply list;
  fill_bridge_list(*sim, list);
  ASSERT_EQ(list.count, 1);
  EXPECT_EQ(list.bridges[0].kind, ipc::kBridgeLcm);
  EXPECT_EQ(ipc::name_of(list.bridges[0].url), "memq://");
  EXPECT_EQ(ipc::name_of(list.bridges[0].channel_prefix), "CANEMU_CAN0_");
  EXPECT_EQ(list.bridges[0].received, 2u);
  EXPECT_EQ(list.bridges[0].to_interface, 3u);
  // The bridge's node is in the NODE table, named by what it joins, with its counts.
  auto status = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>());
  fill_status(*sim, *status);
  ASSERT_EQ(status->node_count, 1u);
  EXPECT_EQ(ipc::name_of(status->nodes[0].name), "lcm:can0");
  EXPECT_EQ(status->nodes[0].bus, 0u);
  EXPECT_EQ(status->nodes[0].mode, static_cast<uint8_t>(ipc::WireNodeMode::running));
  EXPECT_EQ(status->nodes[0].frames_sent, 2u);
  EXPECT_EQ(status->nodes[0].frames_received, 1u);
}

TEST(LcmBridge, WhatIsNoFrameOfTheBusIsCountedNotSent) {
  auto sim = world(kClassic);
  auto b = sim->add_bridge(lcm_bridge("can0"));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  lcm_t* lcm = lcm_instance(bridge.transport());
  Node ecu(*sim, 0);
  canemu_lcm::frame_t fd = frame(0x100, {1, 2});
  fd.fd = true;  // a CAN FD frame on a classic bus
  publish(lcm, "CANEMU_CAN0_TX", fd);
  canemu_lcm::frame_t disagree = frame(0x100, {1, 2});
  disagree.len = 3;  // its DLC says 2 bytes
  publish(lcm, "CANEMU_CAN0_TX", disagree);
  publish(lcm, "CANEMU_CAN0_TX", frame(0x800, {}));  // 12 bits in a standard identifier
  canemu_lcm::state_t other{};                       // another type altogether
  std::vector<uint8_t> bytes(static_cast<std::size_t>(other.getEncodedSize()));
  other.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  lcm_publish(lcm, "CANEMU_CAN0_TX", bytes.data(), static_cast<unsigned>(bytes.size()));
  const uint8_t junk[3] = {1, 2, 3};
  lcm_publish(lcm, "CANEMU_CAN0_TX", junk, sizeof junk);
  publish(lcm, "CANEMU_CAN0_TXX", frame(0x1, {}));  // another channel: not the bridge's
  bridge.kick();
  run_to(*sim, 1'000'000);
  EXPECT_EQ(bridge.stats().received, 5u);
  EXPECT_EQ(bridge.stats().rejected, 5u);
  EXPECT_EQ(bridge.stats().from_interface, 0u);
  EXPECT_TRUE(ecu.at_ns.empty());
}

TEST(LcmBridge, CanFdFramesOnACanFdBus) {
  auto sim = world(kFd);
  auto b = sim->add_bridge(lcm_bridge("fd0"));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  lcm_t* lcm = lcm_instance(bridge.transport());
  Recorded<canemu_lcm::frame_t> frames(lcm, "CANEMU_FD0_FRAMES");
  Node ecu(*sim, 0);
  canemu_lcm::frame_t f{};
  f.id = 0x7AB;
  f.fd = true;
  f.brs = true;
  f.dlc = 9;  // 12 bytes
  f.len = 12;
  for (int i = 0; i < 12; ++i) {
    f.data[i] = static_cast<uint8_t>(0xA0 + i);
  }
  publish(lcm, "CANEMU_FD0_TX", f);
  bridge.kick();
  run_to(*sim, 1'000'000);
  bridge.kick();
  ASSERT_EQ(frames.messages.size(), 1u);
  EXPECT_TRUE(frames.messages[0].fd);
  EXPECT_TRUE(frames.messages[0].brs);
  EXPECT_EQ(frames.messages[0].dlc, 9);
  EXPECT_EQ(frames.messages[0].len, 12);
  EXPECT_EQ(frames.messages[0].data[11], 0xAB);
  EXPECT_EQ(frames.messages[0].timestamp_ns, ecu.at_ns.at(0));
}

TEST(LcmBridge, ErrorsAndStatesArePublishedAndTheNodeRestartsAfterRestartMs) {
  auto sim = world(kClassic);
  auto b = sim->add_bridge(lcm_bridge("can0", 5));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  lcm_t* lcm = lcm_instance(bridge.transport());
  Recorded<canemu_lcm::error_t> errors(lcm, "CANEMU_CAN0_ERRORS");
  Recorded<canemu_lcm::state_t> states(lcm, "CANEMU_CAN0_STATES");
  // Alone on the bus: no acknowledgement. 16 ACK errors take the transmitter to error-passive
  // (warning at 96 on the way), where the passive ACK-error exception holds its counter.
  publish(lcm, "CANEMU_CAN0_TX", frame(0x123, {0x11, 0x22}));
  bridge.kick();
  run_to(*sim, 20'000'000);
  bridge.kick();
  ASSERT_GE(errors.messages.size(), 16u);
  const canemu_lcm::error_t& first = errors.messages[0];
  EXPECT_EQ(first.type, canemu_lcm::error_t::ACK);
  EXPECT_EQ(first.role, canemu_lcm::error_t::TRANSMITTER);
  EXPECT_EQ(first.field, "ACK");  // the ACK slot
  EXPECT_TRUE(first.in_frame);
  EXPECT_EQ(first.tec, 8);
  EXPECT_EQ(first.rec, 0);
  ASSERT_EQ(states.messages.size(), 2u);
  EXPECT_EQ(states.messages[0].state, canemu_lcm::state_t::WARNING);
  EXPECT_EQ(states.messages[0].tec, 96);
  EXPECT_EQ(states.messages[0].timestamp_ns, errors.messages[11].timestamp_ns);
  EXPECT_EQ(states.messages[1].state, canemu_lcm::state_t::PASSIVE);
  EXPECT_EQ(states.messages[1].tec, 128);
  EXPECT_EQ(states.messages[1].timestamp_ns, errors.messages[15].timestamp_ns);
  EXPECT_FALSE(states.messages[1].restarted);

  // Bus-off by hand (as the bus_off fault effect does), then restart_ms later the restart.
  const int64_t off_at = 30'000'000;
  sim->scheduler().schedule_at(model::SimTime::from_ns(off_at), [&bridge](model::SimTime) {
    model::FaultConfinement& fc = bridge.node().controller().confinement();
    fc.set_counters(model::kBusOffLimit, fc.rec());
    bridge.node().bus().counters_changed(bridge.node().node());
  });
  run_to(*sim, off_at + 5'000'000);
  bridge.kick();
  ASSERT_EQ(states.messages.size(), 4u);
  EXPECT_EQ(states.messages[2].state, canemu_lcm::state_t::BUS_OFF);
  EXPECT_EQ(states.messages[2].timestamp_ns, off_at);
  EXPECT_FALSE(states.messages[2].restarted);
  EXPECT_EQ(states.messages[3].state, canemu_lcm::state_t::BUS_OFF);
  EXPECT_TRUE(states.messages[3].restarted);
  EXPECT_EQ(states.messages[3].timestamp_ns, off_at + 5'000'000);
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_EQ(bridge.restart().error(),
            "LCM bridge of can0 restarts already (waits for 128 x 11 "
            "recessive bits, 128 left)");
  EXPECT_EQ(bridge.stats().error_frames, errors.messages.size() + states.messages.size());
  EXPECT_EQ(bridge.stats().to_interface_dropped, 0u);
}

TEST(LcmBridge, OneLcmBridgeABusAndNoTwoOnTheSameChannels) {
  auto sim = world(std::string(kClassic) + "[[bus]]\nname = \"can1\"\n");
  ASSERT_TRUE(sim->add_bridge(lcm_bridge("can0")));
  EXPECT_EQ(sim->add_bridge(lcm_bridge("can0")).error(), "can0 has an LCM bridge already");
  BridgeConfig same = lcm_bridge("can1");
  same.channel_prefix = "CANEMU_CAN0_";
  EXPECT_EQ(sim->add_bridge(same).error(),
            "the LCM bridge of can0 uses the channels CANEMU_CAN0_* on memq:// already (their "
            "frames would loop)");
  BridgeConfig bad = lcm_bridge("can1");
  bad.url = "nosuch://";
  EXPECT_EQ(sim->add_bridge(bad).error(), "LCM cannot open \"nosuch://\"");
  EXPECT_EQ(sim->add_bridge(lcm_bridge("can7")).error(), "no bus is named \"can7\"");
  ASSERT_TRUE(sim->add_bridge(lcm_bridge("can1")));
  EXPECT_EQ(sim->bridges().size(), 2u);
  EXPECT_FALSE(sim->remove_bridge("can0"));  // a SocketCAN bridge's interface: none
  EXPECT_TRUE(sim->remove_bus_bridge(BridgeKind::lcm, "can0"));
  EXPECT_FALSE(sim->remove_bus_bridge(BridgeKind::lcm, "can0"));
  EXPECT_EQ(sim->bridges().size(), 1u);
}

TEST(LcmBridgeConfig, ReadsTheTableWithItsDefaultsAndNamesEveryMistake) {
  auto cfg = parse_config(std::string(kClassic) +
                              "[[bus]]\nname = \"can1\"\n"
                              "[[bridge]]\nkind = \"lcm\"\nbus = \"can0\"\n"
                              "[[bridge]]\nkind = \"lcm\"\nbus = \"can1\"\nrestart_ms = 100\n"
                              "url = \"udpm://239.255.76.67:7668?ttl=0\"\n"
                              "channel_prefix = \"ROBOT/CAN1_\"\n",
                          "t.toml");
  ASSERT_TRUE(cfg) << cfg.error().front();
  ASSERT_EQ(cfg->bridges.size(), 2u);
  EXPECT_EQ(cfg->bridges[0].kind, "lcm");
  EXPECT_EQ(cfg->bridges[0].url, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(cfg->bridges[0].channel_prefix, "CANEMU_CAN0_");
  EXPECT_EQ(cfg->bridges[1].url, "udpm://239.255.76.67:7668?ttl=0");
  EXPECT_EQ(cfg->bridges[1].channel_prefix, "ROBOT/CAN1_");
  EXPECT_EQ(cfg->bridges[1].restart_ms, 100u);
  auto bad = parse_config(std::string(kClassic) +
                              "[[bus]]\nname = \"can1\"\n"
                              "[[bridge]]\nkind = \"lcm\"\nbus = \"can0\"\ninterface = \"vcan0\"\n"
                              "[[bridge]]\nkind = \"lcm\"\nbus = \"can0\"\n"
                              "channel_prefix = \"A B\"\nurl = \"nowhere\"\n"
                              "[[bridge]]\nkind = \"lcm\"\nbus = \"can1\"\n"
                              "channel_prefix = \"CANEMU_CAN0_\"\n",
                          "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(),
            (std::vector<std::string>{
                "t.toml:8:1: bridge[0].interface: unknown key (known here: kind, bus, url, "
                "channel_prefix, restart_ms)",
                "t.toml:11:7: bridge[1].bus: another LCM bridge joins \"can0\" already",
                "t.toml:13:7: bridge[1].url: \"nowhere\" is not an LCM URL "
                "(provider://network?options, up to 127 characters)",
                "t.toml:12:18: bridge[1].channel_prefix: \"A B\" is not a channel prefix "
                "(letters, digits, '_', '-', '.', '/')",
                "t.toml:14:1: bridge[2]: another LCM bridge uses the channels CANEMU_CAN0_* on "
                "udpm://239.255.76.67:7667?ttl=0 already (their frames would loop)"}));
}

// The C++ types programs use and the C types canemud uses are the same messages.
TEST(LcmTypes, CppAndCAgreeOnTheWire) {
  canemu_lcm::frame_t f = frame(0x1ABCDEF0, {9, 8, 7}, true);
  f.timestamp_ns = 123'456'789;
  f.from_tx = true;
  std::vector<uint8_t> bytes(static_cast<std::size_t>(f.getEncodedSize()));
  ASSERT_EQ(f.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(bytes.size(), 8u + 8 + 4 + 7 + 64 + 1);  // fingerprint and fields, big-endian
  EXPECT_EQ(bytes[8 + 7], 0x15);                     // 123456789 = 0x075BCD15
  EXPECT_EQ(bytes[16], 0x1A);
}

}  // namespace
}  // namespace canemu::daemon
