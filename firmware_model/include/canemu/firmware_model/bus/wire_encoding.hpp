// The exact bit sequence of a CAN or CAN FD frame on the wire, and its length and duration.
//
// encode() produces what the transmitter drives from start of frame through end of frame:
// dynamic stuff bits, CRC-15 (classic) or, for ISO CAN FD, the stuff count (Gray code + even
// parity), CRC-17 / CRC-21 and the fixed stuff bits of the CRC field. The ACK slot is sent
// recessive, as a transmitter sends it; receivers overwrite it on the bus. The 3-bit
// intermission is not part of the frame and is accounted separately.
//
// Worked example (tests/firmware_model/wire_encoding_test.cpp): the classic standard data frame
// with identifier 0x000 and DLC 0 has 34 dominant bits before the CRC delimiter (its CRC-15 is
// 0). A stuff bit follows every fifth of them, so it goes out as
//   00000 1 00000 1 00000 1 00000 1 00000 1 00000 1 0000  1  1  1  1111111
//   SOF..CRC with 6 stuff bits                            DEL ACK DEL EOF
// which is 50 bits, 53 with intermission.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model {

inline constexpr uint32_t kIntermissionBits = 3;
inline constexpr uint32_t kEofBits = 7;

// Fields in ISO 11898-1:2015 terms. In a classic standard frame the bit after IDE is FDF (the
// old r0); in a classic extended frame FDF is the old r1 and `res` the old r0. In CAN FD the bit
// after the identifier is RRS instead of RTR.
enum class Field : uint8_t {
  sof,
  base_id,
  srr,
  ide,
  ext_id,
  rtr,
  rrs,
  fdf,
  res,
  brs,
  esi,
  dlc,
  data,
  stuff_count,  // CAN FD: fixed stuff bit, 3-bit Gray-coded stuff count, parity
  crc,          // CRC sequence (CAN FD: with its fixed stuff bits)
  crc_delimiter,
  ack_slot,
  ack_delimiter,
  eof,
};

std::string_view to_string(Field field);

struct FieldSpan {
  Field field;
  uint16_t begin;  // first bit index (stuff bits after a field's last bit belong to that field)
};

struct EncodedFrame {
  static constexpr std::size_t kCapacity = 768;  // longest frame: CAN FD, 29-bit ID, 64 bytes
  using Bits = std::array<uint64_t, kCapacity / 64>;

  // Bit i of the frame is bit 63 - i % 64 of word i / 64 (first bit in the most significant
  // position), so that whole fields move with shifts. Bits at and after `length` are unspecified.
  Bits level{};         // 1 = recessive, 0 = dominant
  Bits stuff{};         // 1 = stuff bit (dynamic or fixed)
  uint16_t length = 0;  // SOF through EOF
  uint16_t dynamic_stuff_bits = 0;
  uint16_t fixed_stuff_bits = 0;  // CAN FD CRC field only
  uint32_t crc = 0;               // CRC-15, CRC-17 or CRC-21 as sent
  uint8_t crc_bits = 0;           // 15, 17 or 21
  uint8_t stuff_count = 0;        // CAN FD: dynamic stuff bits mod 8, before Gray coding
  bool fd = false;
  bool brs = false;
  uint16_t brs_index = 0;            // CAN FD: index of the BRS bit
  uint16_t crc_delimiter_index = 0;  // index of the CRC delimiter
  uint16_t arbitration_end = 0;      // index of the first bit after the arbitration field
  bool extended = false;
  uint8_t data_bytes = 0;          // bytes in the data field
  uint16_t stuff_count_begin = 0;  // CAN FD: index of the stuff count field

  bool level_at(std::size_t i) const { return (level[i >> 6] >> (63 - (i & 63))) & 1u; }
  bool is_stuff(std::size_t i) const { return (stuff[i >> 6] >> (63 - (i & 63))) & 1u; }
  Field field_at(std::size_t i) const;
  // Every field with the index it begins at, in order; returns how many.
  uint8_t fields(std::array<FieldSpan, 19>& out) const;
  // Frame index of the `destuffed`-th bit of the dynamically stuffed part.
  uint16_t stuffed_index(uint16_t destuffed) const;
  // The other way: bits before frame index `i` that are not stuff bits. Inline for the first
  // word (arbitration losses, every frame): a handful of stuff bits to count there.
  uint16_t destuffed_index(uint16_t i) const {
    if (i >= 64) {
      return destuffed_index_far(i);
    }
    uint16_t n = i;
    for (uint64_t m = i == 0 ? 0 : stuff[0] >> (64 - i); m != 0; m &= m - 1) {
      --n;
    }
    return n;
  }
  uint16_t destuffed_index_far(uint16_t i) const;
  // Bit index where `field` begins, or `length` if the frame has no such field.
  uint16_t field_begin(Field field) const;
  // The bits as '0' (dominant) and '1' (recessive), SOF first.
  std::string to_string() const;
  // The stuff marks the same way: '1' for a stuff bit (dynamic or fixed), '0' for any other.
  std::string stuff_marks() const;
};

void encode(const Frame& frame, EncodedFrame& out);
EncodedFrame encode(const Frame& frame);
// What a start of frame without errors needs of the encoding, for less: every field, and of
// `level` and `stuff` the first word (the arbitration field lies in it), as encode() writes
// them; the words after it are left as they were unless the result is true (a CAN FD frame is
// encoded whole, and so is a frame that ends within its first word). encode() gives the rest.
bool encode_head(const Frame& frame, EncodedFrame& out);

// Bits at the nominal and at the data rate. The BRS bit and the CRC delimiter, where the rate
// switches at the sample point, are counted as nominal bits; frame_duration() times them
// exactly. Without bit-rate switch every bit is nominal.
struct BitCounts {
  uint32_t nominal = 0;
  uint32_t data = 0;
  constexpr uint32_t total() const { return nominal + data; }
};
BitCounts bit_counts(const EncodedFrame& frame);

// Exact duration of the first `bits` bits of the frame (bits past its end count at the nominal
// rate), rounded once to the nearest ns; the rate switches as in frame_duration().
SimDuration frame_prefix_duration(const EncodedFrame& frame, const BitTiming& nominal,
                                  const BitTiming& data, uint32_t bits);

// Exact duration from SOF to the end of EOF, rounded once to the nearest ns. With bit-rate switch
// the rate changes at the sample point of BRS (nominal -> data) and at the sample point of the
// CRC delimiter (data -> nominal); `data` is used only then.
SimDuration frame_duration(const EncodedFrame& frame, const BitTiming& nominal,
                           const BitTiming& data);
inline SimDuration frame_duration(const EncodedFrame& frame, const BitTiming& nominal) {
  return frame_duration(frame, nominal, nominal);
}
inline SimDuration intermission_duration(const BitTiming& nominal) {
  return nominal.bits_duration(kIntermissionBits);
}

// Bounds of a frame's length, intermission included, from the Linux kernel's formulas
// (include/linux/can/length.h): no stuff bit at all, or the worst case of one stuff bit every
// four bits after the first (L + (L - 1) / 4 over the dynamically stuffed bits). These are
// bounds: the fixed control bits keep real frames below the worst case (docs/wire-model.md).
enum class Stuffing { none, worst_case };
constexpr uint32_t frame_length_bound(bool fd, bool extended, std::size_t data_length,
                                      Stuffing stuffing) {
  const uint32_t header = fd ? (extended ? 41u : 22u) : (extended ? 39u : 19u);
  const uint32_t crc_field = fd ? (data_length > 16 ? 33u : 28u) : 16u;  // incl. delimiter
  // Classic: stuffing covers SOF..CRC sequence; FD: SOF..data (the CRC field has fixed bits).
  const uint32_t stuffed = header + 8u * static_cast<uint32_t>(data_length) + (fd ? 0u : 15u);
  const uint32_t stuff = stuffing == Stuffing::worst_case ? (stuffed - 1u) / 4u : 0u;
  return stuffed + stuff + (crc_field - (fd ? 0u : 15u)) + 2u + kEofBits + kIntermissionBits;
}

}  // namespace canemu::model
