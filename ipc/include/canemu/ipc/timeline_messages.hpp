// The control protocol's messages about what happened over time (`canemu timeline`, `canemu
// plot`): a node's error counters and state, a bus's load in bins of simulated time. Gathered
// with the others by protocol.hpp.
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

inline constexpr std::size_t kMaxTimelineSamples = 900;
inline constexpr std::size_t kMaxLoadBins = 3000;
// Nodes of ephemeral devices that have gone whose timelines a bus keeps (the newest ones).
inline constexpr std::size_t kMaxGoneNodes = 16;

// Asks for node `node`'s counter timeline (TimelineReply), or with `node` empty for bus `bus`'s
// load history (LoadHistoryReply), from sample or bin `first` on (the replies come in pages).
struct TimelineRequest {
  MsgHeader header;
  char bus[kNameSize] = {};
  char node[kNameSize] = {};
  uint32_t first = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(TimelineRequest) == 16 + 64 + 8);

// Why the counters changed (model::CounterCause).
enum class WireCounterCause : uint8_t {
  success = 0,
  error = 1,
  severe = 2,
  recovered = 3,
  written = 4
};

struct WireCounterSample {
  int64_t at_ns = 0;
  uint16_t tec = 0;
  uint16_t rec = 0;
  uint8_t state = 0;  // WireErrorState
  uint8_t cause = 0;  // WireCounterCause
  uint8_t error = 0;  // cause error: 0 bit, 1 stuff, 2 form, 3 crc, 4 ack
  uint8_t role = 0;   // cause error or severe: 0 transmitter, 1 receiver
};
static_assert(sizeof(WireCounterSample) == 16);

struct TimelineReply {
  MsgHeader header;
  char node[kNameSize] = {};
  uint32_t total = 0;      // samples kept
  uint32_t count = 0;      // in this reply, from `first` on
  uint64_t forgotten = 0;  // older samples no longer kept
  int64_t now_ns = 0;      // simulated time of the reply
  int64_t gone_at_ns = 0;  // when `gone`: the instant the node's device went
  uint8_t gone = 0;        // 1: the node's (ephemeral) device has gone, its timeline is kept
  uint8_t reserved[7] = {};
  WireCounterSample samples[kMaxTimelineSamples];
};
static_assert(sizeof(TimelineReply) <= kMaxMessageSize);

struct LoadHistoryReply {
  MsgHeader header;
  char bus[kNameSize] = {};
  int64_t start_ns = 0;  // of the first bin in this reply
  int64_t now_ns = 0;
  uint32_t bin_ns = 0;
  uint32_t total = 0;       // bins that ended by now_ns and are kept
  uint32_t count = 0;       // in this reply
  uint32_t gone_count = 0;  // names in `gone`
  // The nodes gone from this bus whose timelines are kept, oldest first (TimelineRequest names
  // them as any other node).
  char gone[kMaxGoneNodes][kNameSize] = {};
  uint32_t busy_ns[kMaxLoadBins] = {};
};
static_assert(sizeof(LoadHistoryReply) <= kMaxMessageSize);

}  // namespace canemu::ipc
