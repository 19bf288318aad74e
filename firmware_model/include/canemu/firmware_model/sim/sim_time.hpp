// Simulated time: integer nanoseconds since the start of a simulation.
//
// The model never reads a wall clock. The daemon maps its clock (realtime, scaled or stepped)
// onto SimTime and drives the model with it; tests step it by hand.
#pragma once

#include <compare>
#include <cstdint>

namespace canemu::model {

class SimDuration {
 public:
  constexpr SimDuration() = default;
  constexpr explicit SimDuration(int64_t ns) : ns_(ns) {}
  constexpr int64_t ns() const { return ns_; }

  constexpr SimDuration& operator+=(SimDuration d) {
    ns_ += d.ns_;
    return *this;
  }
  constexpr SimDuration& operator-=(SimDuration d) {
    ns_ -= d.ns_;
    return *this;
  }
  friend constexpr SimDuration operator+(SimDuration a, SimDuration b) {
    return SimDuration(a.ns_ + b.ns_);
  }
  friend constexpr SimDuration operator-(SimDuration a, SimDuration b) {
    return SimDuration(a.ns_ - b.ns_);
  }
  friend constexpr SimDuration operator*(SimDuration a, int64_t k) {
    return SimDuration(a.ns_ * k);
  }
  friend constexpr SimDuration operator*(int64_t k, SimDuration a) {
    return SimDuration(a.ns_ * k);
  }
  friend constexpr auto operator<=>(SimDuration, SimDuration) = default;

 private:
  int64_t ns_ = 0;
};

constexpr SimDuration nanoseconds(int64_t n) {
  return SimDuration(n);
}
constexpr SimDuration microseconds(int64_t n) {
  return SimDuration(n * 1'000);
}
constexpr SimDuration milliseconds(int64_t n) {
  return SimDuration(n * 1'000'000);
}
constexpr SimDuration seconds(int64_t n) {
  return SimDuration(n * 1'000'000'000);
}

class SimTime {
 public:
  constexpr SimTime() = default;
  static constexpr SimTime from_ns(int64_t ns) { return SimTime(ns); }
  constexpr int64_t ns() const { return ns_; }

  constexpr SimTime& operator+=(SimDuration d) {
    ns_ += d.ns();
    return *this;
  }
  friend constexpr SimTime operator+(SimTime t, SimDuration d) { return SimTime(t.ns_ + d.ns()); }
  friend constexpr SimTime operator-(SimTime t, SimDuration d) { return SimTime(t.ns_ - d.ns()); }
  friend constexpr SimDuration operator-(SimTime a, SimTime b) {
    return SimDuration(a.ns_ - b.ns_);
  }
  friend constexpr auto operator<=>(SimTime, SimTime) = default;

 private:
  constexpr explicit SimTime(int64_t ns) : ns_(ns) {}
  int64_t ns_ = 0;
};

}  // namespace canemu::model
