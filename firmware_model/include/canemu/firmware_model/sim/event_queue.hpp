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
    if (taken_) {
      // The top was taken (take_due): the new entry takes its place.
      taken_ = false;
      room_[0] = Entry{time, id, std::move(payload), false};
      place_top();
      return id;
    }
    if (count_ == room_.size()) {
      grow();
    }
    room_[count_] = Entry{time, id, std::move(payload), false};
    ++count_;
    if (count_ > 1) {
      sift_up(count_ - 1);  // out of line: a lone entry (a bus's next event) needs none
    }
    return id;
  }

  // Returns false if the event already ran, was cancelled, or never existed.
  bool cancel(EventId id) {
    settle();
    for (std::size_t k = 0; k < count_; ++k) {
      Entry& e = room_[k];
      if (e.id == id && !e.cancelled) {
        e.cancelled = true;
        ++cancelled_;
        return true;
      }
    }
    return false;
  }

  // The payload of a pending event, or nullptr.
  const Payload* find(EventId id) const {
    for (std::size_t k = taken_ ? 1 : 0; k < count_; ++k) {
      const Entry& e = room_[k];
      if (e.id == id && !e.cancelled) {
        return &e.payload;
      }
    }
    return nullptr;
  }

  bool empty() const { return size() == 0; }
  std::size_t size() const { return count_ - cancelled_ - (taken_ ? 1 : 0); }

  std::optional<SimTime> next_time() {
    settle();
    drop_cancelled();
    if (count_ == 0) {
      return std::nullopt;
    }
    return room_[0].time;
  }

  // Whether an event may be due at or before `t`: an entry of the heap other than the one
  // take_due() took, cancelled or not (a cancelled one answers yes, which is only ever safe). Its
  // earliest lies at the top, or with the top taken in one of the top's two children.
  bool any_due_by(SimTime t) const {
    if (!taken_) {
      return count_ != 0 && room_[0].time <= t;
    }
    return (count_ > 1 && room_[1].time <= t) || (count_ > 2 && room_[2].time <= t);
  }

  // Removes and returns the earliest event, if any.
  std::optional<Entry> pop() {
    settle();
    drop_cancelled();
    if (count_ == 0) {
      return std::nullopt;
    }
    std::optional<Entry> e(std::move(room_[0]));
    remove_top();
    return e;
  }

  // Takes the earliest event if it is due at or before `limit`: its time and payload into `time`
  // and `payload` (field by field, not as an Entry: the entry was usually written just before,
  // and a wide copy of it would wait for those stores); false if none is due. The entry leaves
  // the heap only at the next call: a push then takes its place (one restore of the heap instead
  // of a pop's and a push's, so that an event's handler that schedules its follow-up, as a bus's
  // end of frame and bus free do, pays for one), any other call removes it first. So every call
  // sees the queue as if the event had been removed at once.
  bool take_due(SimTime limit, SimTime& time, Payload& payload) {
    settle();
    drop_cancelled();
    if (count_ == 0 || room_[0].time > limit) {
      return false;
    }
    time = room_[0].time;
    payload = std::move(room_[0].payload);
    taken_ = true;
    return true;
  }
  // Removes the entry take_due() took, if no push has taken its place.
  void settle() {
    if (taken_) {
      taken_ = false;
      remove_top();
    }
  }

 private:
  // A binary heap by hand over room_[0, count_): the few pending events of an island cost a
  // compare or two per push and pop, without the generic algorithms' set-up. (time, id) is a
  // total order, so the order events come out in does not depend on how the heap is arranged.
  // The room is grown by hand (entries past count_ are left as they are), so that a push or
  // pop of the common lone entry is a few stores, not a std::vector's growth path.
  static bool later(const Entry& a, const Entry& b) {
    if (a.time != b.time) {
      return a.time > b.time;
    }
    return a.id > b.id;
  }

  [[gnu::noinline]] void grow() { room_.resize(room_.empty() ? 16 : 2 * room_.size()); }

  [[gnu::noinline]] void sift_up(std::size_t i) {
    while (i > 0) {
      const std::size_t parent = (i - 1) / 2;
      if (!later(room_[parent], room_[i])) {
        return;
      }
      std::swap(room_[parent], room_[i]);
      i = parent;
    }
  }

  // Removes the top entry and restores the heap.
  void remove_top() {
    const std::size_t n = --count_;
    if (n == 0) {
      return;  // the last one: nothing to restore
    }
    room_[0] = std::move(room_[n]);
    place_top();
  }
  // Restores the heap after room_[0] was replaced. An entry that belongs at the top (the
  // follow-up of an event just run, due soon) stays there after one compare. Any other goes
  // bottom up: the hole it leaves goes down to a leaf, each step taking the earlier child (one
  // compare a level), and the entry goes in there and up as far as it must, seldom far for one
  // of the latest (a bus's next end of frame, behind every other bus's next event; canemud at
  // 64 busy buses keeps some 130 entries). That is about half the compares and stores of
  // sifting it down from the top.
  [[gnu::noinline]] void place_top() {
    const std::size_t n = count_;
    if (n < 2) {
      return;
    }
    const std::size_t first = n > 2 && later(room_[1], room_[2]) ? 2 : 1;
    if (!later(room_[0], room_[first])) {
      return;
    }
    Entry e = std::move(room_[0]);
    room_[0] = std::move(room_[first]);
    std::size_t i = first;
    for (std::size_t l = 2 * i + 1; l < n; l = 2 * i + 1) {
      const std::size_t c = l + 1 < n && later(room_[l], room_[l + 1]) ? l + 1 : l;
      room_[i] = std::move(room_[c]);
      i = c;
    }
    while (i > 0) {
      const std::size_t parent = (i - 1) / 2;
      if (!later(room_[parent], e)) {
        break;
      }
      room_[i] = std::move(room_[parent]);
      i = parent;
    }
    room_[i] = std::move(e);
  }

  // Cancelled entries are counted, so that a queue without any (nearly always) skips the look.
  void drop_cancelled() {
    if (cancelled_ == 0) {
      return;
    }
    while (count_ != 0 && room_[0].cancelled) {
      remove_top();
      --cancelled_;
    }
  }

  std::vector<Entry> room_;
  std::size_t count_ = 0;  // entries in the heap: room_[0, count_)
  EventId next_id_ = 1;
  std::size_t cancelled_ = 0;  // entries marked cancelled, still in the heap
  bool taken_ = false;         // room_[0] was taken (take_due) and is no longer an event
};

}  // namespace canemu::model
