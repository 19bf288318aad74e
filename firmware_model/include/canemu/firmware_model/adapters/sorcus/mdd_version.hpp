// The version of the X-CAN-2i's module device driver (MDD) as the manual writes it: "3.C" is
// major 3, revision letter C. The manual marks three features «ab MDD Version 3.C»
// (../shared/spec/sorcus-digest.md §6 item 106); XcanModule leaves them out before.
#pragma once

#include <compare>
#include <cstdint>
#include <optional>
#include <string_view>

namespace canemu::model::sorcus {

struct MddVersion {
  uint8_t major = 3;
  char letter = 'C';
  constexpr auto operator<=>(const MddVersion&) const = default;
  // "N.L" with N 1..9 and L an upper-case letter; nullopt for anything else.
  static constexpr std::optional<MddVersion> parse(std::string_view text) {
    if (text.size() != 3 || text[0] < '1' || text[0] > '9' || text[1] != '.' || text[2] < 'A' ||
        text[2] > 'Z') {
      return std::nullopt;
    }
    return MddVersion{static_cast<uint8_t>(text[0] - '0'), text[2]};
  }
};

// The first version with everything the manual describes, and the model's default.
inline constexpr MddVersion kMdd3C{3, 'C'};

}  // namespace canemu::model::sorcus
