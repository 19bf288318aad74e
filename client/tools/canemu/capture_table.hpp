// canemud's recorders ([[recorder]]) and SocketCAN bridges as `canemu status` and `canemu
// bridge list` show them.
#pragma once

#include <string>
#include <vector>

#include <toml++/toml.h>
#include <tl/expected.hpp>

#include "canemu/client/connection.hpp"

#include "canemu/ipc/protocol.hpp"

namespace canemu::cli {

// canemud's recorders and bridges, asked for together; the error's text on failure.
struct CaptureLists {
  std::vector<ipc::RecorderEntry> recorders;  // every page
  std::vector<ipc::BridgeEntry> bridges;
};
tl::expected<CaptureLists, std::string> capture_lists(client::Connection& c);

// Every recorder, one line each under a header line: bus, format, frames, bytes, rotations,
// frames lost, the file and the last failure.
void print_recorders(const std::vector<ipc::RecorderEntry>& r);

// The same as an array for JSON (fault_table.hpp's one_line_json writes it).
toml::array recorders_array(const std::vector<ipc::RecorderEntry>& r);

// Every bridge, one line each under a header line: bus, interface, the node's state and
// counters, frames each way, and every kind of drop.
void print_bridges(const std::vector<ipc::BridgeEntry>& r);
toml::array bridges_array(const std::vector<ipc::BridgeEntry>& r);

}  // namespace canemu::cli
