// The thread on which a client library runs an application's functions (X-CAN-2i buffered
// callbacks, SL-CANi service routines): the receive thread queues what canemud announced and
// goes back to reading; this thread takes the queue in order and calls `run` for each entry,
// without holding the queue's lock, so that the function may call the library again.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

namespace canemu::client {

template <class Item>
class CallbackThread {
 public:
  // What the destructor does with entries still queued: run them first, or drop them.
  enum class AtEnd : uint8_t { run_queued, drop_queued };
  // `limit`: at most this many entries wait (0: no limit); push refuses more.
  CallbackThread(std::function<void(const Item&)> run, AtEnd at_end, std::size_t limit = 0)
      : run_(std::move(run)), at_end_(at_end), limit_(limit) {}
  ~CallbackThread() {
    stop();
    if (thread_.joinable()) {
      thread_.join();
    }
  }
  CallbackThread(const CallbackThread&) = delete;
  CallbackThread& operator=(const CallbackThread&) = delete;

  // Starts the thread unless it runs (the first connection of a library starts it).
  void start() {
    std::lock_guard lock(mutex_);
    if (!thread_.joinable()) {
      thread_ = std::thread([this] { loop(); });
    }
  }
  // Queues `item`; false (nothing queued) when `limit` entries wait already or after stop().
  bool push(const Item& item) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_ || (limit_ != 0 && queue_.size() >= limit_)) {
        return false;
      }
      queue_.push_back(item);
    }
    queued_.notify_one();
    return true;
  }
  // Tells the thread to end (without waiting for it; the destructor does): after the entry it
  // runs, or once the queue is empty, as `at_end` says. Nothing queued from then on runs.
  void stop() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    queued_.notify_all();
  }
  // Forgets what waits (what a lost connection announced is nobody's business any more).
  void clear() {
    std::lock_guard lock(mutex_);
    queue_.clear();
  }

 private:
  void loop() {
    std::unique_lock lock(mutex_);
    while (true) {
      queued_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_ && (at_end_ == AtEnd::drop_queued || queue_.empty())) {
        return;
      }
      const Item item = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      run_(item);
      lock.lock();
    }
  }

  std::function<void(const Item&)> run_;
  AtEnd at_end_;
  std::size_t limit_;
  std::mutex mutex_;
  std::condition_variable queued_;
  std::deque<Item> queue_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace canemu::client
