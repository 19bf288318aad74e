// canemu fault inject: one fault from the command line, turned into a scenario of the
// language (docs/faults.md) that canemud checks and applies as it would a file.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <tl/expected.hpp>

namespace CLI {
class App;
}

namespace canemu::cli {

// One fault, in the scenario language's own keys. Strings stay as typed (canemud checks them as
// it checks a file); numbers are read here.
struct InjectOptions {
  std::string effect;
  std::string at = "0s";
  std::optional<std::string> until, bus, node, duration, from, wire;
  std::optional<std::string> where, pulse;  // lin_bit_error, lin_wakeup
  std::optional<std::string> id, mask;      // hex: 1A0 or 0x1A0
  bool ext = false;
  bool std_id = false;
  bool rtr = false;
  bool data_frame = false;
  std::optional<int64_t> bit, tec, rec, ppm;
  std::optional<std::string> count;  // a number or "all"
  std::optional<double> probability, bit_error_rate;
  std::optional<std::string> data;  // babble: hex bytes
  // Faults on simulated CAN nodes' messages and signals
  std::optional<std::string> message, signal, raw;
  std::optional<double> value, to;
  std::optional<int64_t> by;
};

// The options of `fault inject`, with its examples.
void add_inject_options(CLI::App& inject, InjectOptions& o);

// The scenario text of one injected fault; the reason when the options do not make one.
tl::expected<std::string, std::string> inject_scenario(const InjectOptions& o);

}  // namespace canemu::cli
