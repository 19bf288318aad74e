// canemud's recorders ([[recorder]]) and SocketCAN bridges as `canemu status` and `canemu
// bridge list` show them.
#pragma once

#include <string>

#include <toml++/toml.h>

#include "canemu/ipc/protocol.hpp"

namespace canemu::cli {

// Every recorder, one line each under a header line: bus, format, frames, bytes, rotations,
// frames lost, the file and the last failure.
void print_recorders(const ipc::RecorderListReply& r);

// The same as an array for JSON (fault_table.hpp's one_line_json writes it).
toml::array recorders_array(const ipc::RecorderListReply& r);

// Every bridge, one line each under a header line: bus, interface, the node's state and
// counters, frames each way, and every kind of drop.
void print_bridges(const ipc::BridgeListReply& r);
toml::array bridges_array(const ipc::BridgeListReply& r);

}  // namespace canemu::cli
