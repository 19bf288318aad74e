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

// The load over time, in bins of 100 ms: an activity across a bin boundary counts in both.
TEST(BusLoad, TheHistoryHasTheBusyTimeOfEveryEndedBinIdleOnesIncluded) {
  BusLoad load;
  load.record(at_ms(50), at_ms(60));
  load.record(at_ms(190), at_ms(230));
  load.record(at_ms(420), at_ms(421));
  const auto bins = load.history(at_ms(450));  // bin 4 has not ended
  ASSERT_EQ(bins.size(), 4u);
  const int64_t ms = 1'000'000;
  EXPECT_EQ(bins[0].start, at_ms(0));
  EXPECT_EQ(bins[0].busy.ns(), 10 * ms);
  EXPECT_EQ(bins[1].busy.ns(), 10 * ms);
  EXPECT_EQ(bins[2].start, at_ms(200));
  EXPECT_EQ(bins[2].busy.ns(), 30 * ms);
  EXPECT_EQ(bins[3].busy.ns(), 0);
  EXPECT_EQ(load.history(at_ms(500)).back().busy.ns(), 1 * ms);
  EXPECT_TRUE(BusLoad().history(at_ms(99)).empty());
}

TEST(BusLoad, TheHistoryKeepsTheNewestFiveMinutes) {
  BusLoad load;
  load.record(at_ms(0), at_ms(100));
  load.record(at_ms(600'000), at_ms(600'050));  // ten minutes later
  const auto bins = load.history(at_ms(600'100));
  ASSERT_EQ(bins.size(), BusLoad::kHistoryBins);
  EXPECT_EQ(bins.front().start, at_ms(600'100 - 300'000));
  EXPECT_EQ(bins.back().start, at_ms(600'000));
  EXPECT_EQ(bins.back().busy.ns(), 50'000'000);
  EXPECT_EQ(bins[0].busy.ns(), 0);
  // Activities that keep coming push the oldest bins out.
  BusLoad busy;
  for (int64_t k = 0; k < 4000; ++k) {
    busy.record(at_ms(100 * k), at_ms(100 * k + 25));
  }
  const auto kept = busy.history(at_ms(400'000));
  ASSERT_EQ(kept.size(), BusLoad::kHistoryBins);
  EXPECT_EQ(kept.front().start, at_ms(100'000));
  EXPECT_EQ(kept.front().busy.ns(), 25'000'000);
}

}  // namespace
}  // namespace canemu::model
