// Ring memory counted against the daemon-wide limit while a channel lives.
#pragma once

#include <cstddef>
#include <utility>

namespace canemu::daemon {

// Shared memory of all channels' rings together.
inline constexpr std::size_t kMaxRingBytes = std::size_t{256} << 20;

class RingBudget {
 public:
  RingBudget() = default;
  RingBudget(std::size_t* in_use, std::size_t bytes) : in_use_(in_use), bytes_(bytes) {
    *in_use_ += bytes_;
  }
  RingBudget(RingBudget&& o) noexcept
      : in_use_(std::exchange(o.in_use_, nullptr)), bytes_(o.bytes_) {}
  RingBudget& operator=(RingBudget&& o) noexcept {
    RingBudget old(std::move(*this));
    in_use_ = std::exchange(o.in_use_, nullptr);
    bytes_ = o.bytes_;
    return *this;
  }
  ~RingBudget() {
    if (in_use_ != nullptr) {
      *in_use_ -= bytes_;
    }
  }

 private:
  std::size_t* in_use_ = nullptr;
  std::size_t bytes_ = 0;
};

}  // namespace canemu::daemon
