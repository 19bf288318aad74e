// A list of at most one entry per node of a bus, filled anew for every frame (contenders,
// arbitration losses, the transmitters in flight): its room is made once for the bus's node count
// (`fit`), so adding an entry is a store and a count, without a std::vector's check for room on
// every push_back.
#pragma once

#include <cassert>
#include <cstddef>
#include <span>
#include <vector>

namespace canemu::model {

template <class T>
class NodeList {
 public:
  // Room for `n` entries; what the list holds is kept.
  void fit(std::size_t n) {
    if (room_.size() < n) {
      room_.resize(n);
    }
  }
  void clear() { size_ = 0; }
  // Adds `v`; the list must have room for it (fit).
  void push_back(const T& v) {
    assert(size_ < room_.size());
    room_[size_++] = v;
  }

  // Removes the entries `pred` holds for, keeping the others in order.
  template <class Pred>
  void erase_if(Pred pred) {
    std::size_t kept = 0;
    for (std::size_t k = 0; k < size_; ++k) {
      if (!pred(room_[k])) {
        room_[kept++] = room_[k];
      }
    }
    size_ = kept;
  }

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const T& operator[](std::size_t k) const { return room_[k]; }
  T& operator[](std::size_t k) { return room_[k]; }
  const T* begin() const { return room_.data(); }
  const T* end() const { return room_.data() + size_; }
  std::span<const T> span() const { return {room_.data(), size_}; }

 private:
  std::vector<T> room_;
  std::size_t size_ = 0;
};

}  // namespace canemu::model
