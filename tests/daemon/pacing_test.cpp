// The lateness histogram and the spin that follows the timer (daemon/src/pacing.cpp).
#include "canemu/daemon/loop/pacing.hpp"

#include <gtest/gtest.h>

namespace canemu::daemon {
namespace {

TEST(LatenessHistogram, BucketsAreExactBelow32NsThenSixteenPerPowerOfTwo) {
  for (int64_t v = 0; v < 32; ++v) {
    EXPECT_EQ(LatenessHistogram::bucket_of(v), static_cast<std::size_t>(v));
    EXPECT_EQ(LatenessHistogram::upper_bound_of(static_cast<std::size_t>(v)), v);
  }
  // 32..63 in buckets two wide, 64..127 four wide, 1,000,000 (2^19 <= v < 2^20) 2^15 wide.
  EXPECT_EQ(LatenessHistogram::bucket_of(32), 32u);
  EXPECT_EQ(LatenessHistogram::bucket_of(33), 32u);
  EXPECT_EQ(LatenessHistogram::upper_bound_of(32), 33);
  EXPECT_EQ(LatenessHistogram::bucket_of(63), 47u);
  EXPECT_EQ(LatenessHistogram::bucket_of(64), 48u);
  EXPECT_EQ(LatenessHistogram::upper_bound_of(48), 67);
  EXPECT_EQ(LatenessHistogram::bucket_of(1'000'000), 15u * 16 + 30);
  EXPECT_EQ(LatenessHistogram::upper_bound_of(15 * 16 + 30), 1'015'807);
  EXPECT_EQ(LatenessHistogram::bucket_of(INT64_MAX), LatenessHistogram::kBuckets - 1);
  EXPECT_EQ(LatenessHistogram::upper_bound_of(LatenessHistogram::kBuckets - 1), INT64_MAX);
  // Every bucket's bound is the last value it holds.
  for (std::size_t i = 0; i + 1 < LatenessHistogram::kBuckets; ++i) {
    const int64_t top = LatenessHistogram::upper_bound_of(i);
    ASSERT_EQ(LatenessHistogram::bucket_of(top), i);
    ASSERT_EQ(LatenessHistogram::bucket_of(top + 1), i + 1);
  }
}

TEST(LatenessHistogram, QuantilesAreBucketBoundsCappedByTheMax) {
  LatenessHistogram h;
  EXPECT_EQ(h.figures().count, 0u);
  EXPECT_EQ(h.quantile(0.5), 0);
  for (int64_t v = 1; v <= 100; ++v) {
    h.add(v * 1000);  // 1 us .. 100 us
  }
  h.add(-5);  // a clock that read a hair early counts as on time
  const ipc::WirePacingFigures f = h.figures();
  EXPECT_EQ(f.count, 101u);
  // The 51st value is 50,000 ns: bucket 2^15 <= v < 2^16, 2^11 wide: 49,152..51,199.
  EXPECT_EQ(f.p50_ns, 51'199);
  // The 100th value is 99,000 ns: bucket 98,304..102,399; capped by the max, 100,000.
  EXPECT_EQ(f.p99_ns, 100'000);
  EXPECT_EQ(f.max_ns, 100'000);
  h.clear();
  EXPECT_EQ(h.figures().count, 0u);
  EXPECT_EQ(h.figures().max_ns, 0);
}

TEST(Pacing, IntervalsRotateAfterASecondAndTheSpinFollowsTheTimersP99) {
  Pacing p(20'000);  // spin_us 20
  EXPECT_EQ(p.spin_ns(), 20'000);
  p.tick(1'000);  // the first interval starts
  for (int i = 0; i < 99; ++i) {
    p.timer_late(3'000);
    p.event_late(10'000);
  }
  p.timer_late(9'000);
  p.event_late(40'000);
  p.wakeup_late(0);
  p.tick(500'000'000);  // within the interval: nothing changes
  ipc::WirePacing w;
  p.fill(w);
  EXPECT_EQ(w.events.count, 100u);
  EXPECT_EQ(w.events_last.count, 0u);
  EXPECT_EQ(p.spin_ns(), 20'000);
  p.tick(1'000'001'000);  // a second after the first tick
  p.fill(w);
  EXPECT_EQ(w.events_last.count, 100u);
  EXPECT_EQ(w.events_last.p50_ns, 10'239);  // bucket 9,728..10,239
  EXPECT_EQ(w.events_last.p99_ns, 10'239);
  EXPECT_EQ(w.events_last.max_ns, 40'000);
  EXPECT_EQ(w.wakeups_last.count, 1u);
  EXPECT_EQ(w.timer_last.p99_ns, 3'071);  // bucket 2,944..3,071
  EXPECT_EQ(p.spin_ns(), 3'071);
  EXPECT_EQ(w.spin_ns, 3'071);
  EXPECT_EQ(w.max_spin_ns, 20'000);
  // A timer later than spin_us allows: the spin stops at the maximum.
  for (int i = 0; i < 100; ++i) {
    p.timer_late(80'000);
  }
  p.tick(2'000'001'000);
  EXPECT_EQ(p.spin_ns(), 20'000);
  // Too few firings in an interval (an idle loop): the spin stays where it was.
  for (int i = 0; i < 10; ++i) {
    p.timer_late(1'000);
  }
  p.tick(3'000'001'000);
  EXPECT_EQ(p.spin_ns(), 20'000);
  p.fill(w);
  EXPECT_EQ(w.events.count, 100u);  // since start keeps everything
  EXPECT_EQ(w.events_last.count, 0u);
  EXPECT_EQ(w.timer.count, 210u);
}

}  // namespace
}  // namespace canemu::daemon
