#include "canemu/firmware_model/adapters/sorcus/acceptance.hpp"

namespace canemu::model::sorcus {

AcceptanceFilter automatic_filter(std::span<const uint32_t> ids, bool extended) {
  const uint32_t width = id_width_mask(extended);
  uint32_t all_and = width;
  uint32_t all_or = 0;
  for (const uint32_t id : ids) {
    all_and &= id;
    all_or |= id;
  }
  return AcceptanceFilter{~(all_and ^ all_or) & width, all_and & width};
}

}  // namespace canemu::model::sorcus
