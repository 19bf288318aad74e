// Buses kept at full load through canemud's own clients, for the benchmarks of canemud.
#pragma once

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "../../tests/support/canemud_process.hpp"
#include "canemu/client/channel.hpp"

namespace canemu::bench {

// Buses can0..canN-1 kept at full load: on each an ephemeral channel's node that a babble fault
// makes send 000#0102030405060708 back to back for an hour, and a second channel's node that
// acknowledges and receives every frame (a connection per bus: a client may open 16 channels).
struct BabblingBuses {
  std::vector<client::Connection> owners;  // none moves once it has channels
  std::vector<client::Channel> babblers;
  std::vector<client::Channel> receivers;
  // An empty text, or what failed.
  std::string open(const canemu::testing::CanemudProcess& daemon, client::Connection& c,
                   int buses) {
    owners.reserve(static_cast<std::size_t>(buses));
    std::string scenario = "[scenario]\nname = \"babble\"\n";
    for (int i = 0; i < buses; ++i) {
      auto owner = client::Connection::open(daemon.socket(), "bench-bus" + std::to_string(i));
      if (!owner) {
        return owner.error().message;
      }
      owners.push_back(std::move(*owner));
      client::ChannelOptions o;
      o.bus = "can" + std::to_string(i);
      o.device = "tx" + std::to_string(i);
      o.rx_capacity = 16;
      o.tx_capacity = 16;
      auto tx = client::Channel::open(owners.back(), o);
      o.device = "rx" + std::to_string(i);
      o.rx_capacity = 2048;
      auto rx = client::Channel::open(owners.back(), o);
      if (!tx || !rx) {
        return (!tx ? tx.error() : rx.error()).message;
      }
      babblers.push_back(std::move(*tx));
      receivers.push_back(std::move(*rx));
      scenario += "[[fault]]\nat = \"0s\"\nnode = \"tx" + std::to_string(i) +
                  ":0\"\neffect = \"babble\"\nid = 0\ndata = [1, 2, 3, 4, 5, 6, 7, 8]\n"
                  "duration = \"3600s\"\n";
    }
    auto load = std::make_unique<ipc::FaultLoadRequest>(ipc::make_message<ipc::FaultLoadRequest>());
    ipc::copy_name(load->source, "bench");
    load->length = static_cast<uint32_t>(scenario.size());
    std::memcpy(load->text, scenario.data(), std::min(scenario.size(), sizeof load->text));
    auto loaded = c.call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(*load);
    if (!loaded) {
      return loaded.error().message;
    }
    return loaded->applied == 1 ? std::string() : std::string(loaded->errors);
  }
  // open() once canemud runs; false (the benchmark skipped with the reason) when canemud did not
  // start or the buses could not be made to babble.
  bool start(benchmark::State& state, const canemu::testing::CanemudProcess& daemon,
             client::Result<client::Connection>& c, int buses) {
    if (!daemon.ready() || !c) {
      state.SkipWithError(("canemud did not start: " + daemon.log()).c_str());
      return false;
    }
    if (std::string e = open(daemon, *c, buses); !e.empty()) {
      state.SkipWithError(e.c_str());
      return false;
    }
    return true;
  }
  // Takes what the receivers hold; returns how many.
  uint64_t drain() {
    uint64_t n = 0;
    ipc::ChannelMessage m;
    for (client::Channel& r : receivers) {
      while (r.rx().get(&m) == ipc::RingStatus::ok) {
        ++n;
      }
    }
    return n;
  }
};

}  // namespace canemu::bench
