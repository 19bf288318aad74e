#include "canemu/ipc/duration.hpp"

#include <cctype>
#include <charconv>
#include <string_view>
#include <system_error>

namespace canemu::ipc {

std::optional<int64_t> parse_duration(std::string_view text) {
  std::size_t i = 0;
  int dots = 0;
  bool digits = false;
  while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.')) {
    dots += text[i] == '.';
    digits = digits || text[i] != '.';
    ++i;
  }
  if (!digits || dots > 1) {
    return std::nullopt;
  }
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + i, value);
  if (ec != std::errc{} || end != text.data() + i) {
    return std::nullopt;
  }
  const std::string_view unit = text.substr(i);
  if (unit.empty() && value == 0) {
    return 0;  // zero needs no unit
  }
  const double scale = unit == "ns"   ? 1
                       : unit == "us" ? 1e3
                       : unit == "ms" ? 1e6
                       : unit == "s"  ? 1e9
                                      : 0;
  if (scale == 0 || value * scale > 9.0e18) {
    return std::nullopt;
  }
  return static_cast<int64_t>(value * scale + 0.5);
}

}  // namespace canemu::ipc
