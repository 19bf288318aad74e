// Fault scenarios: TOML files of timed faults (docs/faults.md). parse_scenario() checks a file
// whole (every problem with file, line and key); ScenarioRunner::apply() resolves its bus and
// node names and applies all of it, or none.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <tl/expected.hpp>

namespace canemu::daemon {

enum class FaultEffect {
  // on matching frames
  bit_error,
  stuff_error,
  form_error,
  crc_error,
  ack_error,
  // on the bus
  ack_suppress,
  stuck_dominant,
  random_errors,
  // on a node
  node_off,
  node_on,
  bus_off,
  error_counters,
  oscillator,
  babble,
  line_error,
  // on a LIN bus's frames (docs/faults.md, "LIN")
  lin_bit_error,
  lin_checksum_error,
  lin_parity_error,
  lin_sync_error,
  lin_no_response,
  lin_short_break,
  // on a LIN node
  lin_responder_off,
  lin_wakeup,
  // on a simulated CAN node's message or signal (docs/faults.md, "Simulated CAN nodes")
  message_timeout,
  checksum_error,
  counter_freeze,
  counter_jump,
  signal_step,
  signal_ramp,
  signal_invalid,
};
// The effects on a LIN bus's frames (rules of its LinFaultPlan), lin_responder_off included.
bool is_lin_frame_effect(FaultEffect effect);
// The effects on a simulated CAN node's message or signal (`message` or `signal` on `bus`).
bool is_restbus_effect(FaultEffect effect);
std::string_view to_string(FaultEffect effect);

// Which frames a frame effect hits; every part optional.
struct FaultMatch {
  uint32_t id = 0;
  uint32_t mask = 0;  // 0: any identifier (with `id` given and no mask: all 29 bits)
  std::optional<bool> ext;
  std::optional<bool> rtr;
  std::string from;  // transmitting node ("DEVICE:N" or an ephemeral device's name)
};

struct FaultSpec {
  uint32_t line = 0;  // in the scenario file
  FaultEffect effect = FaultEffect::bit_error;
  int64_t at_ns = 0;                // from the scenario's start
  std::optional<int64_t> until_ns;  // end of the window (frame effects, node_off, oscillator)
  std::string bus;                  // frame and bus effects
  std::string node;                 // node effects
  FaultMatch match;
  std::optional<uint16_t> bit;    // frame bit (SOF = 0) where the error hits
  std::optional<uint64_t> count;  // matching frames to hit; nothing: every one in the window
  double probability = 1.0;       // per matching frame
  int64_t duration_ns = 0;        // ack_suppress, stuck_dominant; node_off/oscillator: optional
  uint16_t tec = 0;               // error_counters
  uint16_t rec = 0;
  int32_t ppm = 0;            // oscillator
  double bit_error_rate = 0;  // random_errors
  uint32_t id = 0;            // babble: the frame it floods
  bool ext = false;
  std::vector<uint8_t> data;
  bool both_wires = false;     // line_error: both wires broken (else one: single-wire mode)
  bool lin_header = false;     // lin_bit_error: in the header (else in the response)
  int64_t pulse_ns = 250'000;  // lin_wakeup: the dominant pulse
  // A simulated CAN node's message on `bus`, and its signal (`signal = "MESSAGE.SIGNAL"`)
  std::string message;
  std::string signal;
  std::optional<double> value;  // signal_step, signal_invalid: `value`; signal_ramp: `to`
  std::optional<uint64_t> raw;  // signal_invalid: the raw bits instead of a value
  uint64_t by = 0;              // counter_jump: values skipped
};

struct Scenario {
  std::string name;
  std::string source;  // file name
  std::optional<uint64_t> seed;
  std::vector<FaultSpec> faults;
};

tl::expected<Scenario, std::vector<std::string>> parse_scenario(std::string_view text,
                                                                const std::string& source);
tl::expected<Scenario, std::vector<std::string>> load_scenario_file(const std::string& path);

}  // namespace canemu::daemon
