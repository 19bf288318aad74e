// A queue of timed events, ordered by (time, insertion order).
//
// Two events at the same instant always come out in the order they were pushed, so a run
// depends only on its inputs, never on heap layout or addresses. Cancellation marks the entry
// and leaves it in the heap; it is dropped when it reaches the top. Cancelling looks the entry
// up linearly: a simulation island holds a handful of pending events, not thousands.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model {

using EventId = uint64_t;

template <class Payload>
class EventQueue {
 public:
  struct Entry {
    SimTime time;
    EventId id = 0;
    Payload payload;
    bool cancelled = false;
  };

  EventId push(SimTime time, Payload payload) {
    const EventId id = next_id_++;
    heap_.push_back(Entry{time, id, std::move(payload), false});
    sift_up(heap_.size() - 1);
    ++live_;
    return id;
  }

  // Returns false if the event already ran, was cancelled, or never existed.
  bool cancel(EventId id) {
    for (Entry& e : heap_) {
      if (e.id == id && !e.cancelled) {
        e.cancelled = true;
        --live_;
        return true;
      }
    }
    return false;
  }

  // The payload of a pending event, or nullptr.
  const Payload* find(EventId id) const {
    for (const Entry& e : heap_) {
      if (e.id == id && !e.cancelled) {
        return &e.payload;
      }
    }
    return nullptr;
  }

  bool empty() const { return live_ == 0; }
  std::size_t size() const { return live_; }

  std::optional<SimTime> next_time() {
    drop_cancelled();
    if (heap_.empty()) {
      return std::nullopt;
    }
    return heap_.front().time;
  }

  // Removes and returns the earliest event, if any.
  std::optional<Entry> pop() {
    drop_cancelled();
    if (heap_.empty()) {
      return std::nullopt;
    }
    std::optional<Entry> e(std::move(heap_.front()));
    remove_top();
    --live_;
    return e;
  }

  // Removes the earliest event if it is due at or before `limit`: its time and payload into
  // `time` and `payload`; false if none is due. (Field by field, not as an Entry: the entry was
  // usually written just before, and a wide copy of it would wait for those stores.)
  bool pop_due(SimTime limit, SimTime& time, Payload& payload) {
    drop_cancelled();
    if (heap_.empty() || heap_.front().time > limit) {
      return false;
    }
    time = heap_.front().time;
    payload = std::move(heap_.front().payload);
    remove_top();
    --live_;
    return true;
  }

 private:
  // A binary heap by hand: the few pending events of an island cost a compare or two per push
  // and pop, without the generic algorithms' set-up. (time, id) is a total order, so the order
  // events come out in does not depend on how the heap is arranged.
  static bool later(const Entry& a, const Entry& b) {
    if (a.time != b.time) {
      return a.time > b.time;
    }
    return a.id > b.id;
  }

  void sift_up(std::size_t i) {
    while (i > 0) {
      const std::size_t parent = (i - 1) / 2;
      if (!later(heap_[parent], heap_[i])) {
        return;
      }
      std::swap(heap_[parent], heap_[i]);
      i = parent;
    }
  }

  // Replaces the top by the last entry and restores the heap.
  void remove_top() {
    const std::size_t n = heap_.size() - 1;
    if (n > 0) {
      heap_.front() = std::move(heap_.back());
    }
    heap_.pop_back();
    std::size_t i = 0;
    while (true) {
      const std::size_t l = 2 * i + 1;
      if (l >= n) {
        return;
      }
      const std::size_t c = l + 1 < n && later(heap_[l], heap_[l + 1]) ? l + 1 : l;
      if (!later(heap_[i], heap_[c])) {
        return;
      }
      std::swap(heap_[i], heap_[c]);
      i = c;
    }
  }

  void drop_cancelled() {
    while (!heap_.empty() && heap_.front().cancelled) {
      remove_top();
    }
  }

  std::vector<Entry> heap_;
  EventId next_id_ = 1;
  std::size_t live_ = 0;
};

}  // namespace canemu::model
