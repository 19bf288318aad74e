// A world of one 500 kbit/s bus in stepped time with simulated CAN nodes ([[can_node]]) and a
// node that acknowledges, recording every frame on the wire: for the tests of simulated CAN
// nodes and of the faults on them.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/daemon/restbus/can_ecu.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon {

using namespace canemu::model;

constexpr std::string_view kBus = R"(
[simulation]
time = "stepped"

[[bus]]
name = "can0"
bitrate = 500000
)";

inline SimTime ms(int64_t n) {
  return SimTime::from_ns(n * 1'000'000);
}

// The world of one bus with the nodes of `nodes`, a node that acknowledges, and every frame's
// start and end on the wire.
struct World {
  std::unique_ptr<Simulation> sim;
  std::vector<BusEvent> wire;
  explicit World(std::string_view nodes) {
    auto cfg = parse_config(std::string(kBus) + std::string(nodes), "t.toml");
    if (!cfg) {
      ADD_FAILURE() << cfg.error().front();
      return;
    }
    auto built = Simulation::build(*cfg);
    if (!built) {
      ADD_FAILURE() << built.error().front();
      return;
    }
    sim = std::move(*built);
    sim->bus(0).on_bus_event = [this](const BusEvent& e) { wire.push_back(e); };
    sim->spare_node(0).start(*sim->bus_timing(0), nullptr, [] { return std::optional<TxFrame>{}; });
  }
  restbus::CanEcu& ecu(std::string_view name) { return **sim->can_node(name); }
  void run_until(SimTime t) { sim->scheduler().run_until(t); }
  std::vector<SimTime> starts(uint32_t id) const {
    std::vector<SimTime> out;
    for (const BusEvent& e : wire) {
      if (e.kind == BusEvent::Kind::frame && e.frame->id() == id) {
        out.push_back(e.start);
      }
    }
    return out;
  }
  std::vector<std::vector<uint8_t>> payloads(uint32_t id) const {
    std::vector<std::vector<uint8_t>> out;
    for (const BusEvent& e : wire) {
      if (e.kind == BusEvent::Kind::frame && e.frame->id() == id) {
        out.emplace_back(e.frame->data().begin(), e.frame->data().end());
      }
    }
    return out;
  }
};

}  // namespace canemu::daemon
