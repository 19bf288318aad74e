// The SocketCAN bridge on the host: the interface is played by one end of a SOCK_SEQPACKET pair
// (whole frames per packet, as a CAN_RAW socket gives them), the kernel's programs by the other.
// This machine's kernel has no CAN modules; the same bridge runs against vcan in tests/guest/.
#include "canemu/daemon/bridges/socketcan_bridge.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <deque>
#include <fstream>
#include <iterator>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "bridge_test_support.hpp"
#include "canemu/daemon/base/channel.hpp"
#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::daemon {
namespace {

using namespace bridge_test;

// The kernel side: what programs write on the interface and what they read from it.
struct Interface {
  ipc::UniqueFd kernel;
  ipc::UniqueFd bridge;
  Interface() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds), 0);
    kernel.reset(fds[0]);
    bridge.reset(fds[1]);
  }
  void write_frame(const ipc::socketcan::Frame& f) {
    const auto bytes = ipc::socketcan::to_struct(f);
    EXPECT_EQ(::send(kernel.get(), bytes.data(), bytes.size(), 0),
              static_cast<ssize_t>(bytes.size()));
  }
  void write_text(const std::string& cansend) {
    // cansend's syntax through the shared parser's inverse: build the frame by hand.
    write_frame(parse(cansend));
  }
  static ipc::socketcan::Frame parse(const std::string& text) {
    ipc::socketcan::Frame f;
    const std::size_t hash = text.find('#');
    f.can_id = static_cast<uint32_t>(std::stoul(text.substr(0, hash), nullptr, 16));
    if (hash == 8) {
      f.can_id |= CAN_EFF_FLAG;
    }
    std::string rest = text.substr(hash + 1);
    if (!rest.empty() && rest[0] == '#') {
      f.fd = true;
      f.flags = static_cast<uint8_t>(CANFD_FDF | std::stoul(rest.substr(1, 1), nullptr, 16));
      rest = rest.substr(2);
    } else if (!rest.empty() && rest[0] == 'R') {
      f.can_id |= CAN_RTR_FLAG;
      f.len = rest.size() > 1 ? static_cast<uint8_t>(rest[1] - '0') : 0;
      return f;
    }
    for (std::size_t i = 0; i + 1 < rest.size(); i += 2) {
      f.data[f.len++] = static_cast<uint8_t>(std::stoul(rest.substr(i, 2), nullptr, 16));
    }
    return f;
  }
  // Everything the bridge wrote, as candump would print it.
  std::vector<std::string> read_all() {
    std::vector<std::string> out;
    uint8_t buf[128];
    ssize_t n;
    while ((n = ::recv(kernel.get(), buf, sizeof buf, 0)) > 0) {
      const auto f = ipc::socketcan::from_struct(buf, static_cast<std::size_t>(n));
      out.push_back(f ? ipc::socketcan::candump_text(*f) : "(" + std::to_string(n) + " bytes)");
    }
    return out;
  }
};

// A channel-like node on the bus (bridge_test_support.hpp) that receives and sends in
// candump's text.
struct Node : BusNode {
  std::vector<std::string> received;
  Node(Simulation& sim, std::size_t bus) : BusNode(sim, bus) {}
  void frame_received(model::SimTime at, const model::Frame& f, bool own) override {
    BusNode::frame_received(at, f, own);
    const auto s = ipc::socketcan::from_message(to_message(at, f, ipc::ChannelMessageKind::frame));
    received.push_back(ipc::socketcan::candump_text(*s));
  }
  void send(const std::string& cansend) {
    std::string error;
    const auto m = ipc::socketcan::to_message(Interface::parse(cansend), error);
    BusNode::send(to_tx_frame(*m)->frame);
  }
};

void run_for(Simulation& sim, int64_t ns) {
  sim.scheduler().run_until(sim.scheduler().now() + model::SimDuration(ns));
}

TEST(SocketCanBridge, FramesFromTheInterfaceGoOutOnTheBusWithTheirExactTime) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b) << b.error();
  Node ecu(*sim, 0);
  vcan.write_text("123#1122");
  vcan.write_text("12345678#R4");
  vcan.write_text("7FF#");
  (*b)->kick();  // the socket was readable
  run_for(*sim, 1'000'000);
  EXPECT_EQ(ecu.received, (std::vector<std::string>{"123#1122", "12345678#R4", "7FF#"}));
  // Back to back from t = 0: 62 bits (124 us), then 3 + 64 bits, as canemu send shows them.
  EXPECT_EQ(ecu.at_ns[0], 124'000);
  EXPECT_EQ(ecu.at_ns[1], 258'000);
  EXPECT_EQ((*b)->stats().from_interface, 3u);
  // Nothing came back to the interface: the bridge does not receive its own frames.
  EXPECT_TRUE(vcan.read_all().empty());
}

TEST(SocketCanBridge, FramesOfTheBusGoToTheInterface) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  Node ecu(*sim, 0);
  ecu.send("321#DEADBEEF");
  ecu.send("1FFFFFFF#R");
  run_for(*sim, 1'000'000);
  EXPECT_EQ(vcan.read_all(), (std::vector<std::string>{"321#DEADBEEF", "1FFFFFFF#R"}));
  EXPECT_EQ((*b)->stats().to_interface, 2u);
}

TEST(SocketCanBridge, CanFdBothWaysOnAnFdBus) {
  auto sim = world(kFd);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "fd0", "vcan0", false, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  Node ecu(*sim, 0);
  vcan.write_text("123##1000102030405060708090A0B");  // BRS, 12 bytes
  (*b)->kick();
  ecu.send("456##3AABB");  // BRS, and ESI asked for
  run_for(*sim, 2'000'000);
  EXPECT_EQ(ecu.received, (std::vector<std::string>{"123##1000102030405060708090A0B"}));
  // ESI is what the wire carried: the transmitter's error state (error-active: dominant).
  EXPECT_EQ(vcan.read_all(), (std::vector<std::string>{"456##1AABB"}));
}

TEST(SocketCanBridge, WhatTheBusCannotCarryIsCountedNotSent) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  Node ecu(*sim, 0);
  vcan.write_text("123##1AABB");  // CAN FD on a classic bus
  ipc::socketcan::Frame err;
  err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  err.len = 8;
  vcan.write_frame(err);
  const char junk[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(::send(vcan.kernel.get(), junk, sizeof junk, 0), 5);
  (*b)->kick();
  run_for(*sim, 1'000'000);
  EXPECT_TRUE(ecu.received.empty());
  EXPECT_EQ((*b)->stats().rejected, 3u);
  EXPECT_EQ((*b)->stats().from_interface, 0u);
}

// What the bridge makes of each read from the interface, for a classic and a CAN FD bus: the
// frame, or the frame and the rule it breaks.
TEST(SocketCanBridge, EachReadFromTheInterfaceIsAFrameOrARejectionWithItsReason) {
  const auto read = [](const ipc::socketcan::Frame& f, bool fd_bus, uint8_t raw_len = 0xFF) {
    auto bytes = ipc::socketcan::to_struct(f);
    if (raw_len != 0xFF) {
      bytes[4] = raw_len;  // what a program may write, beyond what a Frame holds
    }
    return frame_from_interface(bytes.data(), bytes.size(), fd_bus);
  };
  const auto fd = Interface::parse("123##1AABB");
  EXPECT_EQ(read(fd, false).error().detail,
            "the CAN FD frame 123##1AABB (the bus is a classic CAN bus)");
  EXPECT_EQ(read(fd, false).error().why, BridgeReject::fd_on_classic);
  ASSERT_TRUE(read(fd, true));
  EXPECT_EQ(read(fd, true)->dlc, 2);
  ipc::socketcan::Frame err;
  err.can_id = CAN_ERR_FLAG | CAN_ERR_PROT | CAN_ERR_BUSERROR;
  err.len = 8;
  err.data[2] = CAN_ERR_PROT_BIT;
  const std::string err_reason =
      "the error frame 20000088#0000010000000000 (an error frame reports what a controller saw; "
      "it is no frame to send on a bus)";
  EXPECT_EQ(read(err, false).error().detail, err_reason);
  EXPECT_EQ(read(err, true).error().detail, err_reason);
  EXPECT_EQ(read(err, true).error().why, BridgeReject::error_frame);
  const uint8_t junk[5] = {1, 2, 3, 4, 5};
  EXPECT_EQ(frame_from_interface(junk, sizeof junk, false).error().detail,
            "a read of 5 bytes, neither a struct can_frame (16) nor a canfd_frame (72)");
  EXPECT_EQ(frame_from_interface(junk, sizeof junk, false).error().why, BridgeReject::not_a_frame);
  auto classic = Interface::parse("123#0102030405060708");
  EXPECT_EQ(read(classic, false, 9).error().detail,
            "123#0102030405060708 (its length 9 is above 8)");
  EXPECT_EQ(read(classic, false, 9).error().why, BridgeReject::bad_fields);
  auto long_fd = Interface::parse("123##1AABB");
  EXPECT_EQ(read(long_fd, true, 65).error().detail.substr(0, 10), "123##1AABB");
  EXPECT_NE(read(long_fd, true, 65).error().detail.find("(its length 65 is above 64)"),
            std::string::npos);
  auto remote_fd = fd;
  remote_fd.can_id |= CAN_RTR_FLAG;
  EXPECT_EQ(read(remote_fd, true).error().detail, "123##1AABB (CAN FD has no remote frames)");
  // A CAN FD length between two DLCs' lengths: the next DLC, zeros up to its length.
  auto odd = Interface::parse("123##101020304050607080910111213");  // 13 bytes
  odd.data[13] = 0x77;
  const auto padded = read(odd, true);
  ASSERT_TRUE(padded) << padded.error().detail;
  EXPECT_EQ(padded->dlc, 10);  // 16 bytes
  EXPECT_EQ(padded->data[12], 0x13);
  EXPECT_EQ(padded->data[13], 0);
}

// Rejections are counted by reason, kept with the last one's details, and logged with the
// reason, at most RejectLog's burst of lines in its window (wall-clock: the journal's concern).
TEST(SocketCanBridge, RejectionsAreCountedByReasonAndLoggedRateLimited) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  Node ecu(*sim, 0);
  log::Capture log;
  run_to(*sim, 1'000'000);
  vcan.write_text("123##1AABB");  // CAN FD on a classic bus
  ipc::socketcan::Frame err;
  err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  err.len = 8;
  vcan.write_frame(err);
  for (int i = 0; i < 5; ++i) {
    vcan.write_text("124##0");
  }
  vcan.write_text("125#01");  // a frame: sent
  (*b)->kick();
  run_to(*sim, 2'000'000);
  EXPECT_EQ((*b)->stats().rejected, 7u);
  EXPECT_EQ((*b)->stats().received, 8u);
  EXPECT_EQ(ecu.received, (std::vector<std::string>{"125#01"}));
  const auto& r = (*b)->rejections();
  EXPECT_EQ(r.count(static_cast<std::size_t>(BridgeReject::fd_on_classic)), 6u);
  EXPECT_EQ(r.count(static_cast<std::size_t>(BridgeReject::error_frame)), 1u);
  EXPECT_EQ(r.last(), "rejected the CAN FD frame 124##0 (the bus is a classic CAN bus)");
  const auto lines = log.lines();
  ASSERT_EQ(lines.size(), static_cast<std::size_t>(RejectLog<kBridgeRejectReasons>::kBurst));
  EXPECT_EQ(lines[0],
            "<4>canemud: bridge on vcan0: rejected the CAN FD frame 123##1AABB (the bus is a "
            "classic CAN bus)");
  EXPECT_EQ(lines[1],
            "<4>canemud: bridge on vcan0: rejected the error frame 20000040#0000000000000000 (an "
            "error frame reports what a controller saw; it is no frame to send on a bus)");
}

// A CAN FD bus on an interface whose MTU is not CANFD_MTU: a warning with the way out.
TEST(SocketCanBridge, AnFdBusOnAClassicMtuInterfaceIsWarnedAbout) {
  EXPECT_EQ(mtu_warning("vcan0", "fd0", true, 16),
            "vcan0 has MTU 16, not 72 (CAN FD): the CAN FD frames of fd0 cannot be written to "
            "it (counted as IF-DROP) and programs cannot send CAN FD frames on it; classic frames "
            "pass. For CAN FD: ip link set vcan0 down; ip link set vcan0 mtu 72 up");
  EXPECT_EQ(mtu_warning("vcan0", "fd0", true, 72), std::nullopt);
  EXPECT_EQ(mtu_warning("vcan0", "can0", false, 16), std::nullopt);
  EXPECT_EQ(mtu_warning("vcan0", "can0", false, 72), std::nullopt);  // FD frames: rejected
}

TEST(SocketCanBridge, AFullQueueDropsAndCountsWhatTheBusCouldNotTake) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  Node ecu(*sim, 0);
  // 1100 frames written at one instant: the first goes on the wire, 1024 wait, the rest drop.
  for (int i = 0; i < 1100; ++i) {
    vcan.write_text("100#");
    if (i % 100 == 99) {
      (*b)->kick();  // the socket pair holds a few hundred packets; read as the loop would
    }
  }
  for (int i = 0; i < 8; ++i) {
    (*b)->kick();
  }
  EXPECT_EQ((*b)->stats().queue_dropped, 1100u - 1 - 1024);
  run_for(*sim, 1'000'000'000);
  EXPECT_EQ((*b)->stats().from_interface, 1025u);
  EXPECT_EQ(ecu.received.size(), 1025u);
}

TEST(SocketCanBridge, ErrorFramesOnlyWhenAskedFor) {
  auto sim = world(kClassic);
  Interface quiet;
  Interface loud;
  // Two bridges of one bus on two interfaces, one with error frames. A node at 250 kbit/s on
  // the 500 kbit/s bus makes errors that both bridges' nodes detect.
  ASSERT_TRUE(sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(quiet.bridge)));
  auto b = sim->add_bridge({"socketcan", "can0", "vcan1", true, 0}, std::move(loud.bridge));
  ASSERT_TRUE(b);
  model::HostedNode& wrong = sim->spare_node(0);
  const auto slow = node_timing(false, {250'000, 0, 875});
  bool sent = false;
  wrong.start(*slow, nullptr, [&]() -> std::optional<model::TxFrame> {
    if (sent) {
      return std::nullopt;
    }
    sent = true;
    model::FrameSpec spec;
    spec.id = 0x100;
    return model::TxFrame{*model::Frame::create(spec), true};
  });
  wrong.kick();
  run_for(*sim, 2'000'000);
  EXPECT_TRUE(quiet.read_all().empty());
  const auto errors = loud.read_all();
  ASSERT_FALSE(errors.empty());
  for (const std::string& e : errors) {
    EXPECT_EQ(e.substr(0, 3), "200") << e;  // CAN_ERR_FLAG
    EXPECT_EQ(e.size(), 8u + 1 + 16) << e;  // 8 data bytes
  }
  EXPECT_EQ((*b)->stats().error_frames, errors.size());
}

// A CRC error is flagged where ISO 11898-1 has the receiver flag it, after the ACK delimiter
// (the receiver finds the mismatch in the CRC sequence but starts its error flag at the bit
// after the ACK delimiter): the SJA1000's error code capture records that segment (0x1B), and
// the error frame carries it in data[3] as CAN_ERR_PROT_LOC_ACK_DEL, as Linux's sja1000 driver
// copies it. docs/socketcan.md's error frame table says the same.
TEST(SocketCanBridge, ACrcErrorFrameCarriesTheAckDelimiterAsItsLocation) {
  auto sim = world(kClassic);
  auto scenario = parse_scenario(
      "[[fault]]\nat = \"0s\"\nbus = \"can0\"\nmatch = { id = 0x321 }\neffect = "
      "\"crc_error\"\ncount = 1\n",
      "s.toml");
  ASSERT_TRUE(scenario) << scenario.error().front();
  ASSERT_TRUE(sim->scenarios().apply(*scenario, model::SimTime{}));
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", true, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  Node ecu(*sim, 0);
  ecu.send("321#AB");
  run_for(*sim, 2'000'000);
  const std::vector<std::string> written = vcan.read_all();
  ASSERT_GE(written.size(), 2u);
  // The error frame (a receiver's CRC error: no type bits, not transmitting), then the frame's
  // retransmission.
  const std::string& crc = written.front();
  EXPECT_EQ(crc.substr(0, 9), "20000288#") << crc;
  EXPECT_EQ(crc.substr(9 + 2 * 2, 4), fmt::format("{:02X}{:02X}", 0, CAN_ERR_PROT_LOC_ACK_DEL))
      << crc;
  EXPECT_EQ(CAN_ERR_PROT_LOC_ACK_DEL, 0x1B);
  EXPECT_EQ(written.back(), "321#AB");
  std::ifstream docs(std::string(CANEMU_SOURCE_DIR) + "/docs/socketcan.md");
  std::string line, row;
  while (std::getline(docs, line)) {
    if (line.starts_with("| CRC error |")) {
      row = line;
    }
  }
  EXPECT_NE(row.find("`data[3]` `CAN_ERR_PROT_LOC_ACK_DEL` (0x1B)"), std::string::npos) << row;
  EXPECT_EQ(row.find("CRC_SEQ"), std::string::npos) << row;
}

// ---- restarts after bus-off

// The node's TEC set above 255 at `at_ns`, as the `bus_off` fault effect does it.
void bus_off_at(Simulation& sim, model::HostedNode& node, int64_t at_ns) {
  sim.scheduler().schedule_at(model::SimTime::from_ns(at_ns), [&node](model::SimTime) {
    model::FaultConfinement& fc = node.controller().confinement();
    fc.set_counters(model::kBusOffLimit, fc.rec());
    node.bus().counters_changed(node.node());
  });
}

void run_to(Simulation& sim, int64_t ns) {
  sim.scheduler().run_until(model::SimTime::from_ns(ns));
}

// 128 sequences of 11 recessive bits at 500 kbit/s (2 us a bit), on an idle bus.
constexpr int64_t kRecoveryNs = 128 * 11 * 2'000;

TEST(SocketCanBridge, RestartsRestartMsAfterBusOffThenWaitsForTheRecessiveBits) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", true, 5}, std::move(vcan.bridge));
  ASSERT_TRUE(b) << b.error();
  SocketCanBridge& bridge = **b;
  Node ecu(*sim, 0);
  const model::FaultConfinement& fc = bridge.node().controller().confinement();
  bus_off_at(*sim, bridge.node(), 1'000'000);
  run_to(*sim, 2'000'000);
  ASSERT_TRUE(fc.bus_off());
  vcan.write_text("123#1122");  // waits for the node
  bridge.kick();
  run_to(*sim, 1'000'000 + 5'000'000 - 1);
  EXPECT_EQ(bridge.stats().restarts, 0u);
  EXPECT_FALSE(fc.recovering());
  run_to(*sim, 6'000'000);  // exactly restart_ms after the bus-off instant
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_TRUE(fc.recovering());
  run_to(*sim, 6'000'000 + kRecoveryNs - 1);
  EXPECT_TRUE(fc.bus_off());
  run_to(*sim, 6'000'000 + kRecoveryNs);
  EXPECT_FALSE(fc.bus_off());
  EXPECT_EQ(fc.tec(), 0);
  // Then the queued frame goes: 62 bits from the recovery's end.
  run_to(*sim, 10'000'000);
  EXPECT_EQ(ecu.received, (std::vector<std::string>{"123#1122"}));
  EXPECT_EQ(ecu.at_ns, (std::vector<int64_t>{6'000'000 + kRecoveryNs + 124'000}));
  // Bus-off, the kernel's restart frame, error-active again.
  EXPECT_EQ(vcan.read_all(),
            (std::vector<std::string>{"20000240#000000000000FF00", "20000100#0000000000000000",
                                      "20000204#0040000000000000"}));
  EXPECT_EQ(bridge.stats().error_frames, 3u);
  EXPECT_EQ(bridge.stats().from_interface, 1u);
}

TEST(SocketCanBridge, TheCanFdControllerRestartsTheSameWay) {
  auto sim = world(kFd);  // 500 kbit/s arbitration: the same recovery time
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "fd0", "vcan0", false, 2}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  const model::FaultConfinement& fc = (*b)->node().controller().confinement();
  bus_off_at(*sim, (*b)->node(), 500'000);
  run_to(*sim, 2'500'000 - 1);
  EXPECT_EQ((*b)->stats().restarts, 0u);
  run_to(*sim, 2'500'000);
  EXPECT_EQ((*b)->stats().restarts, 1u);
  run_to(*sim, 2'500'000 + kRecoveryNs - 1);
  EXPECT_TRUE(fc.bus_off());
  run_to(*sim, 2'500'000 + kRecoveryNs);
  EXPECT_FALSE(fc.bus_off());
}

TEST(SocketCanBridge, WithoutRestartMsTheNodeStaysBusOffUntilRestartedByHand) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  SocketCanBridge& bridge = **b;
  const model::FaultConfinement& fc = bridge.node().controller().confinement();
  EXPECT_EQ(bridge.restart().error(),
            "bridge on vcan0 is error-active, not bus-off: nothing to restart");
  bus_off_at(*sim, bridge.node(), 1'000'000);
  run_to(*sim, 1'000'000'000);  // a second: still bus-off
  EXPECT_TRUE(fc.bus_off());
  EXPECT_FALSE(fc.recovering());
  EXPECT_TRUE(bridge.restart());
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_EQ(bridge.restart().error(),
            "bridge on vcan0 restarts already (waits for 128 x 11 recessive bits, 128 left)");
  EXPECT_EQ(bridge.stats().restarts, 1u);
  run_to(*sim, 1'000'000'000 + kRecoveryNs);
  EXPECT_FALSE(fc.bus_off());
  EXPECT_TRUE(vcan.read_all().empty());  // no error frames asked for
  ipc::BridgeListReply list{};
  fill_bridge_list(*sim, list);
  ASSERT_EQ(list.count, 1);
  EXPECT_EQ(list.bridges[0].restarts, 1u);
  EXPECT_EQ(list.bridges[0].restart_ms, 0u);
}

TEST(SocketCanBridge, ARestartByHandBeforeTheTimerCountsOnce) {
  auto sim = world(kClassic);
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", false, 100}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  SocketCanBridge& bridge = **b;
  bus_off_at(*sim, bridge.node(), 1'000'000);
  run_to(*sim, 2'000'000);
  EXPECT_TRUE(bridge.restart());
  run_to(*sim, 200'000'000);  // past the timer's 101 ms
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_FALSE(bridge.node().controller().confinement().bus_off());
  // Removing a bridge whose timer is due cancels it.
  bus_off_at(*sim, bridge.node(), 300'000'000);
  run_to(*sim, 301'000'000);
  EXPECT_TRUE(sim->remove_bridge("vcan0"));
  run_to(*sim, 500'000'000);
}

// A real way there: a fault rule gives every transmission of 123h a bit error, 32 of them take
// the bridge's node from TEC 0 to 256 (8 each), and restart_ms later the node restarts,
// recovers and sends the frame its transmit buffer kept (the SJA1000 keeps a request through
// bus-off) and what waited in the bridge's queue.
TEST(SocketCanBridge, BitErrorsDriveTheNodeBusOffAndItRestartsAfterRestartMs) {
  auto sim = world(kClassic);
  auto scenario = parse_scenario(
      "[[fault]]\nat = \"0s\"\nbus = \"can0\"\nmatch = { id = 0x123 }\neffect = "
      "\"bit_error\"\ncount = 32\n",
      "s.toml");
  ASSERT_TRUE(scenario) << scenario.error().front();
  ASSERT_TRUE(sim->scenarios().apply(*scenario, model::SimTime{}));
  Interface vcan;
  auto b = sim->add_bridge({"socketcan", "can0", "vcan0", true, 20}, std::move(vcan.bridge));
  ASSERT_TRUE(b);
  SocketCanBridge& bridge = **b;
  Node ecu(*sim, 0);
  vcan.write_text("123#01");
  vcan.write_text("124#02");
  bridge.kick();
  const model::FaultConfinement& fc = bridge.node().controller().confinement();
  // In steps of 1 us: the step that sees bus-off, and the one that sees the restart, which
  // must be exactly 20 ms (20000 steps) later.
  int64_t step = 0;
  while (!fc.bus_off() && step < 100'000) {
    run_to(*sim, ++step * 1'000);
  }
  ASSERT_TRUE(fc.bus_off());
  const int64_t bus_off_step = step;
  EXPECT_TRUE(ecu.received.empty());
  while (bridge.stats().restarts == 0 && step < bus_off_step + 100'000) {
    run_to(*sim, ++step * 1'000);
  }
  EXPECT_EQ(step, bus_off_step + 20'000);
  run_to(*sim, step * 1'000 + kRecoveryNs + 1'000'000);
  EXPECT_FALSE(fc.bus_off());
  EXPECT_EQ(ecu.received, (std::vector<std::string>{"123#01", "124#02"}));
  EXPECT_EQ(bridge.stats().from_interface, 2u);
  EXPECT_EQ(bridge.stats().tx_failed, 0u);
  const std::vector<std::string> errors = vcan.read_all();
  ASSERT_GE(errors.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(errors.end() - 3, errors.end()),
            (std::vector<std::string>{"20000240#000000000000FF00", "20000100#0000000000000000",
                                      "20000204#0040000000000000"}));
  EXPECT_EQ(std::count(errors.begin(), errors.end(), "20000100#0000000000000000"), 1);
  EXPECT_EQ(bridge.stats().restarts, 1u);
}

TEST(SocketCanBridge, TwoBridgesOnOneInterfaceAreRefused) {
  auto sim = world(kClassic);
  Interface a;
  Interface c;
  ASSERT_TRUE(sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(a.bridge)));
  auto again = sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(c.bridge));
  ASSERT_FALSE(again);
  EXPECT_EQ(again.error(), "vcan0 is bridged to can0 already (its frames would loop)");
  EXPECT_EQ(sim->add_bridge({"socketcan", "can7", "vcan3", false, 0}, ipc::UniqueFd()).error(),
            "no bus is named \"can7\"");
  EXPECT_TRUE(sim->remove_bridge("vcan0"));
  EXPECT_FALSE(sim->remove_bridge("vcan0"));
  EXPECT_TRUE(sim->bridges().empty());
}

TEST(SocketCanBridge, WithoutCanModulesTheInterfaceCannotBeOpenedAndSaysWhy) {
  auto port = open_can_raw("vcan-none");
  ASSERT_FALSE(port);
  // Either the kernel has no CAN (socket fails) or the interface does not exist.
  EXPECT_EQ(port.error().text.substr(0, 11), "vcan-none: ") << port.error();
  EXPECT_EQ(open_can_raw("a-name-that-is-too-long").error(),
            "\"a-name-that-is-too-long\" is not an interface name (1 to 15 characters)");
}

// socket() of any family but AF_UNIX fails with EAFNOSUPPORT from now on, as in canemud.service
// as shipped (RestrictAddressFamilies=AF_UNIX installs such a seccomp filter).
void refuse_every_family_but_unix() {
  sock_filter filter[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_socket, 0, 3),
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, args[0])),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AF_UNIX, 1, 0),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EAFNOSUPPORT),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
  };
  sock_fprog program{static_cast<unsigned short>(std::size(filter)), filter};
  if (::prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 ||
      ::prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &program) != 0) {
    ::_exit(2);
  }
}

TEST(SocketCanBridge, ABridgeWhoseAddressFamilyIsRefusedNamesTheDropInThatAllowsIt) {
  EXPECT_TRUE(refused_family(AF_INET));  // this machine allows IP sockets
  int out[2];
  ASSERT_EQ(::pipe(out), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // no gtest here: what the child found goes through the pipe
    refuse_every_family_but_unix();
    auto sim = world(kClassic);
    BridgeConfig lcm;
    lcm.kind = "lcm";
    lcm.bus = "can0";
    BridgeConfig dds = lcm;
    dds.kind = "dds";
    const std::string found = std::string(!refused_family(AF_UNIX) ? "AF_UNIX refused" : "-") +
                              "\n" + open_can_raw("vcan0").error().what() + "\n" +
                              sim->add_bridge(lcm).error().what() + "\n" +
                              sim->add_bridge(dds).error().what();
    const bool written =
        ::write(out[1], found.data(), found.size()) == static_cast<ssize_t>(found.size());
    ::_exit(written ? 0 : 3);
  }
  ::close(out[1]);
  std::string found;
  char buffer[512];
  for (ssize_t n; (n = ::read(out[0], buffer, sizeof buffer)) > 0;) {
    found.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(out[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_EQ(found,
            "-\n"
            "vcan0: AF_CAN refused (no CAN in the kernel, or no drop-in socketcan.conf)\n"
            "LCM bridge of can0: AF_INET refused (no drop-in ip.conf)\n"
            "DDS bridge of can0: AF_INET refused (no drop-in ip.conf)");
}

TEST(BridgeConfig, ReadsTheTableAndNamesEveryMistake) {
  auto cfg = parse_config(std::string(kClassic) +
                              "[[bridge]]\nkind = \"socketcan\"\nbus = \"can0\"\n"
                              "interface = \"vcan0\"\nerror_frames = true\n",
                          "t.toml");
  ASSERT_TRUE(cfg) << cfg.error().front();
  ASSERT_EQ(cfg->bridges.size(), 1u);
  EXPECT_EQ(cfg->bridges[0].interface, "vcan0");
  EXPECT_TRUE(cfg->bridges[0].error_frames);
  EXPECT_EQ(cfg->bridges[0].restart_ms, 0u);
  auto restarting = parse_config(std::string(kClassic) +
                                     "[[bridge]]\nkind = \"socketcan\"\nbus = \"can0\"\n"
                                     "interface = \"vcan0\"\nrestart_ms = 100\n",
                                 "t.toml");
  ASSERT_TRUE(restarting) << restarting.error().front();
  EXPECT_EQ(restarting->bridges[0].restart_ms, 100u);
  auto wrong = parse_config(std::string(kClassic) +
                                "[[bridge]]\nkind = \"socketcan\"\nbus = \"can0\"\n"
                                "interface = \"vcan0\"\nrestart_ms = -1\n"
                                "[[bridge]]\nkind = \"socketcan\"\nbus = \"can0\"\n"
                                "interface = \"vcan1\"\nrestart_ms = 60001\n"
                                "[[bridge]]\nkind = \"socketcan\"\nbus = \"can0\"\n"
                                "interface = \"vcan2\"\nrestart_ms = \"100ms\"\n",
                            "t.toml");
  ASSERT_FALSE(wrong);
  EXPECT_EQ(wrong.error(), (std::vector<std::string>{
                               "t.toml:7:14: bridge[0].restart_ms: -1 is outside 0..60000",
                               "t.toml:12:14: bridge[1].restart_ms: 60001 is outside 0..60000",
                               "t.toml:17:14: bridge[2].restart_ms: must be an integer"}));
  auto bad = parse_config(std::string(kClassic) +
                              "[[bridge]]\nkind = \"zmq\"\nbus = \"can9\"\ninterface = \"vcan0\"\n"
                              "[[bridge]]\nkind = \"socketcan\"\nbus = \"can0\"\n"
                              "interface = \"vcan0\"\nloop = 1\n",
                          "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(),
            (std::vector<std::string>{
                "t.toml:4:8: bridge[0].kind: \"zmq\" is not a bridge kind (socketcan, lcm, dds)",
                "t.toml:5:7: bridge[0].bus: no bus is named \"can9\"",
                "t.toml:11:1: bridge[1].loop: unknown key (known here: kind, bus, interface, "
                "error_frames, restart_ms)",
                "t.toml:10:13: bridge[1].interface: another bridge uses \"vcan0\" already (its "
                "frames would loop)"}));
}

}  // namespace
}  // namespace canemu::daemon
