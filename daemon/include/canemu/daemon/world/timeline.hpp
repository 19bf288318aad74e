// What happened over time, for `canemu timeline` and `canemu plot`: a node's error counters and
// state (model::CounterTimeline) and a bus's load in 100 ms bins (model::BusLoad::history), in
// pages of the protocol's fixed-size replies; the nodes of ephemeral devices that have gone from
// Simulation::gone_nodes().
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <variant>

#include "canemu/daemon/world/simulation.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

struct TimelineError {
  ipc::ErrorCode code;
  std::string text;
};

using TimelineAnswer = std::variant<std::unique_ptr<ipc::TimelineReply>,
                                    std::unique_ptr<ipc::LoadHistoryReply>, TimelineError>;

// The answer to `m` at the simulation's current instant.
TimelineAnswer answer_timeline(const Simulation& sim, const ipc::TimelineRequest& m,
                               uint32_t request_id);

}  // namespace canemu::daemon
