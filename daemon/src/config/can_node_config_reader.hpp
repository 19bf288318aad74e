// The [[can_node]] reader of the configuration (config.cpp calls it).
#pragma once

#include <toml++/toml.h>

#include "canemu/daemon/config/config.hpp"
#include "toml_checker.hpp"

namespace canemu::daemon::detail {

void read_can_nodes(Checker& c, const toml::table& root, Config& cfg);

}  // namespace canemu::daemon::detail
