// The CRCs of CAN frames as wire_encoding.cpp computes them: CRC-15 for classic frames (64 bits
// a step), CRC-17 and CRC-21 for CAN FD (16 bits a step), each over a bit string whose first
// bit is its most significant.
#pragma once

#include <array>
#include <cstdint>

#include "canemu/firmware_model/bus/bit_timing.hpp"  // uint128

namespace canemu::model::detail {

// CRC generator polynomials without their top bit (ISO 11898-1:2015, 10.4.2.6).
inline constexpr uint32_t kCrc15Poly = 0x4599;
inline constexpr uint32_t kCrc17Poly = 0x1685B;
inline constexpr uint32_t kCrc21Poly = 0x102899;

// Table-driven CRC over a bit string (MSB first), 16 bits per step. The register after 16
// input bits is linear in (register, input): it equals feeding (top 16 register bits ^ input)
// into a cleared register, plus the register shifted left by 16 when it is wider than 16 bits.
// That 16-bit feed splits into two 256-entry tables, looked up in parallel.
template <uint32_t Width, uint32_t Poly>
struct Crc {
  static constexpr uint32_t kMask = (1u << Width) - 1;

  static constexpr uint32_t step_bit(uint32_t crc, bool bit) {
    const uint32_t feedback = (bit ^ ((crc >> (Width - 1)) & 1u)) ? Poly : 0u;
    return ((crc << 1) & kMask) ^ feedback;
  }
  static constexpr uint32_t feed16(uint32_t v) {
    uint32_t crc = 0;
    for (int i = 15; i >= 0; --i) {
      crc = step_bit(crc, (v >> i) & 1u);
    }
    return crc;
  }
  static constexpr std::array<uint32_t, 256> make_table(uint32_t shift) {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      t[i] = feed16(i << shift);
    }
    return t;
  }
  static constexpr std::array<uint32_t, 256> kHigh = make_table(8);
  static constexpr std::array<uint32_t, 256> kLow = make_table(0);

  template <class Bits>
  static uint32_t over(const Bits& s, uint32_t bits, uint32_t crc) {
    uint32_t i = 0;
    for (; i + 16 <= bits; i += 16) {
      const uint32_t input = (s.byte_at(i) << 8) | s.byte_at(i + 8);
      const uint32_t top = Width >= 16 ? crc >> (Width - 16) : crc << (16 - Width);
      const uint32_t idx = (top ^ input) & 0xFFFF;
      const uint32_t rest = Width > 16 ? (crc << 16) & kMask : 0u;
      crc = rest ^ kHigh[idx >> 8] ^ kLow[idx & 0xFF];
    }
    for (; i < bits; ++i) {
      crc = step_bit(crc, s.bit(i));
    }
    return crc;
  }
};

using Crc15 = Crc<15, kCrc15Poly>;

// CRC-15 of a classic frame, 64 bits a step. From a cleared register leading zeros change
// nothing, so the destuffed bits (at most 103) are read as two words padded in front; and 64 bits
// into the register are the register's 15 bits XORed onto the first 15 of them, then fed into a
// cleared register, which is linear in the 64 bits: eight byte tables, looked up in parallel.
using Crc15Tables = std::array<std::array<uint16_t, 256>, 8>;
constexpr Crc15Tables make_crc15_tables() {
  Crc15Tables t{};
  for (uint32_t k = 0; k < 8; ++k) {
    for (uint32_t b = 0; b < 256; ++b) {
      uint32_t crc = 0;
      for (uint32_t i = 0; i < 64; ++i) {
        // Bit i of the word (first = most significant) is bit 7 - (i - 8k) of byte k.
        const bool bit = i >= 8 * k && i < 8 * k + 8 && ((b >> (7 - (i - 8 * k))) & 1u) != 0;
        crc = Crc15::step_bit(crc, bit);
      }
      t[k][b] = static_cast<uint16_t>(crc);
    }
  }
  return t;
}

struct Crc15Wide {
  static constexpr Crc15Tables kTables = make_crc15_tables();

  // 64 bits, first at the top, into the register `crc`.
  static uint32_t feed64(uint32_t crc, uint64_t v) {
    v ^= uint64_t{crc} << 49;
    return uint32_t{kTables[0][v >> 56]} ^ kTables[1][(v >> 48) & 0xFF] ^
           kTables[2][(v >> 40) & 0xFF] ^ kTables[3][(v >> 32) & 0xFF] ^
           kTables[4][(v >> 24) & 0xFF] ^ kTables[5][(v >> 16) & 0xFF] ^
           kTables[6][(v >> 8) & 0xFF] ^ kTables[7][v & 0xFF];
  }
  // Over the first `bits` (at most 128) of `x`, first bit at bit 127, from a cleared register.
  // The bits are moved to the end of the two words, so that the first holds bits - 64 of them
  // behind zeros: up to 24 (a standard frame's 83 destuffed bits before its CRC), three of its
  // bytes are looked up, not eight (a zero byte into a cleared register leaves it cleared).
  static uint32_t over(uint128 x, uint32_t bits) {
    const uint128 v = x >> (128 - bits);
    const auto hi = static_cast<uint64_t>(v >> 64);
    const uint32_t crc =
        hi < (uint64_t{1} << 24)
            ? uint32_t{kTables[5][hi >> 16]} ^ kTables[6][(hi >> 8) & 0xFF] ^ kTables[7][hi & 0xFF]
            : feed64(0, hi);
    return feed64(crc, static_cast<uint64_t>(v));
  }
};
using Crc17 = Crc<17, kCrc17Poly>;
using Crc21 = Crc<21, kCrc21Poly>;

}  // namespace canemu::model::detail
