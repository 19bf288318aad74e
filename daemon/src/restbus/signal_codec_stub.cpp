// Placeholder of the signal codec until its implementation is merged (then this file goes).
#include <bit>
#include <cmath>
#include <vector>

#include "canemu/daemon/restbus/signal_codec.hpp"

namespace canemu::daemon::restbus {

namespace {

// The payload bit of the signal's k-th bit from its most significant (k = 0) down.
template <typename F>
bool walk(const SignalLayout& s, uint32_t bytes, F f) {
  int64_t pos = s.start;
  if (s.byte_order == SignalLayout::ByteOrder::little_endian) {
    for (uint32_t i = 0; i < s.length; ++i) {
      const int64_t p = pos + i;
      if (p >= int64_t{bytes} * 8) {
        return false;
      }
      f(static_cast<uint32_t>(p), i);  // raw bit i
    }
    return true;
  }
  for (uint32_t k = 0; k < s.length; ++k) {
    if (pos < 0 || pos >= int64_t{bytes} * 8) {
      return false;
    }
    f(static_cast<uint32_t>(pos), s.length - 1 - k);
    pos = pos % 8 == 0 ? pos + 15 : pos - 1;
  }
  return true;
}

}  // namespace

bool fits(const SignalLayout& s, uint32_t bytes) {
  const uint32_t want = s.type == SignalLayout::Type::float32   ? 32
                        : s.type == SignalLayout::Type::float64 ? 64
                                                                : 0;
  if (s.length < 1 || s.length > 64 || (want != 0 && s.length != want)) {
    return false;
  }
  return walk(s, bytes, [](uint32_t, uint32_t) {});
}

uint64_t get_raw(std::span<const uint8_t> payload, const SignalLayout& s) {
  uint64_t raw = 0;
  walk(s, static_cast<uint32_t>(payload.size()), [&](uint32_t p, uint32_t bit) {
    if ((payload[p / 8] >> (p % 8)) & 1U) {
      raw |= uint64_t{1} << bit;
    }
  });
  return raw;
}

void put_raw(std::span<uint8_t> payload, const SignalLayout& s, uint64_t raw) {
  walk(s, static_cast<uint32_t>(payload.size()), [&](uint32_t p, uint32_t bit) {
    const auto mask = static_cast<uint8_t>(1U << (p % 8));
    if ((raw >> bit) & 1U) {
      payload[p / 8] |= mask;
    } else {
      payload[p / 8] &= static_cast<uint8_t>(~mask);
    }
  });
}

double to_physical(const SignalLayout& s, uint64_t raw) {
  double v = 0;
  if (s.type == SignalLayout::Type::float32) {
    v = std::bit_cast<float>(static_cast<uint32_t>(raw));
  } else if (s.type == SignalLayout::Type::float64) {
    v = std::bit_cast<double>(raw);
  } else if (s.is_signed && s.length < 64 && ((raw >> (s.length - 1)) & 1U)) {
    v = static_cast<double>(static_cast<int64_t>(raw | (~uint64_t{0} << s.length)));
  } else if (s.is_signed) {
    v = static_cast<double>(static_cast<int64_t>(raw));
  } else {
    v = static_cast<double>(raw);
  }
  return v * s.scale + s.offset;
}

Result<uint64_t> to_raw(const SignalLayout& s, double physical) {
  const double v = (physical - s.offset) / s.scale;
  if (std::isnan(v)) {
    return fail(Errc::bad_argument, "not a number");
  }
  if (s.type == SignalLayout::Type::float32) {
    return std::bit_cast<uint32_t>(static_cast<float>(v));
  }
  if (s.type == SignalLayout::Type::float64) {
    return std::bit_cast<uint64_t>(v);
  }
  const double r = std::nearbyint(v);
  const double span = std::ldexp(1.0, static_cast<int>(s.length));
  const double lo = s.is_signed ? -span / 2 : 0;
  const double hi = s.is_signed ? span / 2 - 1 : span - 1;
  if (!(r >= lo && r <= hi)) {
    return fail(Errc::bad_argument, "does not fit the signal's bits");
  }
  const uint64_t mask = s.length == 64 ? ~uint64_t{0} : (uint64_t{1} << s.length) - 1;
  return s.is_signed ? static_cast<uint64_t>(static_cast<int64_t>(r)) & mask
                     : static_cast<uint64_t>(r);
}

uint8_t crc8_sae_j1850(std::span<const uint8_t> bytes) {
  uint8_t crc = 0xFF;
  for (uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) {
      crc = static_cast<uint8_t>((crc & 0x80U) != 0 ? (crc << 1) ^ 0x1DU : crc << 1);
    }
  }
  return static_cast<uint8_t>(crc ^ 0xFF);
}

uint8_t checksum(ChecksumKind kind, uint16_t data_id, std::span<const uint8_t> payload,
                 uint32_t at) {
  std::vector<uint8_t> bytes;
  if (kind == ChecksumKind::crc8_sae_j1850) {
    bytes.push_back(static_cast<uint8_t>(data_id & 0xFF));
    bytes.push_back(static_cast<uint8_t>(data_id >> 8));
  }
  for (uint32_t i = 0; i < payload.size(); ++i) {
    if (i != at) {
      bytes.push_back(payload[i]);
    }
  }
  uint8_t x = 0;
  uint8_t sum = 0;
  for (std::size_t i = kind == ChecksumKind::crc8_sae_j1850 ? 2 : 0; i < bytes.size(); ++i) {
    x ^= bytes[i];
    sum = static_cast<uint8_t>(sum + bytes[i]);
  }
  switch (kind) {
    case ChecksumKind::crc8_sae_j1850:
      return crc8_sae_j1850(bytes);
    case ChecksumKind::xor8:
      return x;
    case ChecksumKind::sum8:
      return sum;
    case ChecksumKind::none:
      break;
  }
  return 0;
}

}  // namespace canemu::daemon::restbus
