#include "canemu/firmware_model/bus/lin_frame.hpp"

namespace canemu::model::lin {

namespace {
constexpr uint8_t bit(uint8_t v, unsigned n) {
  return static_cast<uint8_t>((v >> n) & 1u);
}
}  // namespace

uint8_t protected_id(uint8_t id) {
  id &= kMaxId;
  const uint8_t p0 = bit(id, 0) ^ bit(id, 1) ^ bit(id, 2) ^ bit(id, 4);
  const uint8_t p1 =
      static_cast<uint8_t>(~(bit(id, 1) ^ bit(id, 3) ^ bit(id, 4) ^ bit(id, 5)) & 1u);
  return static_cast<uint8_t>(id | (p0 << 6) | (p1 << 7));
}

std::optional<uint8_t> id_of_protected(uint8_t pid) {
  const uint8_t id = pid & kMaxId;
  if (protected_id(id) != pid) {
    return std::nullopt;
  }
  return id;
}

Checksum effective_checksum(Checksum kind, uint8_t id) {
  id &= kMaxId;
  return id == kMasterRequestId || id == kSlaveResponseId ? Checksum::classic : kind;
}

uint8_t checksum(Checksum kind, uint8_t id, std::span<const uint8_t> data) {
  unsigned sum = 0;
  auto add = [&](uint8_t b) {
    sum += b;
    if (sum > 0xFF) {
      sum -= 0xFF;  // the carry goes back into bit 0
    }
  };
  if (effective_checksum(kind, id) == Checksum::enhanced) {
    add(protected_id(id));
  }
  for (uint8_t b : data) {
    add(b);
  }
  return static_cast<uint8_t>(~sum & 0xFFu);
}

uint32_t FrameBits::byte_end(uint32_t k) const {
  return response_start + (k + 1) * kCharacterBits + k * interbyte_bits;
}

FrameBits frame_bits(const Layout& layout, uint32_t data_bytes) {
  FrameBits f;
  f.interbyte_bits = layout.interbyte_bits;
  f.break_end = layout.break_bits;
  f.sync_end = layout.break_bits + layout.delimiter_bits + kCharacterBits;
  f.header_end = f.sync_end + layout.interbyte_bits + kCharacterBits;
  f.response_start = f.header_end + layout.response_space_bits;
  // Data bytes, then the checksum: character `data_bytes` of the response.
  f.response_end = data_bytes == 0 ? f.header_end : f.byte_end(data_bytes);
  return f;
}

uint32_t nominal_response_bits(uint32_t data_bytes) {
  return kCharacterBits * (data_bytes + 1);
}

uint32_t maximum_response_bits(uint32_t data_bytes) {
  return 14 * (data_bytes + 1);
}

SimDuration maximum_frame_duration(uint32_t data_bytes, uint32_t bitrate) {
  const uint64_t tenths = 14ull * (kNominalHeaderBits + nominal_response_bits(data_bytes));
  return SimDuration(static_cast<int64_t>(tenths * 1'000'000'000ull / (10ull * bitrate)));
}

SimDuration bits_duration(uint64_t bits, uint32_t bitrate) {
  return SimDuration(static_cast<int64_t>(bits * 1'000'000'000ull / bitrate));
}

SimTime after_bits(SimTime start, uint64_t bits, uint32_t bitrate) {
  return start + bits_duration(bits, bitrate);
}

}  // namespace canemu::model::lin
