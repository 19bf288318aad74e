// Simulated nodes named by users: "BUS/NAME", or a NAME that only one bus has (names are scoped
// by bus). Shared by the world's LIN and CAN nodes.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/config/config.hpp"

namespace canemu::daemon {

// "BUS/NAME" as the bus's name and the node's; a bare NAME: no bus.
inline std::pair<std::string_view, std::string_view> split_node_name(std::string_view name) {
  const auto slash = name.find('/');
  if (slash == std::string_view::npos) {
    return {{}, name};
  }
  return {name.substr(0, slash), name.substr(slash + 1)};
}

// The one node of `nodes` that `name` names (each node has `.bus`, an index into `buses`, and
// its name from `name_of`), or why there is none: none of that name ("no simulated KIND node
// named ..."), or several buses with it.
template <class Nodes, class NameOf>
Result<typename Nodes::iterator> find_named_node(Nodes& nodes, std::string_view name,
                                                 const std::vector<BusConfig>& buses,
                                                 std::string_view kind, NameOf name_of) {
  const auto [bus, node] = split_node_name(name);
  std::vector<typename Nodes::iterator> found;
  for (auto it = nodes.begin(); it != nodes.end(); ++it) {
    if (name_of(*it) == node && (bus.empty() || buses[it->bus].name == bus)) {
      found.push_back(it);
    }
  }
  if (found.empty()) {
    return fail(Errc::not_found, fmt::format("no simulated {} node named \"{}\"", kind, name));
  }
  if (found.size() > 1) {
    std::vector<std::string> where;
    where.reserve(found.size());
    for (auto it : found) {
      where.push_back(fmt::format("{}/{}", buses[it->bus].name, name_of(*it)));
    }
    return fail(Errc::bad_argument,
                fmt::format("{} nodes named \"{}\" are on several buses: name one as {}", kind,
                            name, fmt::join(where, " or ")));
  }
  return found.front();
}

}  // namespace canemu::daemon
