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

#include "canemu/daemon/config/can_node_config.hpp"
#include "canemu/daemon/config/lin_config.hpp"

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
  // The daemon that simulates this bus ([distributed], docs/distributed.md); empty, or this
  // daemon's own name: this one.
  std::string owner;
  uint32_t line = 0;  // where it was declared
};

// Adapter models the daemon can emulate. The X-CAN-2i module has exactly two interfaces; its
// variant (/H, /F, /M) follows from the transceivers of their buses.
enum class DeviceModel { ixxat_usb_to_can, ixxat_usb_to_can_fd, sorcus_x_can_2i, sorcus_sl_cani };
std::string_view to_string(DeviceModel model);

struct DeviceConfig {
  std::string name;
  DeviceModel model = DeviceModel::ixxat_usb_to_can;
  std::vector<std::string> controllers;  // bus name per controller
  std::string mdd_version;               // sorcus-x-can-2i: "N.L"; empty: "3.C"
  int64_t buffer_load_ns = 0;            // sorcus-x-can-2i: loading a buffer takes this long
  // IXXAT adapters: the LIN bus of each LIN controller. They are numbered after the CAN
  // controllers ("DEVICE:N" with N = controllers.size() + i, and the VCI's bus number N).
  std::vector<std::string> lin;
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

// A configuration or scenario file is at most this long (docs/configuration.md, "Limits").
inline constexpr std::size_t kMaxConfigFileBytes = std::size_t{1} << 20;
// A [security] list names at most this many users or groups (a group serves for more).
inline constexpr std::size_t kMaxSecurityNames = 256;
// The whole of a configuration or scenario file (at most kMaxConfigFileBytes); or
// "PATH: cannot be read (reason)", "PATH: is a directory ...", "PATH: larger than ...".
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
  // ... and while events come densely (many busy buses), a wake-up at most once per
  // batch_max_us, the window doubling from batch_us every wake-up (loop/batch_window.hpp);
  // batch_max_us <= batch_us: never wider than batch_us.
  uint32_t batch_max_us = 1000;
  uint32_t spin_us = 20;
  // Real and scaled time: a bound in microseconds on how long an idle CPU takes to wake,
  // requested from the kernel while canemud runs (PM QoS, loop/cpu_latency.hpp); none if unset.
  std::optional<uint32_t> cpu_latency_us;
};

// The group the packages create (systemd/canemu.sysusers): its members may connect by default.
inline constexpr const char* kServiceGroup = "canemu";

struct SecurityConfig {
  std::vector<std::string> allowed_users;
  // Members (primary or supplementary) of these groups may connect; the group the packages
  // install (canemu.sysusers) by default.
  std::vector<std::string> allowed_groups{kServiceGroup};
  // Members of these groups (besides root and canemud's own user) may clear every client's fault
  // scenarios and the configuration's; others clear their own user's only.
  std::vector<std::string> admin_groups;
  // The control socket's permission bits and group when canemud creates it (not when systemd
  // passes it: canemud.socket's SocketMode= and SocketGroup= decide then). A group that does not
  // exist leaves the socket in canemud's own group, with a warning.
  uint32_t socket_mode = 0660;
  std::string socket_group = kServiceGroup;
  // Quotas of one user (root has none; docs/security.md): connections at once, and ring memory
  // of all its channels and FIFOs together.
  uint32_t max_clients_per_user = 32;
  uint32_t ring_mib_per_user = 64;
};

// [[recorder]]: a bus recorded into a file by canemud (docs/socketcan.md).
struct RecorderConfig {
  std::string bus;
  std::string path;   // relative paths are taken from the configuration file's folder
  bool pcap = false;  // format = "pcap" (default: "candump", "pcap" for a .pcap path or a LIN bus)
  uint64_t max_size = 0;    // bytes; rotate before a file grows past it (0: never)
  uint32_t max_files = 10;  // old files kept by rotation
  bool errors = true;       // error frames recorded too
  uint32_t line = 0;
};

// [[bridge]]: a bus joined to a Linux CAN interface (kind "socketcan", docs/socketcan.md) or to
// LCM channels (kind "lcm") or DDS topics (kind "dds", docs/bridges.md).
struct BridgeConfig {
  std::string kind = "socketcan";  // "socketcan", "lcm" or "dds"
  std::string bus;
  std::string interface;      // socketcan: vcan0, vxcan1, can0, ...
  bool error_frames = false;  // socketcan: the bridge node's errors and states as CAN_ERR_* frames
  uint32_t restart_ms = 0;    // restart the node this long after bus-off; 0: it stays bus-off
  uint32_t line = 0;
  std::string url{};             // lcm: the provider URL (default kDefaultLcmUrl)
  std::string channel_prefix{};  // lcm: the channels' prefix (default CANEMU_<BUS>_); dds: the
                                 // topics' prefix (topic_prefix, default canemu/<bus>/)
  uint32_t domain = 0;           // dds: the DDS domain id
  std::string partition{};       // dds: the partition of canemu's topics (default "canemu")
  bool ros2 = false;             // dds: ROS 2's can_msgs/msg/Frame topics too
};

// [distributed]: this daemon in an installation of several (docs/distributed.md).
struct DistributedConfig {
  bool enabled = false;  // the table is there
  std::string name;      // this daemon's name (default: default_daemon_name())
  uint32_t domain = 0;   // the DDS domain id
  std::string partition = "canemu";
  uint32_t heartbeat_ms = 200;  // how often it tells the others it is there
  uint32_t timeout_ms = 2000;   // another daemon not heard from this long is gone
  // Daemons on one host talk over a Unix socket of their own instead of DDS (docs/distributed.md,
  // "Daemons on one host").
  bool local_link = true;
};

struct Config {
  std::string source;  // file name, or "<embedded default>"
  SimulationConfig simulation;
  SecurityConfig security;
  DistributedConfig distributed;
  // [[scenario]] file = "...": fault scenarios applied at start, paths relative to the
  // configuration file's folder.
  std::vector<std::string> scenario_files;
  std::vector<BusConfig> buses;
  std::vector<DeviceConfig> devices;
  std::vector<LinNodeConfig> lin_nodes;   // [[lin_node]]: simulated LIN nodes
  std::vector<CanNodeConfig> can_nodes;   // [[can_node]]: simulated CAN nodes (restbus)
  std::vector<RecorderConfig> recorders;  // [[recorder]]
  std::vector<BridgeConfig> bridges;      // [[bridge]]

  const BusConfig* bus(std::string_view name) const;
  // Bus `b` is simulated by another daemon.
  bool remote(const BusConfig& b) const {
    return distributed.enabled && !b.owner.empty() && b.owner != distributed.name;
  }
};

using ConfigErrors = std::vector<std::string>;

tl::expected<Config, ConfigErrors> parse_config(std::string_view text, std::string source);
tl::expected<Config, ConfigErrors> load_config_file(const std::string& path);
// config/default.toml, compiled in.
std::string_view embedded_default_config();
tl::expected<Config, ConfigErrors> load_default_config();

// A few lines for humans: buses, devices, time mode.
std::string summary(const Config& config);

// [[lin_node]] tables loaded at run time (`canemu lin load`): checked as the configuration's are,
// against `buses`; every problem with its line.
tl::expected<std::vector<LinNodeConfig>, std::vector<std::string>> parse_lin_nodes(
    std::string_view text, const std::string& source, const std::vector<BusConfig>& buses);

// [[can_node]] tables loaded at run time: checked as the configuration's are, against `buses`;
// every problem with its line.
tl::expected<std::vector<CanNodeConfig>, std::vector<std::string>> parse_can_nodes(
    std::string_view text, const std::string& source, const std::vector<BusConfig>& buses);

}  // namespace canemu::daemon
