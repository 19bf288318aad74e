#include "canemu/daemon/restbus/signal_codec.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

namespace canemu::daemon::restbus {

namespace {

// The payload's bits in the order a big-endian signal walks them: byte 0's bit 7 is 0, its bit 0
// is 7, byte 1's bit 7 is 8. A DBC start bit `p` (byte p / 8, bit p % 8) is position
// p / 8 * 8 + 7 - p % 8 there, and a big-endian signal runs from that position on, most
// significant bit first.
uint32_t msb_first_position(uint32_t dbc_bit) {
  return dbc_bit / 8 * 8 + 7 - dbc_bit % 8;
}

bool length_suits_type(const SignalLayout& s) {
  switch (s.type) {
    case SignalLayout::Type::float32:
      return s.length == 32;
    case SignalLayout::Type::float64:
      return s.length == 64;
    case SignalLayout::Type::integer:
      break;
  }
  return s.length >= 1 && s.length <= 64;
}

// Payload byte and bit of the signal's bit `k`, counted from its least significant bit.
struct BitPlace {
  uint32_t byte;
  uint32_t bit;
};
BitPlace place_of(const SignalLayout& s, uint32_t k) {
  if (s.byte_order == SignalLayout::ByteOrder::little_endian) {
    const uint32_t i = s.start + k;
    return {i / 8, i % 8};
  }
  const uint32_t q = msb_first_position(s.start) + (s.length - 1 - k);
  return {q / 8, 7 - q % 8};
}

uint64_t low_bits(uint32_t length) {
  return length >= 64 ? ~uint64_t{0} : (uint64_t{1} << length) - 1;
}

}  // namespace

bool fits(const SignalLayout& s, uint32_t bytes) {
  if (!length_suits_type(s)) {
    return false;
  }
  const uint64_t bits = uint64_t{bytes} * 8;
  if (s.byte_order == SignalLayout::ByteOrder::little_endian) {
    return uint64_t{s.start} + s.length <= bits;
  }
  return s.start < bits && uint64_t{msb_first_position(s.start)} + s.length <= bits;
}

uint64_t get_raw(std::span<const uint8_t> payload, const SignalLayout& s) {
  uint64_t raw = 0;
  for (uint32_t k = 0; k < s.length; ++k) {
    const BitPlace p = place_of(s, k);
    raw |= uint64_t{(payload[p.byte] >> p.bit) & 1u} << k;
  }
  return raw;
}

void put_raw(std::span<uint8_t> payload, const SignalLayout& s, uint64_t raw) {
  for (uint32_t k = 0; k < s.length; ++k) {
    const BitPlace p = place_of(s, k);
    const auto mask = static_cast<uint8_t>(1u << p.bit);
    payload[p.byte] = static_cast<uint8_t>(((raw >> k) & 1u) != 0 ? payload[p.byte] | mask
                                                                  : payload[p.byte] & ~mask);
  }
}

double to_physical(const SignalLayout& s, uint64_t raw) {
  raw &= low_bits(s.length);
  double value = 0;
  switch (s.type) {
    case SignalLayout::Type::float32:
      value = std::bit_cast<float>(static_cast<uint32_t>(raw));
      break;
    case SignalLayout::Type::float64:
      value = std::bit_cast<double>(raw);
      break;
    case SignalLayout::Type::integer:
      if (s.is_signed && s.length < 64 && ((raw >> (s.length - 1)) & 1u) != 0) {
        raw |= ~low_bits(s.length);  // sign-extended
      }
      value =
          s.is_signed ? static_cast<double>(static_cast<int64_t>(raw)) : static_cast<double>(raw);
      break;
  }
  return value * s.scale + s.offset;
}

Result<uint64_t> to_raw(const SignalLayout& s, double physical) {
  if (!std::isfinite(physical)) {
    return fail(Errc::bad_argument, fmt::format("{} is not a number a signal can carry", physical));
  }
  const double scaled = (physical - s.offset) / s.scale;
  switch (s.type) {
    case SignalLayout::Type::float32: {
      if (std::isfinite(scaled) && std::fabs(scaled) > std::numeric_limits<float>::max()) {
        return fail(Errc::bad_argument,
                    fmt::format("{} is beyond what a 32-bit float holds", physical));
      }
      return std::bit_cast<uint32_t>(static_cast<float>(scaled));
    }
    case SignalLayout::Type::float64:
      return std::bit_cast<uint64_t>(scaled);
    case SignalLayout::Type::integer:
      break;
  }
  // Halves to even: std::nearbyint in the default rounding mode, as Python's round().
  const double rounded = std::nearbyint(scaled);
  // The raw range as doubles: exact for the bounds (powers of two) up to 64 bits.
  const double lowest = s.is_signed ? -std::ldexp(1.0, static_cast<int>(s.length) - 1) : 0.0;
  const double limit = std::ldexp(1.0, static_cast<int>(s.length) - (s.is_signed ? 1 : 0));
  if (!(rounded >= lowest && rounded < limit)) {
    const double low_physical = lowest * s.scale + s.offset;
    const double high_physical = (limit - 1) * s.scale + s.offset;
    return fail(
        Errc::bad_argument,
        fmt::format("{} is outside what {} {} bits hold ({} .. {})", physical, s.length,
                    s.is_signed ? "signed" : "unsigned", std::min(low_physical, high_physical),
                    std::max(low_physical, high_physical)));
  }
  if (s.is_signed) {
    return static_cast<uint64_t>(static_cast<int64_t>(rounded)) & low_bits(s.length);
  }
  return static_cast<uint64_t>(rounded);
}

uint8_t crc8_sae_j1850(std::span<const uint8_t> bytes) {
  uint8_t crc = 0xFF;
  for (const uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) {
      crc = static_cast<uint8_t>((crc & 0x80) != 0 ? (crc << 1) ^ 0x1D : crc << 1);
    }
  }
  return static_cast<uint8_t>(crc ^ 0xFF);
}

uint8_t checksum(ChecksumKind kind, uint16_t data_id, std::span<const uint8_t> payload,
                 uint32_t at) {
  switch (kind) {
    case ChecksumKind::none:
      return 0;
    case ChecksumKind::crc8_sae_j1850: {
      // One pass over data ID and payload: CRC-8 in a buffer of at most 2 + 64 bytes.
      uint8_t buffer[2 + 64];
      std::size_t n = 0;
      buffer[n++] = static_cast<uint8_t>(data_id & 0xFF);
      buffer[n++] = static_cast<uint8_t>(data_id >> 8);
      for (std::size_t i = 0; i < payload.size() && n < sizeof buffer; ++i) {
        if (i != at) {
          buffer[n++] = payload[i];
        }
      }
      return crc8_sae_j1850(std::span<const uint8_t>(buffer, n));
    }
    case ChecksumKind::xor8: {
      uint8_t x = 0;
      for (std::size_t i = 0; i < payload.size(); ++i) {
        x = static_cast<uint8_t>(i != at ? x ^ payload[i] : x);
      }
      return x;
    }
    case ChecksumKind::sum8: {
      unsigned sum = 0;
      for (std::size_t i = 0; i < payload.size(); ++i) {
        sum += i != at ? payload[i] : 0u;
      }
      return static_cast<uint8_t>(sum & 0xFF);
    }
  }
  return 0;
}

}  // namespace canemu::daemon::restbus
