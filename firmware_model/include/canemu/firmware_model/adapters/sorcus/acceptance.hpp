// The automatic acceptance filter of the SORCUS receive-only buffer 15 (digest §1.5): the IDs
// of every object in buffer 15 superimposed into an ID mask and an acceptance mask.
//
// «An den Bitpositionen, an denen alle eingetragenen IDs den gleichen Bitwert haben, ist das Bit
// in der Akzeptanzmaske = 1 und in der ID-Maske gleich dem Bitwert. An den übrigen Bitpositionen
// enthalten beide Masken eine 0.» (where all IDs agree, the acceptance bit is 1 and the ID bit
// that value; elsewhere both are 0.) The manual's "XNOR of all IDs" agrees only for two IDs; the
// rule above is what is implemented: acc = ~(AND ^ OR), idm = AND.
// A message passes when it equals the ID mask wherever the acceptance mask is 1.
//
// Worked examples (the manual's, and tests): IDs {03h, 07h} -> acc 7FBh, idm 003h, only 03h and
// 07h pass; IDs {20h, 07h} -> acc 7D8h, idm 000h, 00h..07h and 20h..27h pass.
#pragma once

#include <cstdint>
#include <span>

namespace canemu::model::sorcus {

struct AcceptanceFilter {
  uint32_t acc = 0;  // 1: compare this bit
  uint32_t idm = 0;  // the value compared with
  bool passes(uint32_t id) const { return ((id ^ idm) & acc) == 0; }
  friend bool operator==(const AcceptanceFilter&, const AcceptanceFilter&) = default;
};

// The identifier width's bits: 0x7FF or 0x1FFFFFFF.
constexpr uint32_t id_width_mask(bool extended) {
  return extended ? 0x1FFFFFFFu : 0x7FFu;
}

// The filter of `ids` (at least one) in the given width.
AcceptanceFilter automatic_filter(std::span<const uint32_t> ids, bool extended);

}  // namespace canemu::model::sorcus
