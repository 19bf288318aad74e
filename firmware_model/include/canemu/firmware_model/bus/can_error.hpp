// Error vocabulary of the CAN protocol (ISO 11898-1:2015, 10.11 and 12.1.4).
#pragma once

#include <cstdint>
#include <string_view>

namespace canemu::model {

enum class CanErrorType : uint8_t { bit, stuff, form, crc, ack };

// Error-active below 96 on both counters, warning from the warning limit (96 by default) on,
// error-passive from 128, bus-off above 255 (transmit counter).
enum class ErrorState : uint8_t { active, warning, passive, bus_off };

// What the node was doing when it detected the error.
enum class ErrorRole : uint8_t { transmitter, receiver };

constexpr std::string_view to_string(CanErrorType t) {
  switch (t) {
    case CanErrorType::bit:
      return "bit";
    case CanErrorType::stuff:
      return "stuff";
    case CanErrorType::form:
      return "form";
    case CanErrorType::crc:
      return "crc";
    case CanErrorType::ack:
      return "ack";
  }
  return "?";
}

constexpr std::string_view to_string(ErrorState s) {
  switch (s) {
    case ErrorState::active:
      return "error-active";
    case ErrorState::warning:
      return "warning";
    case ErrorState::passive:
      return "error-passive";
    case ErrorState::bus_off:
      return "bus-off";
  }
  return "?";
}

constexpr std::string_view to_string(ErrorRole r) {
  return r == ErrorRole::transmitter ? "transmitter" : "receiver";
}

}  // namespace canemu::model
