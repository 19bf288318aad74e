// The counter timelines of ephemeral devices' nodes after their devices went, so that `canemu
// timeline` after a python-can program (or any client's adapter or channel) still shows what its
// node went through: per bus the newest kPerBus, each until a device of its name comes again.
#pragma once

#include <cstddef>
#include <deque>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/sim/sim_time.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

class GoneNodes {
 public:
  static constexpr std::size_t kPerBus = ipc::kMaxGoneNodes;

  struct Node {
    std::string device;
    std::string name;  // "DEVICE:0", as canemu status listed it
    std::size_t bus = 0;
    model::SimTime gone_at;
    model::CounterTimeline timeline;
  };

  // Keeps `timeline` of the node of device `device` on bus `bus`, gone at `at`; the oldest of
  // that bus beyond kPerBus goes.
  void keep(const std::string& device, std::size_t bus, model::SimTime at,
            const model::CounterTimeline& timeline);
  // A device named `device` came: the history of an earlier one of that name goes.
  void forget(std::string_view device);
  // The node named `name` ("DEVICE:0" or "DEVICE"), or nullptr.
  const Node* find(std::string_view name) const;
  // The nodes gone from bus `bus`, oldest first.
  std::vector<const Node*> on_bus(std::size_t bus) const;

 private:
  std::deque<Node> nodes_;  // oldest first
};

}  // namespace canemu::daemon
