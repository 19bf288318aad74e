// Bus load over the last second of simulated time.
#include "canemu/firmware_model/bus/bus_load.hpp"

#include <gtest/gtest.h>

namespace canemu::model {
namespace {

SimTime at_ms(int64_t ms) {
  return SimTime{} + milliseconds(ms);
}

TEST(BusLoad, AnIdleBusHasNoLoad) {
  const BusLoad load;
  EXPECT_EQ(load.percent(at_ms(1000)), 0.0);
}

TEST(BusLoad, BusyTimeCountsAgainstAWholeSecondEvenEarlyOn) {
  BusLoad load;
  load.record(at_ms(0), at_ms(250));
  EXPECT_EQ(load.percent(at_ms(500)), 25.0);
  EXPECT_EQ(load.percent(at_ms(1000)), 25.0);
}

TEST(BusLoad, OnlyTheSecondBeforeNowCounts) {
  BusLoad load;
  load.record(at_ms(0), at_ms(250));
  load.record(at_ms(900), at_ms(1100));
  // From 100 ms: 150 ms of the first activity, all 200 ms of the second.
  EXPECT_EQ(load.percent(at_ms(1100)), 35.0);
  // At 1000 ms the second activity counts up to now only.
  EXPECT_EQ(load.percent(at_ms(1000)), 35.0);
  EXPECT_EQ(load.percent(at_ms(2100)), 0.0);
}

TEST(BusLoad, BackToBackActivitiesFillTheSecond) {
  BusLoad load;
  for (int64_t ms = 0; ms < 1000; ms += 100) {
    load.record(at_ms(ms), at_ms(ms + 100));
  }
  EXPECT_EQ(load.percent(at_ms(1000)), 100.0);
  EXPECT_EQ(load.percent(at_ms(1500)), 50.0);
}

}  // namespace
}  // namespace canemu::model
