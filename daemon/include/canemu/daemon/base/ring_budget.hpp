// Ring memory counted against the daemon-wide limit and the owner's per-user quota while a
// channel lives.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>

namespace canemu::daemon {

// Shared memory of all channels' rings together.
inline constexpr std::size_t kMaxRingBytes = std::size_t{256} << 20;

// The bytes one ring holds while it lives, counted in the daemon-wide total and in its user's
// share; given back when it goes.
class RingBudget {
 public:
  RingBudget() = default;
  RingBudget(std::size_t* total, std::size_t* user, std::size_t bytes)
      : total_(total), user_(user), bytes_(bytes) {
    *total_ += bytes_;
    *user_ += bytes_;
  }
  RingBudget(RingBudget&& o) noexcept
      : total_(std::exchange(o.total_, nullptr)),
        user_(std::exchange(o.user_, nullptr)),
        bytes_(o.bytes_) {}
  RingBudget& operator=(RingBudget&& o) noexcept {
    RingBudget old(std::move(*this));
    total_ = std::exchange(o.total_, nullptr);
    user_ = std::exchange(o.user_, nullptr);
    bytes_ = o.bytes_;
    return *this;
  }
  ~RingBudget() {
    if (total_ != nullptr) {
      *total_ -= bytes_;
      *user_ -= bytes_;
    }
  }

 private:
  std::size_t* total_ = nullptr;
  std::size_t* user_ = nullptr;
  std::size_t bytes_ = 0;
};

// Who holds how much ring memory: the daemon-wide limit kMaxRingBytes, and a per-user quota
// ([security] ring_mib_per_user; root has none).
class RingLedger {
 public:
  void set_user_quota(std::size_t bytes) { user_quota_ = bytes; }
  std::size_t user_quota() const { return user_quota_; }

  // Why `bytes` more for `uid` do not fit, or empty if they do.
  std::string refusal(uint32_t uid, std::size_t bytes) const;
  // Counts `bytes` for `uid` until the budget is destroyed (check refusal() first).
  RingBudget take(uint32_t uid, std::size_t bytes) { return {&total_, &users_[uid], bytes}; }

  std::size_t in_use() const { return total_; }
  std::size_t in_use(uint32_t uid) const;

 private:
  std::size_t total_ = 0;
  std::size_t user_quota_ = kMaxRingBytes;
  // Entries stay (their addresses are in live budgets); one per uid that ever opened a ring.
  std::map<uint32_t, std::size_t> users_;
};

}  // namespace canemu::daemon
