#include "canemu/daemon/base/ring_budget.hpp"

#include <fmt/format.h>

namespace canemu::daemon {

std::string RingLedger::refusal(uint32_t uid, std::size_t bytes) const {
  if (total_ + bytes > kMaxRingBytes) {
    return fmt::format("ring memory for all channels is limited to {} MiB", kMaxRingBytes >> 20);
  }
  if (uid != 0 && in_use(uid) + bytes > user_quota_) {
    return fmt::format(
        "uid {} would hold {} KiB of ring memory; [security] ring_mib_per_user allows {} MiB", uid,
        (in_use(uid) + bytes) >> 10, user_quota_ >> 20);
  }
  return {};
}

std::size_t RingLedger::in_use(uint32_t uid) const {
  const auto it = users_.find(uid);
  return it == users_.end() ? 0 : it->second;
}

}  // namespace canemu::daemon
