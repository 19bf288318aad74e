// What the bridge tests (SocketCAN, LCM, DDS) share: a simulation of a configuration text, and
// a node on the bus like a channel's that acknowledges, sends what it is given and records what
// it receives with its simulated instant.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon::bridge_test {

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
inline constexpr const char* kFd =
    "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n";

inline void run_to(Simulation& sim, int64_t ns) {
  sim.scheduler().run_until(model::SimTime::from_ns(ns));
}

struct BusNode : model::ControllerEvents {
  std::deque<model::Frame> queue;
  std::vector<int64_t> at_ns;
  std::vector<model::Frame> received;
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
};

}  // namespace canemu::daemon::bridge_test
