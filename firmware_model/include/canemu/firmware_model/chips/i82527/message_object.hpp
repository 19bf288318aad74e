// One Intel 82527 message object as the CPU sees it (15 bytes at n * 0x10, n = 1..15): the two
// control registers of 2-bit flag pairs, the arbitration registers, the message configuration
// and eight data bytes; and the identifier/mask encoding they share with the mask registers.
//
// Source: the register map of the Intel 82527 datasheet ("Message Objects",
// cross-checked with the Linux cc770 driver); behaviour the datasheet leaves open is decided
// in i82527.hpp and docs/i82527.md. Register and bit names copy the datasheet mnemonics.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "canemu/firmware_model/bus/frame.hpp"

namespace canemu::model::i82527 {

// Byte offsets inside a message object.
enum ObjectReg : uint8_t {
  CTRL0 = 0,   // MsgVal, TXIE, RXIE, IntPnd
  CTRL1 = 1,   // RmtPnd, TxRqst, MsgLst/CPUUpd, NewDat
  ARB0 = 2,    // arbitration registers 0..3 (identifier)
  CONFIG = 6,  // message configuration: DLC, DIR, XTD
  DATA0 = 7,   // data bytes 0..7
};
inline constexpr uint8_t kObjectBytes = 15;

// Flag pairs. Each flag is two bits: read 10 = set, 01 = reset. A write of 10 sets the flag, 01
// resets it, 11 leaves it unchanged (so one write can change one flag and keep the others);
// the model also leaves a flag unchanged on 00, which the datasheet does not define.
// CTRL0:
inline constexpr uint8_t MSGVAL = 0xC0;  // message valid: the object takes part in bus traffic
inline constexpr uint8_t TXIE = 0x30;    // interrupt (IntPnd) after a successful transmission
inline constexpr uint8_t RXIE = 0x0C;    // interrupt (IntPnd) after a successful reception
inline constexpr uint8_t INTPND = 0x03;  // interrupt pending
// CTRL1:
inline constexpr uint8_t RMTPND = 0xC0;  // a remote frame asked for this (transmit) object
inline constexpr uint8_t TXRQST = 0x30;  // transmission requested
inline constexpr uint8_t MSGLST = 0x0C;  // receive object: a message was stored over NewDat
inline constexpr uint8_t CPUUPD = 0x0C;  // transmit object: CPU updating, do not transmit
inline constexpr uint8_t NEWDAT = 0x03;  // new data (written by the chip or the CPU)

// CONFIG bits
inline constexpr uint8_t CONFIG_DIR = 0x08;  // 1 = transmit object, 0 = receive object
inline constexpr uint8_t CONFIG_XTD = 0x04;  // 29-bit identifier
inline constexpr unsigned kConfigDlcShift = 4;

// The value to write to CTRL0 or CTRL1 that sets the flags in `set`, resets those in `reset`
// and leaves the others unchanged. Example: pair_write(TXRQST | NEWDAT, CPUUPD) = 0xE6.
constexpr uint8_t pair_write(uint8_t set, uint8_t reset = 0) {
  return static_cast<uint8_t>(0xFF & ~(set & 0x55) & ~(reset & 0xAA));
}
constexpr bool pair_is_set(uint8_t reg, uint8_t pair) {
  return (reg & pair & 0xAA) != 0;
}
// Applies a CPU (or chip) write to a control register of flag pairs.
constexpr uint8_t apply_pair_write(uint8_t reg, uint8_t value) {
  for (unsigned shift = 0; shift < 8; shift += 2) {
    const unsigned code = (value >> shift) & 3u;
    if (code == 1 || code == 2) {
      reg = static_cast<uint8_t>((reg & ~(3u << shift)) | (code << shift));
    }
  }
  return reg;
}
// All flags reset: what the model holds after a hardware reset.
inline constexpr uint8_t kAllPairsReset = 0x55;

// Identifier layout of the arbitration registers and of the mask registers, left-aligned and
// most significant byte first:
//   standard (11 bit): ARB0 = ID10..3, ARB1 bits 7..5 = ID2..0 (ARB1 bits 4..0, ARB2 and ARB3
//                      unused);
//   extended (29 bit): ID28..0 shifted left by 3, big-endian over ARB0..ARB3 (ARB3 bits 2..0
//                      unused).
// Worked example (the same values are a test): standard 0x123 -> 24 60; extended 0x12345678 ->
// 0x91A2B3C0 -> 91 A2 B3 C0. The standard form is the extended form's first 11 bits, which is
// how the message-15 mask (extended layout) also covers standard frames.
constexpr std::array<uint8_t, 4> encode_id(uint32_t id, bool extended) {
  if (!extended) {
    return {static_cast<uint8_t>(id >> 3), static_cast<uint8_t>((id << 5) & 0xE0), 0, 0};
  }
  const uint32_t v = id << 3;
  return {static_cast<uint8_t>(v >> 24), static_cast<uint8_t>(v >> 16),
          static_cast<uint8_t>(v >> 8), static_cast<uint8_t>(v & 0xF8)};
}
constexpr uint32_t decode_id(const std::array<uint8_t, 4>& r, bool extended) {
  if (!extended) {
    return (uint32_t{r[0]} << 3) | (uint32_t{r[1]} >> 5);
  }
  return ((uint32_t{r[0]} << 24) | (uint32_t{r[1]} << 16) | (uint32_t{r[2]} << 8) | r[3]) >> 3;
}

// The CPU-visible bytes of one object.
struct MessageObject {
  uint8_t ctrl0 = kAllPairsReset;
  uint8_t ctrl1 = kAllPairsReset;
  std::array<uint8_t, 4> arb{};
  uint8_t config = 0;
  std::array<uint8_t, 8> data{};

  bool valid() const { return pair_is_set(ctrl0, MSGVAL); }
  bool flag0(uint8_t pair) const { return pair_is_set(ctrl0, pair); }
  bool flag1(uint8_t pair) const { return pair_is_set(ctrl1, pair); }
  void set0(uint8_t pair, bool on) {
    ctrl0 = apply_pair_write(ctrl0, on ? pair_write(pair) : pair_write(0, pair));
  }
  void set1(uint8_t pair, bool on) {
    ctrl1 = apply_pair_write(ctrl1, on ? pair_write(pair) : pair_write(0, pair));
  }
  bool transmit() const { return (config & CONFIG_DIR) != 0; }
  bool extended() const { return (config & CONFIG_XTD) != 0; }
  uint8_t dlc() const { return static_cast<uint8_t>(config >> kConfigDlcShift); }
  uint32_t id() const { return decode_id(arb, extended()); }

  uint8_t read(uint8_t offset) const;
  void write(uint8_t offset, uint8_t value);

  // The frame this object sends when it transmits: a data frame with its DLC and data for a
  // transmit object, a remote frame with its DLC for a receive object.
  Frame frame() const { return frame_as(!transmit()); }
  // The object's identifier, DLC and (unless `remote`) data as a frame.
  Frame frame_as(bool remote) const;
  // Stores a received frame as the chip does: identifier into the arbitration registers (the
  // bits the masks leave open become the frame's), DLC into CONFIG (DIR and XTD kept), data.
  void store(const Frame& frame);
};

// Acceptance: the frame's format matches XTD, and the identifier agrees with the object's on
// every bit set in `mask` (1 = must match, 0 = don't care), mask in the layout of encode_id.
bool matches(const MessageObject& object, const Frame& frame, const std::array<uint8_t, 4>& mask);

}  // namespace canemu::model::i82527
