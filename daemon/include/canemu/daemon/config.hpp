// canemud's configuration: TOML text -> checked, typed Config, or every error found, each as
// "file:line:column: key: what is wrong".
//
// The schema and every key are documented in docs/configuration.md; config/default.toml is the
// embedded default and a commented example.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/lin_config.hpp"

namespace canemu::daemon {

enum class BusKind { can, can_fd, lin };
std::string_view to_string(BusKind kind);

struct BusConfig {
  std::string name;
  BusKind kind = BusKind::can;
  uint32_t bitrate = 500000;    // nominal bit/s
  uint32_t sample_point = 875;  // per mille
  uint32_t data_bitrate = 0;    // can-fd: data-phase bit/s (0: no bit-rate switch)
  bool low_speed = false;       // can: ISO 11898-3 fault-tolerant transceivers (<= 125 kbit/s)
  uint32_t line = 0;            // where it was declared
};

// Adapter models the daemon can emulate. The X-CAN-2i module has exactly two interfaces; its
// variant (/H, /F, /M) follows from the transceivers of their buses.
enum class DeviceModel { ixxat_usb_to_can, ixxat_usb_to_can_fd, sorcus_x_can_2i, sorcus_sl_cani };
std::string_view to_string(DeviceModel model);

struct DeviceConfig {
  std::string name;
  DeviceModel model = DeviceModel::ixxat_usb_to_can;
  std::vector<std::string> controllers;  // bus name per controller
  uint32_t line = 0;
  // sorcus-sl-cani: the Multi-COM slot (0..5, channels A..F) and the EEPROM's state file ("":
  // $STATE_DIRECTORY/NAME.eeprom under systemd, else kept in memory only).
  int slot = -1;
  std::string eeprom;
};

enum class TimeMode { realtime, scaled, stepped };

struct TimeSetting {
  TimeMode mode = TimeMode::realtime;
  double scale = 1.0;  // scaled: simulated seconds per wall-clock second
};
// "realtime", "stepped" or "scaled:F" with F > 0.
tl::expected<TimeSetting, std::string> parse_time_setting(std::string_view text);
std::string to_string(const TimeSetting& time);

// The whole of a text file; or "PATH: cannot be read (reason)".
tl::expected<std::string, std::string> read_text_file(const std::string& path);

// "150ns", "20us", "10ms", "2s", "1.5ms": a duration in ns, at least 0 and at most about 285
// years; nothing if the text is not one.
std::optional<int64_t> parse_duration(std::string_view text);

// Names of buses and devices (configured or ephemeral): 1 to 28 characters, so that "device:N"
// fits the protocol's 32-byte names with its NUL.
bool valid_name(std::string_view name);
inline constexpr std::string_view kNameRule = "must be 1 to 28 characters of a-z, 0-9, '_' and '-'";

struct SimulationConfig {
  TimeSetting time;
  uint64_t seed = 1;
  // Real and scaled time: the daemon wakes at most once per batch_us (events due meanwhile run
  // together, each at its exact simulated instant), and wakes spin_us early to spin to the
  // deadline instead of trusting the timer's accuracy.
  uint32_t batch_us = 50;
  uint32_t spin_us = 20;
};

struct SecurityConfig {
  std::vector<std::string> allowed_users;
  std::vector<std::string> allowed_groups;
};

struct Config {
  std::string source;  // file name, or "<embedded default>"
  SimulationConfig simulation;
  SecurityConfig security;
  // [[scenario]] file = "...": fault scenarios applied at start, paths relative to the
  // configuration file's folder.
  std::vector<std::string> scenario_files;
  std::vector<BusConfig> buses;
  std::vector<DeviceConfig> devices;
  std::vector<LinNodeConfig> lin_nodes;  // [[lin_node]]: simulated LIN nodes

  const BusConfig* bus(std::string_view name) const;
};

using ConfigErrors = std::vector<std::string>;

tl::expected<Config, ConfigErrors> parse_config(std::string_view text, std::string source);
tl::expected<Config, ConfigErrors> load_config_file(const std::string& path);
// config/default.toml, compiled in.
std::string_view embedded_default_config();
tl::expected<Config, ConfigErrors> load_default_config();

// A few lines for humans: buses, devices, time mode.
std::string summary(const Config& config);

}  // namespace canemu::daemon
