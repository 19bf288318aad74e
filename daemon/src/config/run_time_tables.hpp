// Tables loaded at run time ([[lin_node]] by `canemu lin load`, [[can_node]] by `canemu restbus
// load`): read from their own text against the buses that run, checked as the configuration's
// are. Shared by the two readers.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>
#include <tl/expected.hpp>

#include "canemu/daemon/config/config.hpp"
#include "config/toml_checker.hpp"

namespace canemu::daemon::detail {

// The tables `key` of `text` (from `source`) read by `read` into a Config of `buses`, as `field`
// of it; every problem otherwise (none there at all is one).
template <class T>
tl::expected<std::vector<T>, std::vector<std::string>> run_time_tables(
    std::string_view text, const std::string& source, const std::vector<BusConfig>& buses,
    const char* key, void (*read)(Checker&, const toml::table&, Config&),
    std::vector<T> Config::*field) {
  auto parsed = parse_toml(text, source);
  if (!parsed) {
    return tl::unexpected(parsed.error());
  }
  const toml::table& root = *parsed;
  Checker c(source);
  c.only_keys(root, "", {key});
  Config cfg;
  cfg.buses = buses;
  read(c, root, cfg);
  if (!c.errors().empty()) {
    return tl::unexpected(c.errors());
  }
  if ((cfg.*field).empty()) {
    return tl::unexpected(
        std::vector<std::string>{fmt::format("{}: no [[{}]] tables", source, key)});
  }
  return std::move(cfg.*field);
}

}  // namespace canemu::daemon::detail
