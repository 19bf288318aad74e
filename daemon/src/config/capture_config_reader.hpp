// The [[recorder]] and [[bridge]] readers of the configuration (config.cpp calls them).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "canemu/daemon/config/config.hpp"
#include "toml_checker.hpp"

namespace canemu::daemon::detail {

void read_recorders(Checker& c, const toml::table& root, Config& cfg);
void read_bridges(Checker& c, const toml::table& root, Config& cfg);

// A Linux interface name: 1 to 15 characters, no '/', no blanks; nothing, or what is wrong.
std::optional<std::string> interface_name_problem(std::string_view name);

// `file` as given in the configuration: relative to the configuration file's folder.
std::string beside_config(const Config& cfg, const std::string& file);

}  // namespace canemu::daemon::detail
