#include "canemu/firmware_model/bus/bus_load.hpp"

#include <algorithm>
#include <cstdint>

namespace canemu::model {

void BusLoad::grow() {
  std::vector<std::pair<SimTime, SimTime>> grown(busy_.empty() ? 64 : 2 * busy_.size());
  for (std::size_t k = 0; k < busy_count_; ++k) {
    grown[k] = busy_[(busy_head_ + k) & (busy_.size() - 1)];
  }
  busy_ = std::move(grown);
  busy_head_ = 0;
}

double BusLoad::percent(SimTime now) const {
  const SimTime from = now - seconds(1);
  int64_t busy = 0;
  for (std::size_t k = 0; k < busy_count_; ++k) {
    const auto& [start, end] = busy_[(busy_head_ + k) & (busy_.size() - 1)];
    const SimTime a = std::max(start, from);
    const SimTime b = std::min(end, now);
    if (b > a) {
      busy += (b - a).ns();
    }
  }
  return 100.0 * static_cast<double>(busy) / 1e9;
}

void BusLoad::add_to_bins(SimTime start, SimTime end) {
  const int64_t bin = kBin.ns();
  for (int64_t k = start.ns() / bin; k * bin < end.ns(); ++k) {
    if (bins_.empty()) {
      first_bin_ = k;
    }
    if (k - (first_bin_ + static_cast<int64_t>(bins_.size())) >=
        static_cast<int64_t>(kHistoryBins)) {
      bins_.clear();  // after a long idle stretch nothing kept would stay
      first_bin_ = k;
    }
    while (first_bin_ + static_cast<int64_t>(bins_.size()) <= k) {
      bins_.push_back(0);
    }
    while (bins_.size() > kHistoryBins) {
      bins_.pop_front();
      ++first_bin_;
    }
    if (k < first_bin_) {
      continue;  // older than what is kept
    }
    const int64_t a = std::max(start.ns(), k * bin);
    const int64_t b = std::min(end.ns(), (k + 1) * bin);
    bins_[static_cast<std::size_t>(k - first_bin_)] += b - a;
  }
  if (bins_.empty()) {
    newest_begin_ns_ = INT64_MAX;
    newest_end_ns_ = INT64_MIN;
  } else {
    newest_begin_ns_ = (first_bin_ + static_cast<int64_t>(bins_.size()) - 1) * bin;
    newest_end_ns_ = newest_begin_ns_ + bin;
  }
}

std::vector<BusLoad::Bin> BusLoad::history(SimTime now) const {
  const int64_t bin = kBin.ns();
  const int64_t end = now.ns() / bin;  // bins before this one have ended
  const int64_t begin = std::max<int64_t>(0, end - static_cast<int64_t>(kHistoryBins));
  std::vector<Bin> out;
  out.reserve(static_cast<std::size_t>(end - begin));
  for (int64_t k = begin; k < end; ++k) {
    const int64_t at = k - first_bin_;
    const int64_t busy = at >= 0 && at < static_cast<int64_t>(bins_.size())
                             ? bins_[static_cast<std::size_t>(at)]
                             : 0;
    out.push_back(Bin{SimTime::from_ns(k * bin), SimDuration(busy)});
  }
  return out;
}

}  // namespace canemu::model
