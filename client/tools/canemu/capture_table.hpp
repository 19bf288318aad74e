// canemud's recorders ([[recorder]]) and SocketCAN bridges as `canemu status` and `canemu
// bridge list` show them.
#pragma once

#include <string>

#include "canemu/ipc/protocol.hpp"

namespace canemu::cli {

// Every recorder, one line each under a header line: bus, format, frames, bytes, rotations,
// frames lost, the file and the last failure.
void print_recorders(const ipc::RecorderListReply& r);

// The same as a JSON array on one line.
std::string recorders_json(const ipc::RecorderListReply& r);

// Every bridge, one line each under a header line: bus, interface, the node's state and
// counters, frames each way, and every kind of drop.
void print_bridges(const ipc::BridgeListReply& r);
std::string bridges_json(const ipc::BridgeListReply& r);

}  // namespace canemu::cli
