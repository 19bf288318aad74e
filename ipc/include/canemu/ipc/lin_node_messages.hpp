// The control protocol's messages about canemud's simulated LIN nodes at run time (`canemu lin`,
// docs/lin.md): load [[lin_node]] tables, switch a node on or off, run or stop its schedule,
// remove it, list them. Gathered with the others by protocol.hpp.
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

inline constexpr std::size_t kMaxLinNodeText = 12288;
inline constexpr std::size_t kMaxLinNodes = 32;

enum class LinNodeOp : uint8_t { list = 0, load = 1, power = 2, schedule = 3, remove = 4 };

struct LinNodeRequest {
  MsgHeader header;
  uint8_t op = 0;  // LinNodeOp
  uint8_t on = 0;  // power: 1 on, 0 off
  uint16_t reserved = 0;
  uint32_t length = 0;              // load: bytes of `text`
  char name[kNameSize] = {};        // power, schedule, remove: the node
  char table[kNameSize] = {};       // schedule: the table to run ("": stop)
  char source[64] = {};             // load: shown in errors (the file's name)
  char text[kMaxLinNodeText] = {};  // load: [[lin_node]] tables (TOML)
};
static_assert(sizeof(LinNodeRequest) == 16 + 8 + 32 + 32 + 64 + kMaxLinNodeText);
static_assert(sizeof(LinNodeRequest) <= kMaxMessageSize);

struct LinNodeEntry {
  char name[kNameSize] = {};
  char bus[kNameSize] = {};
  char schedule[kNameSize] = {};  // running ("" none)
  uint8_t powered = 0;
  uint8_t reserved[7] = {};
  uint64_t headers = 0;    // sent as commander
  uint64_t responses = 0;  // sent as responder
};
static_assert(sizeof(LinNodeEntry) == 32 * 3 + 8 + 16);

// The nodes after the request (every op answers with the list), or `errors` (one per line)
// when it changed nothing.
struct LinNodeReply {
  MsgHeader header;
  uint32_t ok = 0;
  uint16_t count = 0;
  uint16_t total = 0;
  LinNodeEntry nodes[kMaxLinNodes];
  char errors[2048] = {};
};
static_assert(sizeof(LinNodeReply) <= kMaxMessageSize);

}  // namespace canemu::ipc
