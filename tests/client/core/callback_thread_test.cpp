// The client core's callback thread (X-CAN-2i buffered callbacks, SL-CANi service routines):
// entries run in order on one thread that is not the caller's, a bound refuses what does not
// fit, clear forgets what waits, and the end runs or drops what is left as asked.
#include "canemu/client/callback_thread.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace canemu::client {
namespace {

using namespace std::chrono_literals;

// What the callback thread saw, and a gate that holds it in its first call until opened.
struct Recorder {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<int> seen;
  std::vector<std::thread::id> threads;
  bool gate_open = true;
  bool in_first = false;

  void run(int item) {
    std::unique_lock lock(mutex);
    if (seen.empty()) {
      in_first = true;
      changed.notify_all();
      changed.wait(lock, [&] { return gate_open; });
    }
    seen.push_back(item);
    threads.push_back(std::this_thread::get_id());
    changed.notify_all();
  }
  bool wait_for_count(std::size_t n) {
    std::unique_lock lock(mutex);
    return changed.wait_for(lock, 10s, [&] { return seen.size() >= n; });
  }
  bool wait_in_first() {
    std::unique_lock lock(mutex);
    return changed.wait_for(lock, 10s, [&] { return in_first; });
  }
  void open_gate() {
    std::lock_guard lock(mutex);
    gate_open = true;
    changed.notify_all();
  }
};

TEST(ClientCallbackThread, RunsEntriesInOrderOnItsOwnThread) {
  Recorder r;
  CallbackThread<int> t([&](const int& i) { r.run(i); }, CallbackThread<int>::AtEnd::drop_queued);
  t.start();
  t.start();  // a second start changes nothing
  for (int i = 0; i < 100; ++i) {
    ASSERT_TRUE(t.push(i));
  }
  ASSERT_TRUE(r.wait_for_count(100));
  std::lock_guard lock(r.mutex);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(r.seen[i], i);
    EXPECT_EQ(r.threads[i], r.threads[0]);
  }
  EXPECT_NE(r.threads[0], std::this_thread::get_id());
}

TEST(ClientCallbackThread, ABoundRefusesWhatDoesNotFitAndClearForgets) {
  Recorder r;
  r.gate_open = false;
  CallbackThread<int> t([&](const int& i) { r.run(i); }, CallbackThread<int>::AtEnd::drop_queued,
                        2);
  t.start();
  ASSERT_TRUE(t.push(0));
  ASSERT_TRUE(r.wait_in_first());  // 0 is running (held at the gate), the queue is empty
  EXPECT_TRUE(t.push(1));
  EXPECT_TRUE(t.push(2));
  EXPECT_FALSE(t.push(3));  // two wait: the bound
  t.clear();
  EXPECT_TRUE(t.push(4));
  r.open_gate();
  ASSERT_TRUE(r.wait_for_count(2));
  std::lock_guard lock(r.mutex);
  EXPECT_EQ(r.seen, (std::vector<int>{0, 4}));
}

TEST(ClientCallbackThread, TheEndRunsOrDropsWhatWaits) {
  for (const auto at_end :
       {CallbackThread<int>::AtEnd::run_queued, CallbackThread<int>::AtEnd::drop_queued}) {
    Recorder r;
    r.gate_open = false;
    {
      CallbackThread<int> t([&](const int& i) { r.run(i); }, at_end);
      t.start();
      t.push(0);
      ASSERT_TRUE(r.wait_in_first());  // 0 runs, held at the gate
      t.push(1);
      t.push(2);
      t.stop();
      r.open_gate();
    }  // the destructor waits for the thread
    std::lock_guard lock(r.mutex);
    const std::vector<int> expected = at_end == CallbackThread<int>::AtEnd::run_queued
                                          ? std::vector<int>{0, 1, 2}
                                          : std::vector<int>{0};
    EXPECT_EQ(r.seen, expected);
  }
}

}  // namespace
}  // namespace canemu::client
