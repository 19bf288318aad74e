// Bus load: the share of the last second of simulated time in which the bus was busy, from a
// start of frame (or of a dominant hold) to the end of the intermission after its frame or
// error frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <utility>
#include <vector>

#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model {

class BusLoad {
 public:
  // The bus was busy from `start` to `end`. Calls come in the order the activities end; what
  // ended more than two seconds before the latest `end` is forgotten (percent() leaves it out;
  // its room in the ring is taken back when the ring is full).
  void record(SimTime start, SimTime end) {
    if (busy_count_ == busy_size_) {
      make_room(end);
    }
    const std::size_t mask = busy_size_ - 1;
    if (busy_count_ != 0 && start.ns() < busy_[(busy_head_ + busy_count_ - 1) & mask].end) {
      overlapped_ = true;
    }
    busy_[(busy_head_ + busy_count_) & mask] = {start.ns(), end.ns(), busy_total_};
    busy_total_ += (end - start).ns();
    ++busy_count_;
    // Most activities fall inside the newest bin.
    if (start.ns() >= newest_begin_ns_ && end.ns() <= newest_end_ns_ && end > start) {
      bins_.back() += (end - start).ns();
    } else {
      add_to_bins(start, end);
    }
  }
  // Busy time within the second before `now`, in percent of that second.
  double percent(SimTime now) const;

  // The load over time: simulated time in bins of kBin (bin k covers [k * kBin, (k + 1) * kBin)),
  // the busy time of each. history(now) gives the bins that ended by `now`, oldest first, idle
  // ones included, the newest kHistoryBins of them (five minutes).
  static constexpr SimDuration kBin = milliseconds(100);
  static constexpr std::size_t kHistoryBins = 3000;
  struct Bin {
    SimTime start;
    SimDuration busy;
  };
  std::vector<Bin> history(SimTime now) const;

 private:
  // What ended longer than this before the latest activity's end is forgotten (record()).
  static constexpr SimDuration kKept = seconds(2);
  void add_to_bins(SimTime start, SimTime end);
  // busy_ is full: what ended two seconds before `end` leaves it, and if none did, it gets
  // twice the room (out of record's way: once every so many activities).
  [[gnu::noinline]] void make_room(SimTime end);
  void grow();

  // The activities of the last two seconds (and older ones until their room is needed), oldest
  // first: a ring over busy_ (its size a power of two, doubled when full of the last two
  // seconds), so that recording one costs no allocation once it has grown. Each
  // with the busy time of everything recorded before it, in ns, and busy_total_ that of
  // everything: percent() sums the activities between its edges as one difference.
  struct Activity {  // in ns
    int64_t start;
    int64_t end;
    int64_t before;
  };
  std::unique_ptr<Activity[]> busy_;  // uninitialised past busy_count_: grown without a fill
  std::size_t busy_size_ = 0;
  int64_t busy_total_ = 0;
  // Some activity began before the one recorded before it ended: percent() then adds each up.
  bool overlapped_ = false;
  std::size_t busy_head_ = 0;
  std::size_t busy_count_ = 0;
  // Busy nanoseconds of bins first_bin_, first_bin_ + 1, ...; later bins are idle so far.
  std::deque<int64_t> bins_;
  int64_t first_bin_ = 0;
  // The span of bins_.back(), [begin, end) in ns; empty while there are no bins.
  int64_t newest_begin_ns_ = INT64_MAX;
  int64_t newest_end_ns_ = INT64_MIN;
};

}  // namespace canemu::model
