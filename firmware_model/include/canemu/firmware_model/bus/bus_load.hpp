// Bus load: the share of the last second of simulated time in which the bus was busy, from a
// start of frame (or of a dominant hold) to the end of the intermission after its frame or
// error frame.
#pragma once

#include <deque>
#include <utility>

#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model {

class BusLoad {
 public:
  // The bus was busy from `start` to `end`. Calls come in the order the activities end; what
  // ended more than two seconds before the latest `end` is forgotten.
  void record(SimTime start, SimTime end);
  // Busy time within the second before `now`, in percent of that second.
  double percent(SimTime now) const;

 private:
  std::deque<std::pair<SimTime, SimTime>> busy_;
};

}  // namespace canemu::model
