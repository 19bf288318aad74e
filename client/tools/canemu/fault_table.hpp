// The faults canemud applied, as `canemu fault list` and `canemu status` show them.
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include <toml++/toml.h>
#include <tl/expected.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::cli {

using FaultList = std::vector<ipc::FaultEntry>;

// Asks canemud for its fault list, every page of it; the error's text on failure.
tl::expected<FaultList, std::string> fault_list(client::Connection& c);

// What a fault's frames must be, as `fault list` shows it: "id 0x123 mask 0x7F0 ext from
// ixxat0:0", "any" (every frame), babble's "sends 0x123", "-" for effects on no frame.
std::string match_text(const ipc::FaultEntry& e);

// Every fault, one line each under a header line.
void print_faults(const FaultList& faults);

// The same as a JSON array on one line.
std::string faults_json(const FaultList& faults);
toml::array faults_array(const FaultList& faults);

// A table or array as JSON on one line, written by toml++ (strings escaped as JSON wants them:
// a name can never end a string or a line early).
template <typename Node>
std::string one_line_json(const Node& node) {
  std::ostringstream out;
  out << toml::json_formatter{node, toml::format_flags::none};
  std::string text = out.str();
  std::erase(text, '\n');  // only the formatter's line breaks: strings have theirs escaped
  return text;
}

}  // namespace canemu::cli
