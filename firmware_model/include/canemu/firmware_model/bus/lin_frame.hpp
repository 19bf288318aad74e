// LIN on the wire: protected identifiers, checksums and the exact layout and duration of a
// frame (LIN 2.x; ISO 17987). Pure arithmetic, shared by the bus engine, the controllers and
// `canemu calc lin`.
//
// A frame is a header (break, break delimiter, sync byte 0x55, protected identifier) sent by
// the commander, and a response (1..8 data bytes and a checksum) sent by one responder. Every
// field but the break is a UART character of 10 bits (start bit, 8 data bits LSB first, stop
// bit). Instants inside a frame are counted in bits from its start and turned into ns once,
// rounded down: bit k of a frame begins at start + floor(k * 10^9 / bitrate) ns, so that no
// rounding accumulates at rates whose bit time is not a whole number of ns (19200 bit/s).
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::model::lin {

inline constexpr uint8_t kMaxId = 0x3F;            // 6-bit identifiers 0..63
inline constexpr uint8_t kMasterRequestId = 0x3C;  // diagnostic frames: classic checksum always
inline constexpr uint8_t kSlaveResponseId = 0x3D;
inline constexpr uint8_t kSyncByte = 0x55;
inline constexpr uint8_t kMaxData = 8;
inline constexpr uint32_t kMinBitrate = 1000;
inline constexpr uint32_t kMaxBitrate = 20000;
inline constexpr uint32_t kCharacterBits = 10;  // start, 8 data bits, stop
inline constexpr uint32_t kMinBreakBits = 13;
inline constexpr uint32_t kNominalHeaderBits = 34;  // 13 + 1 + 10 + 10

// The identifier with its two parity bits: P0 = ID0^ID1^ID2^ID4 (bit 6),
// P1 = !(ID1^ID3^ID4^ID5) (bit 7). `id` above 63 is masked to its 6 bits.
uint8_t protected_id(uint8_t id);
// The identifier a protected identifier carries, or nullopt when its parity bits are wrong.
std::optional<uint8_t> id_of_protected(uint8_t pid);

enum class Checksum : uint8_t {
  classic = 0,   // data bytes only (LIN 1.x, and the diagnostic frames 0x3C / 0x3D)
  enhanced = 1,  // protected identifier and data bytes (LIN 2.x)
};

// The checksum byte: the inverted 8-bit sum with carry added back (each carry out of bit 7 is
// added to bit 0), over the data bytes and, enhanced, the protected identifier of `id`. The
// diagnostic frames 0x3C and 0x3D always have the classic checksum.
uint8_t checksum(Checksum kind, uint8_t id, std::span<const uint8_t> data);
Checksum effective_checksum(Checksum kind, uint8_t id);

// The frame's shape on the wire (the commander's settings; the spaces are nominally 0).
struct Layout {
  uint32_t bitrate = 19200;
  uint32_t break_bits = kMinBreakBits;  // dominant bits of the break, >= 13
  uint32_t delimiter_bits = 1;          // recessive bits of the break delimiter, >= 1
  uint32_t interbyte_bits = 0;          // recessive bits between two characters
  uint32_t response_space_bits = 0;     // recessive bits between the header and the response
};

// Bit counts, from the frame's start, of the ends of its fields.
struct FrameBits {
  uint32_t break_end = 0;
  uint32_t sync_end = 0;
  uint32_t header_end = 0;    // the protected identifier's stop bit
  uint32_t response_end = 0;  // the checksum's stop bit (= header_end without a response)
  // The end of data byte k (0-based) of the response, k < data bytes; then the checksum.
  uint32_t byte_end(uint32_t k) const;
  uint32_t response_start = 0;  // first bit of the first response character
  uint32_t interbyte_bits = 0;
};

// The bits of a frame with `data_bytes` (0: a header alone) in `layout`.
FrameBits frame_bits(const Layout& layout, uint32_t data_bytes);

// Nominal and maximum times (LIN 2.x): THeader_Nominal = 34 bits, TResponse_Nominal =
// 10 * (N + 1) bits, and 1.4 times those at most: TResponse_Maximum = 14 * (N + 1) bits (from
// the header's end), TFrame_Maximum = 1.4 * (34 + 10 * (N + 1)) bits (from the break).
uint32_t nominal_response_bits(uint32_t data_bytes);
uint32_t maximum_response_bits(uint32_t data_bytes);
SimDuration maximum_frame_duration(uint32_t data_bytes, uint32_t bitrate);

// The instant `bits` bits after `start` at `bitrate` (rounded down to the ns).
SimTime after_bits(SimTime start, uint64_t bits, uint32_t bitrate);
// `bits` bits at `bitrate` as a duration (rounded down to the ns).
SimDuration bits_duration(uint64_t bits, uint32_t bitrate);

}  // namespace canemu::model::lin
