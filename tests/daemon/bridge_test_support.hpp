// What the bridge tests (SocketCAN, LCM, DDS) share: a simulation of a configuration text, a
// node on the bus like a channel's that acknowledges, sends what it is given and records what it
// receives with its simulated instant, frames written as cansend and candump write them, and a
// node driven bus-off. bridge_contract.hpp holds what every bridge does, run through each.
#pragma once

#include <linux/can.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "canemu/daemon/base/channel.hpp"
#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/ipc/socketcan.hpp"
#include "daemon_test_support.hpp"

namespace canemu::daemon::bridge_test {

using daemon_test::error_text;

// A DDS domain of this test process's own (from its pid), Cyclone on the loopback interface
// only (CYCLONEDDS_URI set for the process the first time).
inline uint32_t test_domain() {
  static const uint32_t domain = [] {
    ::setenv("CYCLONEDDS_URI",
             "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
             "name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
             "</Domain></CycloneDDS>",
             1);
    return static_cast<uint32_t>(1 + ::getpid() % 200);
  }();
  return domain;
}

inline std::unique_ptr<Simulation> world(const std::string& text) {
  auto cfg = parse_config(text, "test.toml");
  EXPECT_TRUE(cfg) << (cfg ? "" : cfg.error().front());
  auto sim = Simulation::build(*cfg);
  EXPECT_TRUE(sim) << (sim ? "" : sim.error().front());
  return std::move(*sim);
}

inline constexpr const char* kClassic = "[[bus]]\nname = \"can0\"\n";
inline constexpr const char* kTwoBuses = "[[bus]]\nname = \"can0\"\n[[bus]]\nname = \"can1\"\n";
inline constexpr const char* kFd =
    "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n";

// A [[bridge]] table of the configuration: its kind, its bus and the keys after them.
inline std::string bridge_table(const std::string& kind, const std::string& bus,
                                const std::string& keys = "") {
  return "[[bridge]]\nkind = \"" + kind + "\"\nbus = \"" + bus + "\"\n" + keys;
}

inline void run_to(Simulation& sim, int64_t ns) {
  sim.scheduler().run_until(model::SimTime::from_ns(ns));
}

// A frame in cansend's syntax ("123#1122", "12345678#R4", "123##1AABB") as SocketCAN holds it.
inline ipc::socketcan::Frame cansend_frame(const std::string& text) {
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

// A frame of the bus as candump prints it.
inline std::string candump(model::SimTime at, const model::Frame& f) {
  return ipc::socketcan::candump_text(
      *ipc::socketcan::from_message(to_message(at, f, ipc::ChannelMessageKind::frame)));
}

// A frame of the bus in cansend's syntax.
inline model::Frame bus_frame(const std::string& cansend) {
  std::string error;
  const auto m = ipc::socketcan::to_message(cansend_frame(cansend), error);
  EXPECT_TRUE(m) << cansend << ": " << error;
  return to_tx_frame(*m)->frame;
}

// The node's TEC set above 255 at `at_ns`, as the `bus_off` fault effect does it.
inline void bus_off_at(Simulation& sim, model::HostedNode& node, int64_t at_ns) {
  sim.scheduler().schedule_at(model::SimTime::from_ns(at_ns), [&node](model::SimTime) {
    model::FaultConfinement& fc = node.controller().confinement();
    fc.set_counters(model::kBusOffLimit, fc.rec());
    node.bus().counters_changed(node.node());
  });
}

// 128 sequences of 11 recessive bits at 500 kbit/s (2 us a bit), on an idle bus.
inline constexpr int64_t kRecoveryNs = 128 * 11 * 2'000;

struct BusNode : model::ControllerEvents {
  std::deque<model::Frame> queue;
  std::vector<int64_t> at_ns;
  std::vector<model::Frame> received;
  std::vector<std::string> texts;  // what it received, as candump prints it
  model::HostedNode* node = nullptr;
  BusNode(Simulation& sim, std::size_t bus) {
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
    at_ns.push_back(at.ns());
    received.push_back(f);
    texts.push_back(candump(at, f));
  }
  void send(const model::Frame& f) {
    queue.push_back(f);
    node->kick();
  }
  void send(uint32_t id, std::vector<uint8_t> data, bool fd = false) {
    model::FrameSpec spec;
    spec.id = id;
    spec.dlc = static_cast<uint8_t>(data.size());
    spec.data = data;
    spec.fd = fd;
    send(*model::Frame::create(spec));
  }
  void send(const std::string& cansend) { send(bus_frame(cansend)); }
};

}  // namespace canemu::daemon::bridge_test
