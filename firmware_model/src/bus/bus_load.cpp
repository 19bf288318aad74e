#include "canemu/firmware_model/bus/bus_load.hpp"

#include <algorithm>
#include <cstdint>

namespace canemu::model {

void BusLoad::make_room(SimTime end) {
  const int64_t forget = (end - kKept).ns();
  const std::size_t mask = busy_size_ - 1;
  while (busy_count_ != 0 && busy_[busy_head_].end < forget) {
    busy_head_ = (busy_head_ + 1) & mask;
    --busy_count_;
  }
  if (busy_count_ == busy_size_) {
    grow();
  }
}

void BusLoad::grow() {
  const std::size_t size = busy_size_ == 0 ? 64 : 2 * busy_size_;
  auto grown = std::make_unique_for_overwrite<Activity[]>(size);
  // The ring unrolled: from its head to the end of the room, then what wrapped.
  const std::size_t first = std::min(busy_count_, busy_size_ - busy_head_);
  std::copy_n(busy_.get() + busy_head_, first, grown.get());
  std::copy_n(busy_.get(), busy_count_ - first, grown.get() + first);
  busy_ = std::move(grown);
  busy_size_ = size;
  busy_head_ = 0;
}

double BusLoad::percent(SimTime now) const {
  const SimTime from = now - seconds(1);
  const std::size_t mask = busy_size_ - 1;
  const auto at = [&](std::size_t k) -> const Activity& { return busy_[(busy_head_ + k) & mask]; };
  // What ended more than two seconds before the newest activity's end counts as forgotten,
  // whether or not make_room() has dropped it yet: the ring keeps such activities until their
  // room is needed, and the answer must not depend on that.
  // `forgotten`: the latest end that counts as forgotten.
  const int64_t forgotten = busy_count_ == 0 ? INT64_MIN : at(busy_count_ - 1).end - kKept.ns() - 1;
  int64_t busy = 0;
  const auto add_clipped = [&](std::size_t k) {
    const int64_t a = std::max(at(k).start, from.ns());
    const int64_t b = std::min(at(k).end, now.ns());
    if (b > a) {
      busy += b - a;
    }
  };
  if (overlapped_) {
    for (std::size_t k = 0; k < busy_count_; ++k) {
      if (at(k).end > forgotten) {
        add_clipped(k);
      }
    }
    return 100.0 * static_cast<double>(busy) / 1e9;
  }
  // The activities follow one another: the ones ending after `from` are a tail of the ring (found
  // by halving), of which only the first may begin before `from` and only the last few end after
  // `now`; what lies between counts whole, the difference of two running totals.
  // (Ends come in order, so the forgotten ones are a head of the ring too.)
  const int64_t after = std::max(from.ns(), forgotten);
  std::size_t lo = 0;
  std::size_t hi = busy_count_;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (at(mid).end > after) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  hi = busy_count_;
  while (hi > lo && at(hi - 1).end > now.ns()) {
    add_clipped(--hi);
  }
  if (lo < hi && at(lo).start < from.ns()) {
    add_clipped(lo++);
  }
  if (lo < hi) {
    busy += (hi < busy_count_ ? at(hi).before : busy_total_) - at(lo).before;
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
