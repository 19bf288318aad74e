// What the SORCUS services' tests (X-CAN-2i, SL-CANi) share: the service of a simulation with
// every packet it sends kept, and those packets read back as the replies they are.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <vector>

#include <gtest/gtest.h>

#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon::daemon_test {

template <class ServiceType>
struct KeptPackets {
  std::unique_ptr<Simulation> sim;
  ServiceType service;
  std::vector<std::vector<uint8_t>> sent;
  typename ServiceType::Send send = [this](const void* data, std::size_t size,
                                           std::span<const int>) {
    const auto* p = static_cast<const uint8_t*>(data);
    sent.emplace_back(p, p + size);
  };

  explicit KeptPackets(std::unique_ptr<Simulation> world) : sim(std::move(world)), service(*sim) {}

  // Handles request `m` of `session`, keeping only what that sends.
  template <class Session, class Request>
  void handle(Session& session, const Request& m) {
    sent.clear();
    service.handle(session, m, send);
  }
  // Packet k as a `Packet` (zeros past what was sent); it must be one.
  template <class Packet>
  Packet packet(std::size_t k) const {
    Packet p{};
    EXPECT_EQ(sent.at(k).size(), sizeof p);
    std::memcpy(&p, sent.at(k).data(), std::min(sizeof p, sent.at(k).size()));
    return p;
  }
};

}  // namespace canemu::daemon::daemon_test
