// A hosted node (hosted_node.hpp) for tests: its own transmit queue, and a log of everything its
// sink was told, with the instants in ns.
#pragma once

#include <gtest/gtest.h>

#include <deque>
#include <utility>
#include <vector>

#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "test_controller.hpp"

namespace canemu::model::testing {

// Instants in ns.
struct NodeLog : ControllerEvents, FrameLog<int64_t> {
  std::vector<std::pair<int64_t, ErrorState>> states;
  std::vector<std::pair<int64_t, uint16_t>> lost;  // arbitration losses: instant, bit
  void frame_received(SimTime at, const Frame& f, bool own) override {
    received.push_back({at.ns(), f, own});
  }
  void frame_transmitted(SimTime at, const Frame& f) override {
    sent.push_back({at.ns(), f, false});
  }
  void transmission_dropped(SimTime at, const Frame&) override { dropped.push_back(at.ns()); }
  void bus_error(const BusErrorEvent& e) override { errors.push_back(e); }
  void arbitration_lost(SimTime at, uint16_t bit) override { lost.emplace_back(at.ns(), bit); }
  void state_changed(SimTime at, ErrorState s, uint16_t, uint16_t) override {
    states.emplace_back(at.ns(), s);
  }
};

template <class Node>
struct Station {
  Node node;
  NodeLog log;
  std::deque<TxFrame> queue;
  int pulls = 0;  // how often the node asked the queue for a frame
  explicit Station(BusFixture& b) : node(b.sched, b.bus) {}
  void start(const HostedNodeSettings& s) {
    node.start(s, &log, [this]() -> std::optional<TxFrame> {
      ++pulls;
      if (queue.empty()) {
        return std::nullopt;
      }
      TxFrame f = queue.front();
      queue.pop_front();
      return f;
    });
  }
  void send(const Frame& f, bool single_shot = false, bool self_reception = false) {
    queue.push_back(TxFrame{f, single_shot, self_reception});
    node.kick();
  }
};

// A node that went bus-off at `off` (the last state `log` shows) and whose driver restarts it
// `delay` ns later: bus-off until 128 x 11 recessive bits after the restart (the bus idle),
// error-active from that instant.
inline void expect_bus_off_until_recovery(BusFixture& b, const NodeLog& log, int64_t off,
                                          int64_t delay) {
  ASSERT_FALSE(log.states.empty());
  EXPECT_EQ(log.states.back(), std::make_pair(off, ErrorState::bus_off));
  const int64_t recovered = off + delay + 128 * 11 * kBit;
  b.run_until(recovered - 1);
  EXPECT_EQ(log.states.back().second, ErrorState::bus_off);
  b.run_until(recovered);
  EXPECT_EQ(log.states.back(), std::make_pair(recovered, ErrorState::active));
}

}  // namespace canemu::model::testing
