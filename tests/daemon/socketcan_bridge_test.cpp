// The SocketCAN bridge on the host: the interface is played by one end of a SOCK_SEQPACKET pair
// (whole frames per packet, as a CAN_RAW socket gives them), the kernel's programs by the other.
// This machine's kernel has no CAN modules; the same bridge runs against vcan in tests/guest/.
#include "canemu/daemon/socketcan_bridge.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <deque>

#include <gtest/gtest.h>

#include "canemu/daemon/channel.hpp"
#include "canemu/daemon/simulation.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::daemon {
namespace {

std::unique_ptr<Simulation> world(const std::string& text) {
  auto cfg = parse_config(text, "test.toml");
  EXPECT_TRUE(cfg) << (cfg ? "" : cfg.error().front());
  auto sim = Simulation::build(*cfg);
  EXPECT_TRUE(sim) << (sim ? "" : sim.error().front());
  return std::move(*sim);
}

constexpr const char* kClassic = "[[bus]]\nname = \"can0\"\n";
constexpr const char* kFd =
    "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n";

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

// A channel-like node on the bus: acknowledges, records what it receives, sends a queue.
struct Node : model::ControllerEvents {
  std::vector<std::string> received;
  std::vector<int64_t> at_ns;
  std::deque<model::Frame> queue;
  model::HostedNode* node = nullptr;
  Node(Simulation& sim, std::size_t bus) {
    node = &sim.spare_node(bus);
    node->start(*sim.bus_timing(bus), this, [this]() -> std::optional<model::TxFrame> {
      if (queue.empty()) {
        return std::nullopt;
      }
      model::TxFrame f{queue.front()};
      queue.pop_front();
      return f;
    });
  }
  void frame_received(model::SimTime at, const model::Frame& f, bool) override {
    const auto s = ipc::socketcan::from_message(to_message(at, f, ipc::ChannelMessageKind::frame));
    received.push_back(ipc::socketcan::candump_text(*s));
    at_ns.push_back(at.ns());
  }
  void send(const std::string& cansend) {
    std::string error;
    const auto m = ipc::socketcan::to_message(Interface::parse(cansend), error);
    queue.push_back(to_tx_frame(*m)->frame);
    node->kick();
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
  const auto slow = controller_timing(false, 250'000, 250'000, 875);
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
  auto port = open_can_raw("vcan-none", false);
  ASSERT_FALSE(port);
  // Either the kernel has no CAN (socket fails) or the interface does not exist.
  EXPECT_EQ(port.error().substr(0, 11), "vcan-none: ") << port.error();
  EXPECT_EQ(open_can_raw("a-name-that-is-too-long", false).error(),
            "\"a-name-that-is-too-long\" is not an interface name (1 to 15 characters)");
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
  auto bad = parse_config(std::string(kClassic) +
                              "[[bridge]]\nkind = \"lcm\"\nbus = \"can9\"\ninterface = \"vcan0\"\n"
                              "[[bridge]]\nkind = \"socketcan\"\nbus = \"can0\"\n"
                              "interface = \"vcan0\"\nloop = 1\n",
                          "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(),
            (std::vector<std::string>{
                "t.toml:4:8: bridge[0].kind: \"lcm\" is not a bridge kind (socketcan)",
                "t.toml:5:7: bridge[0].bus: no bus is named \"can9\"",
                "t.toml:11:1: bridge[1].loop: unknown key (known here: kind, bus, interface, "
                "error_frames)",
                "t.toml:10:13: bridge[1].interface: another bridge uses \"vcan0\" already (its "
                "frames would loop)"}));
}

}  // namespace
}  // namespace canemu::daemon
