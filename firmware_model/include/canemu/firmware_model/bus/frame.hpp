// CAN and CAN FD frames as values: identifier, format flags, DLC and payload.
//
// A Frame is always valid: the only way to get one is Frame::create(), which checks the
// identifier range, the DLC, the flag combinations and the payload length against the DLC, and
// names what is wrong otherwise.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>

#include "canemu/firmware_model/sim/model_error.hpp"

namespace canemu::model {

inline constexpr uint32_t kMaxStandardId = 0x7FF;       // 11-bit identifier
inline constexpr uint32_t kMaxExtendedId = 0x1FFFFFFF;  // 29-bit identifier
inline constexpr std::size_t kMaxClassicLength = 8;
inline constexpr std::size_t kMaxFdLength = 64;
inline constexpr uint8_t kMaxDlc = 15;

// Payload length in bytes for a DLC (ISO 11898-1:2015 table 5). Classic frames treat DLC 9..15
// as 8 bytes; CAN FD maps 9..15 to 12, 16, 20, 24, 32, 48, 64.
constexpr std::size_t dlc_to_length(uint8_t dlc, bool fd) {
  constexpr std::array<uint8_t, 16> kFdLengths{0, 1,  2,  3,  4,  5,  6,  7,
                                               8, 12, 16, 20, 24, 32, 48, 64};
  const uint8_t code = dlc & 0x0F;
  if (fd) {
    return kFdLengths[code];
  }
  return code > 8 ? 8 : code;
}

// The DLC whose length is exactly `length`, or nothing if no DLC gives that length.
constexpr std::optional<uint8_t> length_to_dlc(std::size_t length, bool fd) {
  for (uint8_t dlc = 0; dlc <= kMaxDlc; ++dlc) {
    if (dlc_to_length(dlc, fd) == length) {
      return dlc;
    }
  }
  return std::nullopt;
}

// What a caller asks for. `dlc` may be left out: it is then the DLC whose length is exactly the
// payload's (0 for a remote frame).
struct FrameSpec {
  uint32_t id = 0;
  bool extended = false;  // 29-bit identifier (IDE recessive)
  bool remote = false;    // remote transmission request; classic frames only
  bool fd = false;        // CAN FD frame (FDF recessive)
  bool brs = false;       // bit-rate switch; CAN FD only
  bool esi = false;       // error-state indicator (transmitter error-passive); CAN FD only
  std::optional<uint8_t> dlc;
  std::span<const uint8_t> data;
};

class Frame {
 public:
  static Result<Frame> create(const FrameSpec& spec);

  // Shorthands for the common cases; both validate like create().
  static Result<Frame> classic(uint32_t id, std::span<const uint8_t> data, bool extended = false);
  static Result<Frame> fd_frame(uint32_t id, std::span<const uint8_t> data, bool extended = false,
                                bool brs = false);

  constexpr uint32_t id() const { return id_; }
  constexpr bool extended() const { return extended_; }
  constexpr bool remote() const { return remote_; }
  constexpr bool fd() const { return fd_; }
  constexpr bool brs() const { return brs_; }
  constexpr bool esi() const { return esi_; }
  constexpr uint8_t dlc() const { return dlc_; }
  // Bytes in the data field on the wire (0 for a remote frame, whatever its DLC).
  constexpr std::size_t length() const { return remote_ ? 0 : dlc_to_length(dlc_, fd_); }
  std::span<const uint8_t> data() const { return {data_.data(), length()}; }

  // The same frame with the error-state indicator `esi`; a classic frame has none and stays as
  // it is. (A CAN FD transmitter sends its error state at the frame's start.)
  Frame with_esi(bool esi) const {
    Frame f = *this;
    f.esi_ = fd_ && esi;
    return f;
  }

  // All kMaxFdLength data bytes: those past length() are zero (only create() writes them), so
  // a copy of the whole array needs no length.
  const std::array<uint8_t, kMaxFdLength>& padded_data() const { return data_; }

  // Equal in every field and data byte. With the bytes past the length zero, the first eight
  // compare as one word whatever the lengths.
  friend bool operator==(const Frame& a, const Frame& b) {
    uint64_t da;
    uint64_t db;
    std::memcpy(&da, a.data_.data(), sizeof da);
    std::memcpy(&db, b.data_.data(), sizeof db);
    if (a.id_ != b.id_ || da != db || std::memcmp(a.header_tail(), b.header_tail(), 6) != 0) {
      return false;
    }
    const std::size_t n = a.length();
    return n <= 8 || std::memcmp(a.data_.data() + 8, b.data_.data() + 8, n - 8) == 0;
  }

 private:
  Frame() = default;
  // dlc_ and the five flags, side by side: six bytes compared as one block.
  const unsigned char* header_tail() const {
    static_assert(offsetof(Frame, esi_) == offsetof(Frame, dlc_) + 5);
    return reinterpret_cast<const unsigned char*>(this) + offsetof(Frame, dlc_);
  }

  std::array<uint8_t, kMaxFdLength> data_{};
  uint32_t id_ = 0;
  uint8_t dlc_ = 0;
  bool extended_ = false;
  bool remote_ = false;
  bool fd_ = false;
  bool brs_ = false;
  bool esi_ = false;
};

}  // namespace canemu::model
