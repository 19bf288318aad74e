// Bus load over the last second of simulated time.
#include "canemu/firmware_model/bus/bus_load.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

#include "case_name.hpp"

namespace canemu::model {
namespace {

SimTime at_ms(int64_t ms) {
  return SimTime{} + milliseconds(ms);
}

// Activities on the bus (start and end, in ms) and the load seen at given instants.
struct LoadCase {
  const char* name;
  std::vector<std::pair<int64_t, int64_t>> busy;
  std::vector<std::pair<int64_t, double>> percent_at;
};

class BusLoadPercent : public ::testing::TestWithParam<LoadCase> {};

TEST_P(BusLoadPercent, IsTheBusyTimeOfTheSecondBeforeNow) {
  BusLoad load;
  for (const auto& [from, to] : GetParam().busy) {
    load.record(at_ms(from), at_ms(to));
  }
  for (const auto& [now, percent] : GetParam().percent_at) {
    EXPECT_EQ(load.percent(at_ms(now)), percent) << "at " << now << " ms";
  }
}

INSTANTIATE_TEST_SUITE_P(
    BusLoad, BusLoadPercent,
    ::testing::Values(LoadCase{"AnIdleBusHasNoLoad", {}, {{1000, 0.0}}},
                      LoadCase{"BusyTimeCountsAgainstAWholeSecondEvenEarlyOn",
                               {{0, 250}},
                               {{500, 25.0}, {1000, 25.0}}},
                      // At 1100 ms, from 100 ms: 150 ms of the first activity, all 200 ms of the
                      // second; at 1000 ms the second activity counts up to now only.
                      LoadCase{"OnlyTheSecondBeforeNowCounts",
                               {{0, 250}, {900, 1100}},
                               {{1100, 35.0}, {1000, 35.0}, {2100, 0.0}}},
                      LoadCase{"BackToBackActivitiesFillTheSecond",
                               {{0, 100},
                                {100, 200},
                                {200, 300},
                                {300, 400},
                                {400, 500},
                                {500, 600},
                                {600, 700},
                                {700, 800},
                                {800, 900},
                                {900, 1000}},
                               {{1000, 100.0}, {1500, 50.0}}}),
    test_support::CaseName{});

// percent() sums what lies between its edges from running totals: against the busy time added
// up activity by activity, at instants before, inside and after them, for activities that follow
// one another (frames with gaps, back to back) and for ones that overlap.
TEST(BusLoad, PercentIsTheSumOfEveryActivityClippedToTheSecond) {
  for (const bool overlap : {false, true}) {
    std::mt19937_64 rng(overlap ? 7 : 3);
    BusLoad load;
    std::vector<std::pair<int64_t, int64_t>> kept;  // in us
    int64_t t = 0;
    for (int i = 0; i < 3000; ++i) {
      const int64_t gap = static_cast<int64_t>(rng() % 400);
      const int64_t start = overlap && i % 7 == 3 ? t - static_cast<int64_t>(rng() % 50) : t + gap;
      const int64_t end = std::max(start + 1 + static_cast<int64_t>(rng() % 300), t);
      load.record(SimTime{} + microseconds(start), SimTime{} + microseconds(end));
      kept.emplace_back(start, end);
      t = end;
      if (i % 97 != 0) {
        continue;
      }
      for (const int64_t back : {int64_t{-500}, int64_t{0}, int64_t{150}, int64_t{900'000}}) {
        const int64_t now = t - back;
        int64_t busy = 0;
        for (const auto& [s, e] : kept) {
          if (e >= t - 2'000'000) {  // what record() keeps: two seconds before the latest end
            busy += std::max<int64_t>(0, std::min(e, now) - std::max(s, now - 1'000'000));
          }
        }
        EXPECT_DOUBLE_EQ(load.percent(SimTime{} + microseconds(now)),
                         100.0 * static_cast<double>(busy * 1000) / 1e9)
            << "overlap " << overlap << ", activity " << i << ", now " << now << " us";
      }
    }
  }
}

// What ended two seconds before the newest activity's end is forgotten, whether or not the ring
// needed its room: a bus held for two seconds after N back-to-back frames reads, half a second
// into the hold, the hold alone (the frames ended before it began, more than two seconds before
// its end), whatever N and so however full the ring was.
TEST(BusLoad, WhatEndedTwoSecondsBeforeTheNewestEndIsForgottenHoweverFullTheRing) {
  for (const int64_t n : {int64_t{5'000}, int64_t{8'192}, int64_t{16'384}, int64_t{20'000}}) {
    BusLoad load;
    const int64_t d = 1'000'000'000 / n;  // ns a frame
    for (int64_t k = 0; k < n; ++k) {
      load.record(SimTime::from_ns(k * d), SimTime::from_ns((k + 1) * d));
    }
    const SimTime held = SimTime::from_ns(n * d);
    load.record(held, held + milliseconds(2'010));
    EXPECT_DOUBLE_EQ(load.percent(held + milliseconds(500)), 50.0) << n << " frames";
    // A second later than the hold's start plus 1.5 s, still the hold alone.
    EXPECT_DOUBLE_EQ(load.percent(held + milliseconds(1'500)), 100.0) << n << " frames";
  }
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
