// [[can_node]] of canemud's configuration: simulated CAN nodes that canemud runs itself (the
// restbus room, docs/restbus.md), each with the messages it sends and their signals' layout.
// `python -m canemu.dbc FILE.dbc --bus can0 --real NODE` writes these tables from a DBC file.
// The keys are documented in docs/configuration.md and docs/restbus.md.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace canemu::daemon {

// Where a signal's bits are and how its raw value becomes a physical one.
struct SignalLayout {
  enum class ByteOrder : uint8_t { little_endian, big_endian };  // Intel, Motorola
  enum class Type : uint8_t { integer, float32, float64 };
  uint32_t start = 0;   // the DBC start bit: the least significant bit of a little-endian
                        // signal, the most significant of a big-endian one (sawtooth numbering)
  uint32_t length = 1;  // bits, 1..64 (32 for float32, 64 for float64)
  ByteOrder byte_order = ByteOrder::little_endian;
  Type type = Type::integer;
  bool is_signed = false;  // two's complement (integer only)
  double scale = 1.0;      // physical = raw * scale + offset
  double offset = 0.0;
  bool operator==(const SignalLayout&) const = default;
};

// A payload check a signal carries, computed over the payload as it goes out.
enum class ChecksumKind : uint8_t {
  none,
  crc8_sae_j1850,  // CRC-8/SAE-J1850 over the data ID's bytes, then the other payload bytes
  xor8,            // XOR of the other payload bytes
  sum8,            // their sum modulo 256
};

struct CanSignalConfig {
  std::string name;
  SignalLayout layout;
  std::optional<double> minimum;  // physical range that `canemu signal set` checks
  std::optional<double> maximum;
  double initial = 0.0;            // physical start value (GenSigStartValue)
  std::optional<double> inactive;  // physical value meaning "not active" (cyclic_if_active)
  std::string unit;
  bool multiplexer = false;               // the message's multiplexor
  std::vector<uint64_t> multiplexer_ids;  // present only while the multiplexor has one of these
  bool counter = false;                   // alive counter: +1 per frame sent, wraps at 2^length
  ChecksumKind checksum = ChecksumKind::none;
  uint16_t data_id = 0;  // crc8_sae_j1850: the data ID, low byte first, then high byte
  bool operator==(const CanSignalConfig&) const = default;
};

struct CanMessageConfig {
  enum class Send : uint8_t {
    cyclic,                // every `cycle_ns`
    on_change,             // when a signal changes (not before)
    cyclic_if_active,      // every `cycle_ns` while a signal is not at its inactive value
    cyclic_and_on_change,  // every `cycle_ns`, and at once when a signal changes
  };
  std::string name;
  uint32_t id = 0;
  bool extended = false;
  bool fd = false;      // a CAN FD frame (needs a CAN FD bus)
  bool brs = false;     // its data phase at the data bit rate
  uint32_t length = 8;  // payload bytes: 0..8, or a CAN FD length up to 64
  Send send = Send::cyclic;
  int64_t cycle_ns = 0;  // cyclic kinds: the period, 1 ms .. 1 hour
  int64_t delay_ns = 0;  // the first frame's instant after the node starts, 0 .. 1 hour
  std::vector<CanSignalConfig> signals;
  bool operator==(const CanMessageConfig&) const = default;
};

struct CanNodeConfig {
  std::string name;  // unique among the CAN nodes of its bus
  std::string bus;   // a CAN or CAN FD bus
  bool powered = true;
  std::vector<CanMessageConfig> messages;
  uint32_t line = 0;
  bool same_as(const CanNodeConfig& o) const {
    return name == o.name && bus == o.bus && powered == o.powered && messages == o.messages;
  }
};

}  // namespace canemu::daemon
