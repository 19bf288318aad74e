// The control protocol's messages about canemud's simulated CAN nodes at run time (`canemu
// restbus`, `canemu signal`, docs/restbus.md): load [[can_node]] tables, switch a node on or off,
// remove it, list them, set and read a signal. Gathered with the others by protocol.hpp.
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

inline constexpr std::size_t kMaxCanNodeText = 12288;
// The most text one load may gather over its requests: 1 MiB, as a configuration file (some
// 2,000 messages with their signals). canemud checks and starts a load in its loop, which a
// load of that size holds for some tens of milliseconds; larger restbuses load in parts.
inline constexpr std::size_t kMaxCanNodeLoad = 1u << 20;
inline constexpr std::size_t kMaxCanNodes = 48;
inline constexpr std::size_t kLongNameSize = 128;  // DBC message and signal names

enum class CanNodeOp : uint8_t {
  list = 0,
  load = 1,       // `text` is the last (or only) part of the tables: they are read and started
  load_part = 2,  // `text` is a part of the tables; more follow from this client
  power = 3,
  remove = 4,
  set_signal = 5,
  get_signal = 6,
};

struct CanNodeRequest {
  MsgHeader header;
  uint8_t op = 0;  // CanNodeOp
  uint8_t on = 0;  // power: 1 on, 0 off
  uint16_t reserved = 0;
  uint32_t length = 0;               // load, load_part: bytes of `text`
  double value = 0;                  // set_signal: the physical value
  char name[kNameSize] = {};         // power, remove: the node (NAME or BUS/NAME); set_signal,
                                     // get_signal: the bus
  char message[kLongNameSize] = {};  // set_signal, get_signal
  char signal[kLongNameSize] = {};   // set_signal, get_signal
  char source[64] = {};              // load: shown in errors (the file's name)
  char text[kMaxCanNodeText] = {};   // load, load_part: [[can_node]] tables (TOML)
};
static_assert(sizeof(CanNodeRequest) == 16 + 8 + 8 + 32 + 128 + 128 + 64 + kMaxCanNodeText);
static_assert(sizeof(CanNodeRequest) <= kMaxMessageSize);

struct CanNodeEntry {
  char name[kNameSize] = {};
  char bus[kNameSize] = {};
  uint8_t powered = 0;
  uint8_t reserved[3] = {};
  uint32_t messages = 0;  // messages it sends
  uint64_t frames = 0;    // frames it sent whole
};
static_assert(sizeof(CanNodeEntry) == 32 * 2 + 8 + 8);

// The nodes after the request (every op answers with the list), or `errors` (one per line) when
// it changed nothing. set_signal and get_signal also say which node sends the message and the
// signal's value after the request.
struct CanNodeReply {
  MsgHeader header;
  uint32_t ok = 0;
  uint16_t count = 0;
  uint16_t total = 0;
  double value = 0;
  char node[kNameSize] = {};
  CanNodeEntry nodes[kMaxCanNodes];
  char errors[2048] = {};
};
static_assert(sizeof(CanNodeReply) <= kMaxMessageSize);

}  // namespace canemu::ipc
