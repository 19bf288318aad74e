// The event loop's batch window: batch_us while events come sparsely, doubling towards
// batch_max_us while they come densely, back at once when they thin out
// (daemon/include/canemu/daemon/loop/batch_window.hpp).
#include "canemu/daemon/loop/batch_window.hpp"

#include <gtest/gtest.h>

namespace canemu::daemon {
namespace {

constexpr int64_t kUs = 1000;

TEST(BatchWindow, SparseEventsKeepBatchUs) {
  BatchWindow w;
  w.configure(50, 1000);
  int64_t t = 0;
  w.woke(0, t);
  // One bus at full load: a frame (two events) every 130 us, 15,400 events a second.
  for (int k = 0; k < 100; ++k) {
    t += 130 * kUs;
    EXPECT_EQ(w.woke(2, t), 50 * kUs) << "wake-up " << k;
  }
}

TEST(BatchWindow, DenseEventsDoubleItUpToBatchMaxUsAndThinningOnesBringItBackAtOnce) {
  BatchWindow w;
  w.configure(50, 1000);
  int64_t t = 0;
  w.woke(0, t);
  // 64 busy buses: about one event a microsecond, whatever the window.
  const int64_t expected[] = {100, 200, 400, 800, 1000, 1000};
  int64_t window = w.window_ns();
  for (const int64_t e : expected) {
    t += window;
    window = w.woke(static_cast<uint64_t>(window / kUs), t);
    EXPECT_EQ(window, e * kUs);
  }
  // Exactly the busy rate (160,000 a second: 160 in 1 ms) keeps it wide; between half of it
  // and it nothing changes; below half it is batch_us again at the next wake-up.
  t += 1000 * kUs;
  EXPECT_EQ(w.woke(160, t), 1000 * kUs);
  t += 1000 * kUs;
  EXPECT_EQ(w.woke(80, t), 1000 * kUs);
  EXPECT_TRUE(w.widened());
  t += 1000 * kUs;
  EXPECT_EQ(w.woke(79, t), 50 * kUs);
  EXPECT_FALSE(w.widened());
  // A lone frame after the load: its wake-up sees few events over a long span.
  t += 20'000 * kUs;
  EXPECT_EQ(w.woke(1, t), 50 * kUs);
}

TEST(BatchWindow, NoWideningWhenBatchMaxUsIsNotAboveBatchUs) {
  for (const uint32_t max_us : {0u, 50u}) {
    BatchWindow w;
    w.configure(50, max_us);
    int64_t t = 0;
    w.woke(0, t);
    for (int k = 0; k < 10; ++k) {
      t += 50 * kUs;
      EXPECT_EQ(w.woke(1000, t), 50 * kUs) << "batch_max_us " << max_us;
    }
  }
}

TEST(BatchWindow, FromBatchUsZeroTheFirstWideningIs100Us) {
  BatchWindow w;
  w.configure(0, 1000);
  EXPECT_EQ(w.window_ns(), 0);
  int64_t t = 0;
  w.woke(0, t);
  t += 10 * kUs;
  EXPECT_EQ(w.woke(10, t), 100 * kUs);  // a million events a second
  t += 100 * kUs;
  EXPECT_EQ(w.woke(100, t), 200 * kUs);
}

TEST(BatchWindow, ConfiguringTheSameValuesAgainKeepsTheWindowAndNewOnesResetIt) {
  BatchWindow w;
  w.configure(50, 1000);
  int64_t t = 0;
  w.woke(0, t);
  t += 50 * kUs;
  ASSERT_EQ(w.woke(1000, t), 100 * kUs);
  w.configure(50, 1000);  // every turn of the loop does this
  EXPECT_EQ(w.window_ns(), 100 * kUs);
  w.configure(20, 1000);  // a reload
  EXPECT_EQ(w.window_ns(), 20 * kUs);
}

}  // namespace
}  // namespace canemu::daemon
