// [[lin_node]] of canemud's configuration: simulated LIN nodes that canemud runs itself
// (firmware_model chips/lin/lin_ecu.hpp): their response tables and schedule tables. The keys
// are documented in docs/configuration.md and docs/lin.md.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace canemu::daemon {

struct LinResponseConfig {
  uint8_t id = 0;
  std::vector<uint8_t> data;               // 1..8 bytes
  bool enhanced = true;                    // the checksum: enhanced (LIN 2.x) or classic
  std::optional<uint8_t> event_triggered;  // may go in this event-triggered frame
  bool operator==(const LinResponseConfig&) const = default;
};

struct LinSlotConfig {
  enum class Kind : uint8_t { unconditional, event_triggered, sporadic };
  Kind kind = Kind::unconditional;
  uint8_t id = 0;               // unconditional, event-triggered: the header's identifier
  std::vector<uint8_t> frames;  // event-triggered: associated frames; sporadic: candidates
  int64_t delay_ns = 0;
  bool operator==(const LinSlotConfig&) const = default;
};

struct LinScheduleConfig {
  std::string name;
  std::vector<LinSlotConfig> slots;
  bool operator==(const LinScheduleConfig&) const = default;
};

struct LinNodeConfig {
  std::string name;
  std::string bus;
  uint32_t bitrate = 0;  // 0: the bus's
  bool powered = true;
  std::string schedule;  // the table it runs from the start ("" none)
  std::vector<LinResponseConfig> responses;
  std::vector<LinScheduleConfig> schedules;
  uint32_t line = 0;
  // The same node (where it was declared aside).
  bool same_as(const LinNodeConfig& o) const {
    return name == o.name && bus == o.bus && bitrate == o.bitrate && powered == o.powered &&
           schedule == o.schedule && responses == o.responses && schedules == o.schedules;
  }
};

}  // namespace canemu::daemon
