// LIN 2.x's protected identifier and checksum as the specification defines them, computed bit
// by bit and byte by byte, independently of the model's lin_frame.cpp: what the LIN capture
// tests compare the model's bytes with. And bytes as hex text for their messages.
#pragma once

#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <string>

namespace canemu::test_support::lin {

inline int bit(int value, int n) {
  return (value >> n) & 1;
}

// The identifier with its parity bits P0 (bit 6) and P1 (bit 7).
inline uint8_t pid(int id) {
  const int p0 = bit(id, 0) ^ bit(id, 1) ^ bit(id, 2) ^ bit(id, 4);
  const int p1 = 1 - (bit(id, 1) ^ bit(id, 3) ^ bit(id, 4) ^ bit(id, 5));
  return static_cast<uint8_t>(id | (p0 << 6) | (p1 << 7));
}

// The inverted sum with each carry added back: classic over the data, enhanced over the PID
// and the data.
inline uint8_t inverted_sum(std::initializer_list<int> bytes) {
  int sum = 0;
  for (int b : bytes) {
    sum += b;
    if (sum > 0xFF) {
      sum -= 0xFF;
    }
  }
  return static_cast<uint8_t>(0xFF - sum);
}

template <class Bytes>
std::string hex(const Bytes& bytes) {
  std::string s;
  for (const auto b : bytes) {
    char two[3];
    std::snprintf(two, sizeof two, "%02X", static_cast<unsigned>(static_cast<uint8_t>(b)));
    s += two;
  }
  return s;
}

}  // namespace canemu::test_support::lin
