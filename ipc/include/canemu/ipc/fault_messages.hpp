// The control protocol's messages about fault scenarios (docs/faults.md): a scenario's text
// loaded, the faults applied listed in pages, scenarios cleared. Gathered with the others by
// protocol.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

inline constexpr std::size_t kMaxScenarioText = 12288;
inline constexpr std::size_t kFaultPage = 48;  // faults in one FaultListReply
// A fault's target as the list shows it: a bus, a node, or a simulated node's message or signal
// (BUS/MESSAGE.SIGNAL, names as long as a DBC writes them).
inline constexpr std::size_t kFaultTargetSize = 128;

// A scenario's text (not a path: the daemon never reads files on a client's behalf), applied
// from the simulated time the request is handled.
struct FaultLoadRequest {
  MsgHeader header;
  char source[64] = {};  // shown in errors, e.g. the client's file name
  uint32_t length = 0;   // bytes of `text` used
  uint32_t reserved = 0;
  char text[kMaxScenarioText] = {};
};
static_assert(sizeof(FaultLoadRequest) == 16 + 72 + kMaxScenarioText);

struct FaultLoadReply {
  MsgHeader header;
  uint32_t applied = 0;  // 1: applied; 0: rejected, see `errors`
  uint32_t faults = 0;
  char name[kScenarioNameSize] = {};
  char errors[4096] = {};  // one problem per line, with the line of the scenario text
};
static_assert(sizeof(FaultLoadReply) == 16 + 8 + kScenarioNameSize + 4096);

enum class WireFaultState : uint8_t { pending = 0, active = 1, done = 2, cleared = 3 };

// A fault's state as `canemu fault list` shows it; "?" for a value that is none.
constexpr std::string_view to_string(WireFaultState state) {
  switch (state) {
    case WireFaultState::pending:
      return "pending";
    case WireFaultState::active:
      return "active";
    case WireFaultState::done:
      return "done";
    case WireFaultState::cleared:
      return "cleared";
  }
  return "?";
}

// What FaultEntry's match describes: nothing (an effect on a bus or node), the CAN or LIN frames
// a frame effect hits, or the frame babble sends (its id and ext).
enum class WireFaultMatch : uint8_t { none = 0, can = 1, lin = 2, babble = 3 };
// A condition of a match on a frame's kind: either, or only one (ext: standard / extended;
// rtr: data / remote frames).
enum class WireMatchFlag : uint8_t { any = 0, no = 1, yes = 2 };

struct FaultEntry {
  char scenario[kScenarioNameSize] = {};
  char effect[24] = {};
  char target[kFaultTargetSize] = {};  // bus, node, or BUS/MESSAGE[.SIGNAL]
  uint32_t line = 0;
  uint8_t state = 0;  // WireFaultState
  uint8_t has_until = 0;
  uint16_t reserved = 0;
  int64_t at_ns = 0;
  int64_t until_ns = 0;
  uint64_t seen = 0;
  uint64_t hits = 0;
  uint8_t match = 0;      // WireFaultMatch
  uint8_t match_ext = 0;  // WireMatchFlag
  uint8_t match_rtr = 0;  // WireMatchFlag
  uint8_t reserved2 = 0;
  uint32_t match_id = 0;
  uint32_t match_mask = 0;  // identifier bits that must equal match_id; 0: any identifier
  uint32_t reserved3 = 0;
  char match_from[kNameSize] = {};  // the transmitting (CAN) or commanding (LIN) node; "": any
};
static_assert(sizeof(FaultEntry) ==
              kScenarioNameSize + 24 + kFaultTargetSize + 8 + 32 + 16 + kNameSize);

// The faults in pages, as the other lists: from the `first` on. A load adds faults at the end;
// what moves them (cleared scenarios forgotten beyond the newest 32) changes the generation, so
// that a reader of pages of different generations starts over.
struct FaultListRequest {
  MsgHeader header;
  uint16_t first = 0;
  uint16_t reserved = 0;
  uint32_t reserved2 = 0;
};
static_assert(sizeof(FaultListRequest) == 24);

struct FaultListReply {
  MsgHeader header;
  uint16_t count = 0;  // in this page, at most kFaultPage
  uint16_t total = 0;  // faults applied
  uint16_t first = 0;  // index of faults[0] among all (the request's)
  uint16_t reserved = 0;
  uint32_t generation = 0;  // changes whenever faults move (not when a load adds some)
  uint32_t reserved2 = 0;
  FaultEntry faults[kFaultPage];
};
static_assert(sizeof(FaultListReply) <= kMaxMessageSize);

struct FaultClearRequest {
  MsgHeader header;
  char scenario[kScenarioNameSize] = {};  // empty: every scenario
};
static_assert(sizeof(FaultClearRequest) == 16 + kScenarioNameSize);

struct FaultClearReply {
  MsgHeader header;
  uint32_t cleared = 0;  // scenarios
  uint32_t refused = 0;  // scenarios of other users (or the configuration's) left in force
};
static_assert(sizeof(FaultClearReply) == 24);

}  // namespace canemu::ipc
