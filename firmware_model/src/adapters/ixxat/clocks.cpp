#include "canemu/firmware_model/adapters/ixxat/clocks.hpp"

namespace canemu::model::ixxat {

namespace {
constexpr int64_t kNsPerSecond = 1'000'000'000;
}  // namespace

int64_t ticks_to_ns(uint128 count, uint32_t divisor, uint32_t clock_hz) {
  const uint128 num = count * divisor * kNsPerSecond;
  return static_cast<int64_t>((num + clock_hz - 1) / clock_hz);
}

uint64_t ns_to_ticks(int64_t ns, uint32_t divisor, uint32_t clock_hz) {
  if (ns <= 0) {
    return 0;
  }
  const uint128 num = static_cast<uint128>(ns) * clock_hz;
  return static_cast<uint64_t>(num / (static_cast<uint128>(divisor) * kNsPerSecond));
}

}  // namespace canemu::model::ixxat
