#include "canemu/firmware_model/bus/bus_load.hpp"

#include <algorithm>
#include <cstdint>

namespace canemu::model {

void BusLoad::record(SimTime start, SimTime end) {
  busy_.emplace_back(start, end);
  while (!busy_.empty() && busy_.front().second < end - seconds(2)) {
    busy_.pop_front();
  }
}

double BusLoad::percent(SimTime now) const {
  const SimTime from = now - seconds(1);
  int64_t busy = 0;
  for (const auto& [start, end] : busy_) {
    const SimTime a = std::max(start, from);
    const SimTime b = std::min(end, now);
    if (b > a) {
      busy += (b - a).ns();
    }
  }
  return 100.0 * static_cast<double>(busy) / 1e9;
}

}  // namespace canemu::model
