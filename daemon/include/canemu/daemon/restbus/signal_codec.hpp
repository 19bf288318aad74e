// Signals in a CAN payload as a DBC file lays them out (docs/restbus.md): where a signal's bits
// are, its raw value as a physical one and back, and the payload checks (counters, checksums)
// a simulated node computes as a frame goes out. Pure functions of their arguments.
#pragma once

#include <cstdint>
#include <span>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/config/can_node_config.hpp"

namespace canemu::daemon::restbus {

// Whether the signal's bits lie inside a payload of `bytes` bytes (and its length suits its
// type: 1..64 bits for an integer, 32 for float32, 64 for float64).
bool fits(const SignalLayout& s, uint32_t bytes);

// The signal's raw bits, right-aligned (a signed signal's bits as they are, not sign-extended).
// The signal must fit the payload.
uint64_t get_raw(std::span<const uint8_t> payload, const SignalLayout& s);
// Writes the low `s.length` bits of `raw` into the signal's place; the other bits stay.
void put_raw(std::span<uint8_t> payload, const SignalLayout& s, uint64_t raw);

// The physical value of raw bits: sign-extended for a signed integer, the IEEE value for a
// float, then scaled: raw * scale + offset.
double to_physical(const SignalLayout& s, uint64_t raw);
// The raw bits of a physical value: (physical - offset) / scale rounded to the nearest integer
// (halves to even, as Python's round() in cantools), or the IEEE bits of a float. An error
// (bad_argument) when the bits cannot hold the value or it is not a number.
Result<uint64_t> to_raw(const SignalLayout& s, double physical);

// CRC-8/SAE-J1850: polynomial 0x1D, initial value 0xFF, final XOR 0xFF, no reflection (check
// value 0x4B for the nine ASCII digits "123456789").
uint8_t crc8_sae_j1850(std::span<const uint8_t> bytes);
// The check byte `kind` computes for a payload whose check byte is byte `at`: over the other
// bytes of the payload; crc8_sae_j1850 first over the data ID (its low byte, then its high byte).
uint8_t checksum(ChecksumKind kind, uint16_t data_id, std::span<const uint8_t> payload,
                 uint32_t at);

}  // namespace canemu::daemon::restbus
