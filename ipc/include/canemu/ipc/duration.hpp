// Durations as people write them, shared by canemud's configuration and scenarios and the
// canemu command line.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace canemu::ipc {

// "150ns", "20us", "10ms", "2s", "1.5ms", and "0" (zero needs no unit): a duration in ns, at
// least 0 and at most about 285 years; nothing if the text is not one.
std::optional<int64_t> parse_duration(std::string_view text);

}  // namespace canemu::ipc
