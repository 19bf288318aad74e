#include "command.hpp"

#include <cstdio>

#include "canemu/ipc/duration.hpp"

namespace canemu::cli {

int fail(const std::string& message) {
  std::fprintf(stderr, "canemu: %s\n", message.c_str());
  return 1;
}

std::optional<int64_t> parse_positive_duration(const std::string& text) {
  const auto ns = ipc::parse_duration(text);
  return ns && *ns > 0 ? ns : std::nullopt;
}

}  // namespace canemu::cli
