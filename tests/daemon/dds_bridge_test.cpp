// The DDS bridge with a DDS participant of the test's own in the same process (Cyclone DDS
// delivers between participants of one process without the network). Each test process takes a
// domain of its own, on the loopback interface only, so tests running at once never hear each
// other. What arrives for the bridge wakes its eventfd, as in canemud's loop: the test waits on
// that descriptor (with a timeout) and then kicks the bridge. The same bridge runs between
// processes in tests/python/test_dds_bridge.py.
#include "canemu/daemon/bridges/dds_bridge.hpp"

#include <poll.h>
#include <unistd.h>

#include <cstdlib>
#include <deque>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <gtest/gtest.h>

#include "bridge_test_support.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu_dds.h"
#include "ros2_can_msgs.h"

namespace canemu::daemon {
namespace {

using namespace bridge_test;
using Node = BusNode;

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

canemu_dds_Frame frame(uint32_t id, std::vector<uint8_t> data, bool extended = false) {
  canemu_dds_Frame f{};
  f.id = id;
  f.extended = extended;
  f.dlc = static_cast<uint8_t>(data.size());
  f.len = static_cast<uint8_t>(data.size());
  std::copy(data.begin(), data.end(), f.data);
  return f;
}

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

TEST(DdsBridge, FramesFromTxGoOutOnTheBusAndEveryFrameIsPublishedWithItsExactTime) {
  auto sim = world(kClassic);
  auto b = sim->add_bridge(dds_bridge("can0"));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  EXPECT_EQ(bridge.options().channel_prefix, "canemu/can0/");
  EXPECT_EQ(bridge.options().url, std::to_string(test_domain()) + "/canemu");
  Peer peer;
  const dds_entity_t frames = peer.reader(&canemu_dds_Frame_desc, "canemu/can0/frames");
  const dds_entity_t tx = peer.writer(&canemu_dds_Frame_desc, "canemu/can0/tx");
  ASSERT_GT(frames, 0);
  ASSERT_GT(tx, 0);
  Node ecu(*sim, 0);

  const canemu_dds_Frame data = frame(0x123, {0x11, 0x22});
  ASSERT_EQ(dds_write(tx, &data), DDS_RETCODE_OK);
  canemu_dds_Frame remote{};
  remote.id = 0x12345678;
  remote.extended = true;
  remote.remote = true;
  remote.dlc = 4;
  ASSERT_EQ(dds_write(tx, &remote), DDS_RETCODE_OK);
  kick_when_rung(bridge);
  if (bridge.stats().received < 2) {
    kick_when_rung(bridge);  // the second sample rang after the first kick
  }
  run_to(*sim, 1'000'000);
  // As the LCM and SocketCAN bridges' frames from the same instant: back to back from t = 0.
  EXPECT_EQ(ecu.at_ns, (std::vector<int64_t>{124'000, 258'000}));

  ecu.send(0x321, {1, 2, 3});
  run_to(*sim, 2'000'000);
  await(frames, 3);
  const auto got = take_all<canemu_dds_Frame>(frames);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].timestamp_ns, 124'000);
  EXPECT_EQ(got[0].id, 0x123u);
  EXPECT_FALSE(got[0].extended);
  EXPECT_EQ(got[0].dlc, 2);
  EXPECT_EQ(got[0].len, 2);
  EXPECT_EQ(got[0].data[0], 0x11);
  EXPECT_EQ(got[0].data[1], 0x22);
  EXPECT_EQ(got[0].data[2], 0);
  EXPECT_TRUE(got[0].from_tx);
  EXPECT_EQ(got[1].timestamp_ns, 258'000);
  EXPECT_EQ(got[1].id, 0x12345678u);
  EXPECT_TRUE(got[1].extended);
  EXPECT_TRUE(got[1].remote);
  EXPECT_EQ(got[1].dlc, 4);
  EXPECT_EQ(got[1].len, 0);
  // From t = 1 ms: 73 bits at 500 kbit/s (canemu calc frame 321#010203).
  EXPECT_EQ(got[2].timestamp_ns, 1'000'000 + 146'000);
  EXPECT_EQ(got[2].id, 0x321u);
  EXPECT_EQ(got[2].len, 3);
  EXPECT_EQ(got[2].data[2], 3);
  EXPECT_FALSE(got[2].from_tx);

  const BridgeStats& st = bridge.stats();
  EXPECT_EQ(st.received, 2u);
  EXPECT_EQ(st.from_interface, 2u);
  EXPECT_EQ(st.to_interface, 3u);
  EXPECT_EQ(st.rejected, 0u);
  ipc::BridgeListReply list;
  fill_bridge_list(*sim, list);
  ASSERT_EQ(list.count, 1);
  EXPECT_EQ(list.bridges[0].kind, ipc::kBridgeDds);
  EXPECT_EQ(ipc::name_of(list.bridges[0].url), std::to_string(test_domain()) + "/canemu");
  EXPECT_EQ(ipc::name_of(list.bridges[0].channel_prefix), "canemu/can0/");
  EXPECT_EQ(list.bridges[0].received, 2u);
  EXPECT_EQ(list.bridges[0].to_interface, 3u);
}

TEST(DdsBridge, WhatIsNoFrameOfTheBusIsCountedNotSent) {
  auto sim = world(kClassic);
  auto b = sim->add_bridge(dds_bridge("can0"));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  Peer peer;
  const dds_entity_t tx = peer.writer(&canemu_dds_Frame_desc, "canemu/can0/tx");
  Node ecu(*sim, 0);
  canemu_dds_Frame fd = frame(0x100, {1, 2});
  fd.fd = true;  // a CAN FD frame on a classic bus
  canemu_dds_Frame disagree = frame(0x100, {1, 2});
  disagree.len = 3;  // its DLC says 2 bytes
  canemu_dds_Frame big_dlc = frame(0x100, {});
  big_dlc.dlc = 16;
  for (const canemu_dds_Frame& f : {fd, disagree, frame(0x800, {}), big_dlc}) {
    ASSERT_EQ(dds_write(tx, &f), DDS_RETCODE_OK);
  }
  for (int i = 0; i < 4 && bridge.stats().received < 4; ++i) {
    kick_when_rung(bridge);
  }
  run_to(*sim, 1'000'000);
  EXPECT_EQ(bridge.stats().received, 4u);
  EXPECT_EQ(bridge.stats().rejected, 4u);
  EXPECT_EQ(bridge.stats().from_interface, 0u);
  EXPECT_TRUE(ecu.at_ns.empty());
}

TEST(DdsBridge, CanFdFramesOnACanFdBus) {
  auto sim = world(kFd);
  auto b = sim->add_bridge(dds_bridge("fd0", true));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  Peer peer;
  const dds_entity_t frames = peer.reader(&canemu_dds_Frame_desc, "canemu/fd0/frames");
  const dds_entity_t ros =
      peer.reader(&can_msgs_msg_dds__Frame__desc, "rt/fd0/from_can_bus", false);
  const dds_entity_t tx = peer.writer(&canemu_dds_Frame_desc, "canemu/fd0/tx");
  Node ecu(*sim, 0);
  canemu_dds_Frame f{};
  f.id = 0x7AB;
  f.fd = true;
  f.brs = true;
  f.dlc = 9;  // 12 bytes
  f.len = 12;
  for (uint8_t i = 0; i < 12; ++i) {
    f.data[i] = static_cast<uint8_t>(0xA0 + i);
  }
  ASSERT_EQ(dds_write(tx, &f), DDS_RETCODE_OK);
  kick_when_rung(bridge);
  run_to(*sim, 1'000'000);
  ecu.send(0x10, {1, 2}, false);  // a classic frame on the CAN FD bus after it
  run_to(*sim, 2'000'000);
  await(frames, 2);
  const auto got = take_all<canemu_dds_Frame>(frames);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_TRUE(got[0].fd);
  EXPECT_TRUE(got[0].brs);
  EXPECT_EQ(got[0].dlc, 9);
  EXPECT_EQ(got[0].len, 12);
  EXPECT_EQ(got[0].data[11], 0xAB);
  EXPECT_EQ(got[0].timestamp_ns, ecu.at_ns.at(0));
  // ROS 2's Frame has no form for CAN FD: only the classic frame is there.
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
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  EXPECT_EQ(bridge.options().url, std::to_string(test_domain()) + "/canemu+ros2");
  Peer peer;
  const dds_entity_t from =
      peer.reader(&can_msgs_msg_dds__Frame__desc, "rt/can0/from_can_bus", false);
  const dds_entity_t to = peer.writer(&can_msgs_msg_dds__Frame__desc, "rt/can0/to_can_bus", false);
  ASSERT_GT(from, 0);
  ASSERT_GT(to, 0);
  Node ecu(*sim, 0);

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

TEST(DdsBridge, ErrorsAndStatesArePublishedAndTheNodeRestartsAfterRestartMs) {
  auto sim = world(kClassic);
  auto b = sim->add_bridge(dds_bridge("can0", false, 5));
  ASSERT_TRUE(b) << b.error();
  Bridge& bridge = **b;
  Peer peer;
  const dds_entity_t errors = peer.reader(&canemu_dds_BusError_desc, "canemu/can0/errors");
  const dds_entity_t states = peer.reader(&canemu_dds_NodeState_desc, "canemu/can0/states");
  const dds_entity_t tx = peer.writer(&canemu_dds_Frame_desc, "canemu/can0/tx");
  // Alone on the bus: no acknowledgement. 16 ACK errors take the transmitter to error-passive.
  const canemu_dds_Frame f = frame(0x123, {0x11, 0x22});
  ASSERT_EQ(dds_write(tx, &f), DDS_RETCODE_OK);
  kick_when_rung(bridge);
  run_to(*sim, 20'000'000);
  await(states, 2);
  const auto e = take_all<canemu_dds_BusError>(errors);
  auto s = take_all<canemu_dds_NodeState>(states);
  ASSERT_GE(e.size(), 16u);
  EXPECT_EQ(e[0].type, canemu_dds_ERROR_ACK);
  EXPECT_EQ(e[0].role, canemu_dds_ROLE_TRANSMITTER);
  EXPECT_EQ(std::string(e[0].field), "ACK");
  EXPECT_TRUE(e[0].in_frame);
  EXPECT_EQ(e[0].tec, 8);
  EXPECT_EQ(e[0].rec, 0);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].state, canemu_dds_STATE_WARNING);
  EXPECT_EQ(s[0].tec, 96);
  EXPECT_EQ(s[0].timestamp_ns, e[11].timestamp_ns);
  EXPECT_EQ(s[1].state, canemu_dds_STATE_PASSIVE);
  EXPECT_EQ(s[1].tec, 128);
  EXPECT_EQ(s[1].timestamp_ns, e[15].timestamp_ns);
  EXPECT_FALSE(s[1].restarted);

  const int64_t off_at = 30'000'000;
  sim->scheduler().schedule_at(model::SimTime::from_ns(off_at), [&bridge](model::SimTime) {
    model::FaultConfinement& fc = bridge.node().controller().confinement();
    fc.set_counters(model::kBusOffLimit, fc.rec());
    bridge.node().bus().counters_changed(bridge.node().node());
  });
  run_to(*sim, off_at + 5'000'000);
  await(states, 2);
  s = take_all<canemu_dds_NodeState>(states);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].state, canemu_dds_STATE_BUS_OFF);
  EXPECT_EQ(s[0].timestamp_ns, off_at);
  EXPECT_FALSE(s[0].restarted);
  EXPECT_EQ(s[1].state, canemu_dds_STATE_BUS_OFF);
  EXPECT_TRUE(s[1].restarted);
  EXPECT_EQ(s[1].timestamp_ns, off_at + 5'000'000);
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_EQ(bridge.restart().error(),
            "DDS bridge of can0 restarts already (waits for 128 x 11 recessive bits, 128 left)");
  EXPECT_EQ(bridge.stats().to_interface_dropped, 0u);
}

TEST(DdsBridge, OneDdsBridgeABusAndNoTwoOnTheSameTopics) {
  auto sim = world(std::string(kClassic) + "[[bus]]\nname = \"can1\"\n");
  ASSERT_TRUE(sim->add_bridge(dds_bridge("can0")));
  EXPECT_EQ(sim->add_bridge(dds_bridge("can0")).error(), "can0 has a DDS bridge already");
  BridgeConfig same = dds_bridge("can1");
  same.channel_prefix = "canemu/can0/";
  EXPECT_EQ(sim->add_bridge(same).error(),
            "the DDS bridge of can0 uses the topics canemu/can0/* in domain " +
                std::to_string(test_domain()) +
                ", partition canemu already (their frames would loop)");
  same.partition = "other";  // the same topics in another partition: no loop
  ASSERT_TRUE(sim->add_bridge(same));
  EXPECT_EQ(sim->add_bridge(dds_bridge("can7")).error(), "no bus is named \"can7\"");
  EXPECT_EQ(sim->bridges().size(), 2u);
  EXPECT_TRUE(sim->remove_bus_bridge(BridgeKind::dds, "can0"));
  EXPECT_FALSE(sim->remove_bus_bridge(BridgeKind::dds, "can0"));
  EXPECT_FALSE(sim->remove_bus_bridge(BridgeKind::lcm, "can1"));  // a DDS bridge, not LCM
  EXPECT_EQ(sim->bridges().size(), 1u);
}

TEST(DdsBridgeConfig, ReadsTheTableWithItsDefaultsAndNamesEveryMistake) {
  auto cfg = parse_config(std::string(kClassic) +
                              "[[bus]]\nname = \"can1\"\n"
                              "[[bridge]]\nkind = \"dds\"\nbus = \"can0\"\n"
                              "[[bridge]]\nkind = \"dds\"\nbus = \"can1\"\ndomain = 7\n"
                              "partition = \"rig-a\"\ntopic_prefix = \"robot/can1/\"\n"
                              "ros2 = true\nrestart_ms = 100\n",
                          "test.toml");
  ASSERT_TRUE(cfg) << cfg.error().front();
  ASSERT_EQ(cfg->bridges.size(), 2u);
  EXPECT_EQ(cfg->bridges[0].kind, "dds");
  EXPECT_EQ(cfg->bridges[0].domain, 0u);
  EXPECT_EQ(cfg->bridges[0].partition, "canemu");
  EXPECT_EQ(cfg->bridges[0].channel_prefix, "canemu/can0/");
  EXPECT_FALSE(cfg->bridges[0].ros2);
  EXPECT_EQ(cfg->bridges[1].domain, 7u);
  EXPECT_EQ(cfg->bridges[1].partition, "rig-a");
  EXPECT_EQ(cfg->bridges[1].channel_prefix, "robot/can1/");
  EXPECT_TRUE(cfg->bridges[1].ros2);
  EXPECT_EQ(cfg->bridges[1].restart_ms, 100u);

  const auto errors_of = [](const std::string& bridges) {
    auto bad = parse_config(
        std::string(kClassic) + "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\n" + bridges, "bad.toml");
    EXPECT_FALSE(bad);
    return bad ? std::vector<std::string>{} : bad.error();
  };
  const auto e = errors_of(
      "[[bridge]]\nkind = \"dds\"\nbus = \"can0\"\ndomain = 233\npartition = \"a*\"\n"
      "topic_prefix = \"1x\"\nros2 = 1\ninterface = \"vcan0\"\n"
      "[[bridge]]\nkind = \"dds\"\nbus = \"can0\"\n"
      "[[bridge]]\nkind = \"dds\"\nbus = \"lin0\"\n"
      "[[bridge]]\nkind = \"ddx\"\nbus = \"can0\"\ninterface = \"vcan1\"\n");
  const std::string all = [&] {
    std::string s;
    for (const auto& line : e) {
      s += line + "\n";
    }
    return s;
  }();
  EXPECT_NE(all.find("bridge[0].domain"), std::string::npos) << all;
  EXPECT_NE(all.find("\"a*\" is not a partition"), std::string::npos) << all;
  EXPECT_NE(all.find("\"1x\" is not a topic prefix"), std::string::npos) << all;
  EXPECT_NE(all.find("bridge[0].ros2: must be true or false"), std::string::npos) << all;
  EXPECT_NE(all.find("bridge[0].interface"), std::string::npos) << all;
  EXPECT_NE(all.find("another DDS bridge joins \"can0\" already"), std::string::npos) << all;
  EXPECT_NE(all.find("\"lin0\" is a LIN bus; DDS bridges join CAN buses"), std::string::npos)
      << all;
  EXPECT_NE(all.find("\"ddx\" is not a bridge kind (socketcan, lcm, dds)"), std::string::npos)
      << all;
}

}  // namespace
}  // namespace canemu::daemon
