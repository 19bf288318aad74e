// The DDS bridge with a DDS participant of the test's own in the same process (Cyclone DDS
// delivers between participants of one process without the network). Each test process takes a
// domain of its own, on the loopback interface only, so tests running at once never hear each
// other. What arrives for the bridge wakes its eventfd, as in canemud's loop: the test waits on
// that descriptor (with a timeout) and then kicks the bridge. The same bridge runs between
// processes in tests/python/test_dds_bridge.py. What every bridge does is bridge_contract.hpp's,
// run here as DdsBridge/BridgeContract, and message_bridge_contract.hpp's as
// DdsBridge/MessageBridges.
#include "canemu/daemon/bridges/dds_bridge.hpp"

#include <poll.h>
#include <unistd.h>

#include <cstdlib>
#include <deque>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <gtest/gtest.h>

#include "bridge_contract.hpp"
#include "bridge_test_support.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu_dds.h"
#include "message_bridge_contract.hpp"
#include "ros2_can_msgs.h"

namespace canemu::daemon {
namespace {

using namespace bridge_test;
using namespace daemon_test;

BridgeConfig dds_bridge(const std::string& bus, bool ros2 = false, uint32_t restart_ms = 0) {
  BridgeConfig b;
  b.kind = "dds";
  b.bus = bus;
  b.domain = test_domain();
  b.partition = "canemu";
  b.ros2 = ros2;
  b.restart_ms = restart_ms;
  return b;
}

// The test's side: a participant with readers and writers like a program's.
struct Peer {
  dds_entity_t participant;
  dds_qos_t* qos;
  dds_qos_t* ours;
  Peer() : participant(dds_create_participant(test_domain(), nullptr, nullptr)) {
    qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    ours = dds_create_qos();
    dds_copy_qos(ours, qos);
    dds_qset_partition1(ours, "canemu");
  }
  ~Peer() {
    dds_delete_qos(ours);
    dds_delete_qos(qos);
    dds_delete(participant);
  }
  dds_entity_t topic(const dds_topic_descriptor_t* type, const std::string& name) {
    return dds_create_topic(participant, type, name.c_str(), nullptr, nullptr);
  }
  // In canemu's partition, or without one (ROS 2's topics).
  dds_entity_t writer(const dds_topic_descriptor_t* type, const std::string& name,
                      bool partition = true) {
    const dds_entity_t pub = dds_create_publisher(participant, partition ? ours : nullptr, nullptr);
    return dds_create_writer(pub, topic(type, name), qos, nullptr);
  }
  dds_entity_t reader(const dds_topic_descriptor_t* type, const std::string& name,
                      bool partition = true) {
    const dds_entity_t sub =
        dds_create_subscriber(participant, partition ? ours : nullptr, nullptr);
    return dds_create_reader(sub, topic(type, name), qos, nullptr);
  }
};

// Takes every sample `reader` has now.
template <class T>
std::vector<T> take_all(dds_entity_t reader) {
  std::vector<T> out;
  for (;;) {
    T sample{};
    void* p = &sample;
    dds_sample_info_t info;
    if (dds_take(reader, &p, &info, 1, 1) != 1) {
      return out;
    }
    if (info.valid_data) {
      out.push_back(sample);
    }
  }
}

// Waits (at most 5 s) until `reader` has `count` samples or more; local delivery is immediate,
// so this only guards against a slow machine.
void await(dds_entity_t reader, std::size_t count) {
  const dds_entity_t ws = dds_create_waitset(dds_get_participant(reader));
  const dds_entity_t cond = dds_create_readcondition(reader, DDS_NOT_READ_SAMPLE_STATE);
  dds_waitset_attach(ws, cond, 0);
  for (int i = 0; i < 50; ++i) {
    void* samples[64] = {};
    dds_sample_info_t infos[64];
    const dds_return_t n = dds_read(reader, samples, infos, 64, 64);  // all, read or not
    if (n > 0) {
      dds_return_loan(reader, samples, n);
    }
    if (n >= 0 && static_cast<std::size_t>(n) >= count) {
      break;
    }
    dds_waitset_wait(ws, nullptr, 0, DDS_MSECS(100));
  }
  dds_delete(ws);
}

// Waits (at most 5 s) until the bridge's descriptor is readable, then kicks it, as canemud does.
void kick_when_rung(Bridge& bridge) {
  pollfd p{bridge.doorbell_fd(), POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 5000), 1) << "the bridge's eventfd was never rung";
  bridge.kick();
}

// The contract's adapter (bridge_contract.hpp): a participant of the test's own with the
// bridge's topics, in its partition.
struct DdsAdapter {
  std::unique_ptr<Peer> peer;  // with the first bridge's topics
  dds_entity_t tx = 0;
  dds_entity_t frames = 0;
  dds_entity_t error_reader = 0;
  dds_entity_t state_reader = 0;
  static constexpr TransportTraits kTraits{"dds", ipc::kBridgeDds, true, "DDS bridge of can0",
                                           "dds:can0"};

  void configure(BridgeConfig& b, const std::string& channels_of) {
    b.domain = test_domain();
    b.partition = "canemu";
    if (channels_of != b.bus) {
      b.channel_prefix = default_dds_prefix(channels_of);
    }
  }
  // Readers of the topics the bridge publishes, a writer of the one it takes frames from.
  void attach(Bridge& bridge) {
    const std::string prefix = bridge.options().channel_prefix;
    EXPECT_EQ(prefix, default_dds_prefix(bridge.options().bus));
    peer = std::make_unique<Peer>();
    frames = peer->reader(&canemu_dds_Frame_desc, prefix + "frames");
    error_reader = peer->reader(&canemu_dds_BusError_desc, prefix + "errors");
    state_reader = peer->reader(&canemu_dds_NodeState_desc, prefix + "states");
    tx = peer->writer(&canemu_dds_Frame_desc, prefix + "tx");
    EXPECT_GT(frames, 0);
    EXPECT_GT(tx, 0);
  }
  bool remove(Simulation& sim, const std::string& bus) {
    return sim.remove_bus_bridge(BridgeKind::dds, bus);
  }
  void inject(const std::string& cansend) { write(published<canemu_dds_Frame>(cansend)); }
  void write(const canemu_dds_Frame& f) { EXPECT_EQ(dds_write(tx, &f), DDS_RETCODE_OK); }
  std::size_t inject_what_is_no_frame() {
    canemu_dds_Frame disagree = published<canemu_dds_Frame>("100#0102");
    disagree.len = 3;  // its DLC says 2 bytes
    canemu_dds_Frame big_dlc = published<canemu_dds_Frame>("100#");
    big_dlc.dlc = 16;
    for (const canemu_dds_Frame& f : {disagree, published<canemu_dds_Frame>("800#"), big_dlc}) {
      write(f);
    }
    return 3;
  }
  // Each sample rings the bridge's eventfd; a kick takes what has arrived by then.
  void deliver(Bridge& bridge, std::size_t count) {
    for (std::size_t i = 0; i < count && bridge.stats().received < count; ++i) {
      kick_when_rung(bridge);
    }
  }
  std::vector<std::string> seen(Bridge&, std::size_t count) {
    await(frames, count);
    return converted(take_all<canemu_dds_Frame>(frames), seen_text<canemu_dds_Frame>);
  }
  std::vector<PublishedError> errors(Bridge&, std::size_t count) {
    await(error_reader, count);
    return converted(take_all<canemu_dds_BusError>(error_reader),
                     published_error<canemu_dds_BusError>);
  }
  std::vector<std::string> states(Bridge&, std::size_t count, bool with_tec = false) {
    await(state_reader, count);
    return converted(take_all<canemu_dds_NodeState>(state_reader),
                     [&](const canemu_dds_NodeState& s) { return published_state(s, with_tec); });
  }
  std::string second_bridge_error() const { return "can0 has a DDS bridge already"; }
  std::string listing() const {
    return "interface= url=" + std::to_string(test_domain()) + "/canemu prefix=canemu/can0/";
  }
  std::string loop_error() const {
    return "the DDS bridge of can0 uses the topics canemu/can0/* in domain " +
           std::to_string(test_domain()) + ", partition canemu already (their frames would loop)";
  }
};

TEST(DdsBridge, NamesLocatorsAndTheirChecks) {
  EXPECT_EQ(default_dds_prefix("can0"), "canemu/can0/");
  EXPECT_EQ(default_dds_prefix("fd-1.x"), "canemu/fd_1_x/");
  EXPECT_EQ(dds_prefix_problem("robot/can0/"), std::nullopt);
  EXPECT_EQ(dds_prefix_problem("a b"),
            "\"a b\" is not a topic prefix (1 to 63 letters, digits, '_' and '/', not starting "
            "with a digit)");
  EXPECT_TRUE(dds_prefix_problem("0can"));
  EXPECT_TRUE(dds_prefix_problem(""));
  EXPECT_EQ(dds_partition_problem("rig-a"), std::nullopt);
  EXPECT_EQ(dds_partition_problem("rig*"),
            "\"rig*\" is not a partition (1 to 63 printable characters; no blanks, '*', '?', '+' "
            "or '/')");
  EXPECT_EQ(dds_domain_problem(232), std::nullopt);
  EXPECT_EQ(dds_domain_problem(233), "233 is not a DDS domain id (0 to 232)");
  DdsOptions o;
  o.domain = 7;
  o.partition = "rig-a";
  EXPECT_EQ(dds_locator(o), "7/rig-a");
  o.ros2 = true;
  EXPECT_EQ(dds_locator(o), "7/rig-a+ros2");
  const auto back = parse_dds_locator("7/rig-a+ros2");
  ASSERT_TRUE(back);
  EXPECT_EQ(back->domain, 7u);
  EXPECT_EQ(back->partition, "rig-a");
  EXPECT_TRUE(back->ros2);
  EXPECT_FALSE(parse_dds_locator("7"));
  EXPECT_FALSE(parse_dds_locator("300/canemu"));
  EXPECT_FALSE(parse_dds_locator("x/canemu"));
  EXPECT_FALSE(parse_dds_locator("1/a b"));
  EXPECT_TRUE(dds_available());
}

TEST(DdsBridgeConfig, ReadsTheTableWithItsDefaultsAndNamesEveryMistake) {
  const Config cfg = config_of(kTwoBuses + bridge_table("dds", "can0") +
                                   bridge_table("dds", "can1",
                                                "domain = 7\npartition = \"rig-a\"\n"
                                                "topic_prefix = \"robot/can1/\"\nros2 = true\n"
                                                "restart_ms = 100\n"),
                               "test.toml");
  ASSERT_EQ(cfg.bridges.size(), 2u);
  EXPECT_EQ(cfg.bridges[0].kind, "dds");
  EXPECT_EQ(cfg.bridges[0].domain, 0u);
  EXPECT_EQ(cfg.bridges[0].partition, "canemu");
  EXPECT_EQ(cfg.bridges[0].channel_prefix, "canemu/can0/");
  EXPECT_FALSE(cfg.bridges[0].ros2);
  EXPECT_EQ(cfg.bridges[1].domain, 7u);
  EXPECT_EQ(cfg.bridges[1].partition, "rig-a");
  EXPECT_EQ(cfg.bridges[1].channel_prefix, "robot/can1/");
  EXPECT_TRUE(cfg.bridges[1].ros2);
  EXPECT_EQ(cfg.bridges[1].restart_ms, 100u);

  const auto e = config_errors(
      std::string(kClassic) + "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\n" +
          bridge_table("dds", "can0",
                       "domain = 233\npartition = \"a*\"\ntopic_prefix = \"1x\"\nros2 = 1\n"
                       "interface = \"vcan0\"\n") +
          bridge_table("dds", "can0") + bridge_table("dds", "lin0") +
          bridge_table("ddx", "can0", "interface = \"vcan1\"\n"),
      "bad.toml");
  std::string all;
  for (const auto& line : e) {
    all += line + "\n";
  }
  for (const char* part : {"bridge[0].domain", "\"a*\" is not a partition",
                           "\"1x\" is not a topic prefix", "bridge[0].ros2: must be true or false",
                           "bridge[0].interface", "another DDS bridge joins \"can0\" already",
                           "\"lin0\" is a LIN bus; DDS bridges join CAN buses",
                           "\"ddx\" is not a bridge kind (socketcan, lcm, dds)"}) {
    EXPECT_NE(all.find(part), std::string::npos) << part << " not in:\n" << all;
  }
}

// ROS 2's Frame has no form for CAN FD: of a CAN FD and a classic frame, only the classic one
// is on its topic.
TEST(DdsBridge, Ros2TopicsCarryOnlyTheClassicFramesOfACanFdBus) {
  auto sim = world(kFd);
  auto b = sim->add_bridge(dds_bridge("fd0", true));
  ASSERT_TRUE(b) << error_text(b);
  Bridge& bridge = **b;
  Peer peer;
  const dds_entity_t ros =
      peer.reader(&can_msgs_msg_dds__Frame__desc, "rt/fd0/from_can_bus", false);
  const dds_entity_t tx = peer.writer(&canemu_dds_Frame_desc, "canemu/fd0/tx");
  BusNode ecu(*sim, 0);
  const auto f = published<canemu_dds_Frame>("7AB##1A0A1A2A3A4A5A6A7A8A9AAAB");
  ASSERT_EQ(dds_write(tx, &f), DDS_RETCODE_OK);
  kick_when_rung(bridge);
  run_to(*sim, 1'000'000);
  ecu.send(0x10, {1, 2}, false);  // a classic frame on the CAN FD bus after it
  run_to(*sim, 2'000'000);
  EXPECT_EQ(ecu.texts, (std::vector<std::string>{"7AB##1A0A1A2A3A4A5A6A7A8A9AAAB"}));
  await(ros, 1);
  const auto on_ros = take_all<can_msgs_msg_dds__Frame_>(ros);
  ASSERT_EQ(on_ros.size(), 1u);
  EXPECT_EQ(on_ros[0].id, 0x10u);
  EXPECT_EQ(on_ros[0].dlc, 2);
  EXPECT_EQ(bridge.stats().to_interface, 2u);
  for (auto r : on_ros) {
    dds_sample_free(&r, &can_msgs_msg_dds__Frame__desc, DDS_FREE_CONTENTS);  // frame_id
  }
}

TEST(DdsBridge, Ros2FramesBothWaysOnTheTopicsOfRos2Socketcan) {
  auto sim = world(kClassic);
  auto b = sim->add_bridge(dds_bridge("can0", true));
  ASSERT_TRUE(b) << error_text(b);
  Bridge& bridge = **b;
  EXPECT_EQ(bridge.options().url, std::to_string(test_domain()) + "/canemu+ros2");
  Peer peer;
  const dds_entity_t from =
      peer.reader(&can_msgs_msg_dds__Frame__desc, "rt/can0/from_can_bus", false);
  const dds_entity_t to = peer.writer(&can_msgs_msg_dds__Frame__desc, "rt/can0/to_can_bus", false);
  ASSERT_GT(from, 0);
  ASSERT_GT(to, 0);
  BusNode ecu(*sim, 0);

  can_msgs_msg_dds__Frame_ m{};
  m.header.frame_id = const_cast<char*>("ros");
  m.id = 0x1ABCDEF0;
  m.is_extended = true;
  m.dlc = 3;
  m.data[0] = 7;
  m.data[1] = 8;
  m.data[2] = 9;
  ASSERT_EQ(dds_write(to, &m), DDS_RETCODE_OK);
  can_msgs_msg_dds__Frame_ error_frame{};
  error_frame.header.frame_id = const_cast<char*>("ros");
  error_frame.is_error = true;  // no frame to send
  ASSERT_EQ(dds_write(to, &error_frame), DDS_RETCODE_OK);
  for (int i = 0; i < 2 && bridge.stats().received < 2; ++i) {
    kick_when_rung(bridge);
  }
  run_to(*sim, 1'000'000);
  ASSERT_EQ(ecu.received.size(), 1u);
  EXPECT_EQ(ecu.received[0].id(), 0x1ABCDEF0u);
  EXPECT_TRUE(ecu.received[0].extended());
  EXPECT_EQ(ecu.received[0].length(), 3u);
  EXPECT_EQ(ecu.received[0].data()[2], 9);
  EXPECT_EQ(bridge.stats().rejected, 1u);

  run_to(*sim, 3'000'000'000);
  ecu.send(0x42, {0xDE, 0xAD});  // from 3 s: the stamp's seconds count
  run_to(*sim, 4'000'000'000);
  await(from, 2);
  const auto got = take_all<can_msgs_msg_dds__Frame_>(from);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].id, 0x1ABCDEF0u);
  EXPECT_TRUE(got[0].is_extended);
  EXPECT_FALSE(got[0].is_rtr);
  EXPECT_FALSE(got[0].is_error);
  EXPECT_EQ(got[0].dlc, 3);
  EXPECT_EQ(got[0].data[0], 7);
  EXPECT_EQ(std::string(got[0].header.frame_id), "can0");
  EXPECT_EQ(got[0].header.stamp.sec, 0);
  EXPECT_EQ(static_cast<int64_t>(got[0].header.stamp.nanosec), ecu.at_ns.at(0));
  EXPECT_EQ(got[1].id, 0x42u);
  EXPECT_EQ(got[1].dlc, 2);
  EXPECT_EQ(got[1].data[1], 0xAD);
  // 0x42 with two bytes: 63 bits, stuff bits included, at 500 kbit/s from 3 s on (canemu calc
  // frame 042#DEAD).
  EXPECT_EQ(got[1].header.stamp.sec, 3);
  EXPECT_EQ(got[1].header.stamp.nanosec, 126'000u);
  for (auto g : got) {
    dds_sample_free(&g, &can_msgs_msg_dds__Frame__desc, DDS_FREE_CONTENTS);
  }
}

TEST(DdsBridge, TheSameTopicsInAnotherPartitionDoNotLoop) {
  auto sim = world(kTwoBuses);
  ASSERT_TRUE(sim->add_bridge(dds_bridge("can0")));
  BridgeConfig same = dds_bridge("can1");
  same.channel_prefix = "canemu/can0/";
  same.partition = "other";  // the same topics in another partition: no loop
  ASSERT_TRUE(sim->add_bridge(same));
  EXPECT_EQ(sim->bridges().size(), 2u);
  EXPECT_FALSE(sim->remove_bus_bridge(BridgeKind::lcm, "can1"));  // a DDS bridge, not LCM
  EXPECT_EQ(sim->bridges().size(), 2u);
}

// The contract (bridge_contract.hpp) through this transport.
INSTANTIATE_TYPED_TEST_SUITE_P(DdsBridge, BridgeContract, DdsAdapter);
INSTANTIATE_TYPED_TEST_SUITE_P(DdsBridge, MessageBridges, DdsAdapter);

}  // namespace
}  // namespace canemu::daemon
