#include "canemu/daemon/config/config.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "can_node_config_reader.hpp"
#include "canemu/daemon/config/names.hpp"
#include "canemu/firmware_model/adapters/sorcus/mdd_version.hpp"
#include "canemu/ipc/duration.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/text_file.hpp"
#include "capture_config_reader.hpp"
#include "lin_config_reader.hpp"
#include "toml_checker.hpp"

namespace canemu::daemon {

namespace detail {
std::string_view default_config_text();  // generated from config/default.toml
}

namespace {

using detail::Checker;
using detail::name_of;
using detail::NamedValue;

constexpr NamedValue<BusKind> kBusKinds[] = {
    {BusKind::can, ipc::to_string(ipc::WireBusKind::can)},
    {BusKind::can_fd, ipc::to_string(ipc::WireBusKind::can_fd)},
    {BusKind::lin, ipc::to_string(ipc::WireBusKind::lin)}};
constexpr NamedValue<bool> kTransceivers[] = {{false, "high-speed"}, {true, "low-speed"}};
constexpr NamedValue<DeviceModel> kDeviceModels[] = {
    {DeviceModel::ixxat_usb_to_can, ipc::to_string(ipc::WireDeviceModel::ixxat_usb_to_can)},
    {DeviceModel::ixxat_usb_to_can_fd, ipc::to_string(ipc::WireDeviceModel::ixxat_usb_to_can_fd)},
    {DeviceModel::sorcus_x_can_2i, ipc::to_string(ipc::WireDeviceModel::sorcus_x_can_2i)},
    {DeviceModel::sorcus_sl_cani, ipc::to_string(ipc::WireDeviceModel::sorcus_sl_cani)}};

// The required key "name" of a [[bus]] or [[device]] table: valid, and unique among `names`.
std::optional<std::string> read_name(Checker& c, const toml::table& t, const std::string& path,
                                     std::set<std::string>& names, std::string_view what) {
  auto name = c.string(t, path, "name", true);
  if (name) {
    if (!valid_name(*name)) {
      c.error(*t.get("name"), path + ".name", kNameRule);
    } else if (!names.insert(*name).second) {
      c.error(*t.get("name"), path + ".name",
              fmt::format("a {} named \"{}\" exists already", what, *name));
    }
  }
  return name;
}
// Buses in a configuration (docs/configuration.md says what bounds it): the status comes in
// pages of 32 (a full `canemu status` is 32 requests at this limit), an idle bus costs nothing,
// and tests/system/scale_test.cpp runs 256 and starts with 1024.
constexpr std::size_t kMaxBuses = 1024;
constexpr std::size_t kMaxControllers = 256;

void read_simulation(Checker& c, const toml::table& root, Config& cfg) {
  const toml::table* t = c.section(root, "simulation");
  if (t == nullptr) {
    return;
  }
  c.only_keys(*t, "simulation",
              {"time", "seed", "batch_us", "batch_max_us", "spin_us", "cpu_latency_us"});
  if (auto time = c.string(*t, "simulation", "time", false)) {
    auto parsed = parse_time_setting(*time);
    if (parsed) {
      cfg.simulation.time = *parsed;
    } else {
      c.error(*t->get("time"), "simulation.time", parsed.error());
    }
  }
  if (auto seed = c.integer(*t, "simulation", "seed", false, 0, INT64_MAX)) {
    cfg.simulation.seed = static_cast<uint64_t>(*seed);
  }
  if (auto batch = c.integer(*t, "simulation", "batch_us", false, 0, 100'000)) {
    cfg.simulation.batch_us = static_cast<uint32_t>(*batch);
  }
  if (auto batch_max = c.integer(*t, "simulation", "batch_max_us", false, 0, 100'000)) {
    cfg.simulation.batch_max_us = static_cast<uint32_t>(*batch_max);
  }
  if (auto spin = c.integer(*t, "simulation", "spin_us", false, 0, 1000)) {
    cfg.simulation.spin_us = static_cast<uint32_t>(*spin);
  }
  if (auto bound = c.integer(*t, "simulation", "cpu_latency_us", false, 0, 100'000)) {
    cfg.simulation.cpu_latency_us = static_cast<uint32_t>(*bound);
  }
}

void read_security(Checker& c, const toml::table& root, Config& cfg) {
  const toml::table* t = c.section(root, "security");
  if (t == nullptr) {
    return;
  }
  c.only_keys(*t, "security",
              {"allowed_users", "allowed_groups", "admin_groups", "socket_mode", "socket_group",
               "max_clients_per_user", "ring_mib_per_user"});
  // Each name is looked up at every reload, in the event loop: the lists are short.
  constexpr std::string_view kUseAGroup = " (give more users a group and list the group)";
  if (auto v = c.strings(*t, "security", "admin_groups", kMaxSecurityNames)) {
    cfg.security.admin_groups = *v;
  }
  if (auto v = c.strings(*t, "security", "allowed_users", kMaxSecurityNames, kUseAGroup)) {
    cfg.security.allowed_users = *v;
  }
  if (auto v = c.strings(*t, "security", "allowed_groups", kMaxSecurityNames)) {
    cfg.security.allowed_groups = *v;
  }
  // Permission bits read as octal, so the error says them in octal too.
  if (const toml::node* n = t->get("socket_mode")) {
    const auto* mode = n->as_integer();
    if (mode == nullptr || mode->get() < 0 || mode->get() > 0777) {
      c.error(*n, "security.socket_mode",
              mode == nullptr ? std::string("must be an integer (octal, such as 0o660)")
                              : fmt::format("0o{:o} is outside 0o000..0o777", mode->get()));
    } else {
      cfg.security.socket_mode = static_cast<uint32_t>(mode->get());
    }
  }
  if (auto group = c.string(*t, "security", "socket_group", false)) {
    cfg.security.socket_group = *group;
  }
  if (auto n = c.integer(*t, "security", "max_clients_per_user", false, 1, 256)) {
    cfg.security.max_clients_per_user = static_cast<uint32_t>(*n);
  }
  if (auto n = c.integer(*t, "security", "ring_mib_per_user", false, 1, 256)) {
    cfg.security.ring_mib_per_user = static_cast<uint32_t>(*n);
  }
}

void read_distributed(Checker& c, const toml::table& root, Config& cfg) {
  const toml::table* t = c.section(root, "distributed");
  if (t == nullptr) {
    return;
  }
  DistributedConfig& d = cfg.distributed;
  d.enabled = true;
  c.only_keys(*t, "distributed",
              {"name", "domain", "partition", "heartbeat_ms", "timeout_ms", "local_link"});
  if (auto name = c.string(*t, "distributed", "name", false)) {
    if (!valid_name(*name)) {
      c.error(*t->get("name"), "distributed.name", kNameRule);
    } else {
      d.name = *name;
    }
  }
  if (d.name.empty()) {
    d.name = default_daemon_name();
  }
  if (auto domain = c.integer(*t, "distributed", "domain", false, 0, kMaxDdsDomain)) {
    d.domain = static_cast<uint32_t>(*domain);
  }
  if (auto partition = c.string(*t, "distributed", "partition", false)) {
    if (auto problem = dds_partition_problem(*partition)) {
      c.error(*t->get("partition"), "distributed.partition", *problem);
    } else {
      d.partition = *partition;
    }
  }
  if (auto ms = c.integer(*t, "distributed", "heartbeat_ms", false, 10, 10'000)) {
    d.heartbeat_ms = static_cast<uint32_t>(*ms);
  }
  if (auto ms = c.integer(*t, "distributed", "timeout_ms", false, 30, 600'000)) {
    d.timeout_ms = static_cast<uint32_t>(*ms);
  }
  if (const toml::node* n = t->get("local_link")) {
    if (n->is_boolean()) {
      d.local_link = n->as_boolean()->get();
    } else {
      c.error(*n, "distributed.local_link", "must be true or false");
    }
  }
  if (d.timeout_ms < 3 * d.heartbeat_ms) {
    c.error(*t, "distributed.timeout_ms",
            fmt::format("{} ms is less than three heartbeats ({} ms each)", d.timeout_ms,
                        d.heartbeat_ms));
  }
}

void read_buses(Checker& c, const toml::table& root, Config& cfg) {
  std::set<std::string> names;
  c.for_each_table(root, "bus", [&](const toml::table& t, const std::string& path) {
    c.only_keys(
        t, path,
        {"name", "kind", "bitrate", "sample_point", "data_bitrate", "transceiver", "owner"});
    BusConfig bus;
    bus.line = static_cast<uint32_t>(t.source().begin.line);
    if (auto name = read_name(c, t, path, names, "bus")) {
      bus.name = *name;
    }
    if (auto kind = c.choice(t, path, "kind", false, kBusKinds, "bus kind")) {
      bus.kind = *kind;
    }
    const int64_t max_rate = bus.kind == BusKind::lin ? 20'000 : 1'000'000;
    const int64_t min_rate = bus.kind == BusKind::lin ? 1'000 : 5'000;
    if (auto rate = c.integer(t, path, "bitrate", false, min_rate, max_rate)) {
      bus.bitrate = static_cast<uint32_t>(*rate);
    } else if (bus.kind == BusKind::lin && t.get("bitrate") == nullptr) {
      bus.bitrate = 19'200;
    }
    if (auto sp = c.number(t, path, "sample_point")) {
      if (!(*sp >= 0.5 && *sp <= 0.95)) {  // also rejects NaN
        c.error(*t.get("sample_point"), path + ".sample_point",
                fmt::format("{} is outside 0.5..0.95", *sp));
      } else {
        bus.sample_point = static_cast<uint32_t>(std::lround(*sp * 1000));
      }
    }
    if (t.get("data_bitrate") != nullptr) {
      if (bus.kind != BusKind::can_fd) {
        c.error(*t.get("data_bitrate"), path + ".data_bitrate",
                "only a can-fd bus has a data bit rate");
      } else if (auto d = c.integer(t, path, "data_bitrate", false, bus.bitrate, 10'000'000)) {
        bus.data_bitrate = static_cast<uint32_t>(*d);
      }
    }
    if (auto low = c.choice(t, path, "transceiver", false, kTransceivers, "transceiver")) {
      bus.low_speed = *low;
      if (*low && bus.kind != BusKind::can) {
        c.error(*t.get("transceiver"), path + ".transceiver",
                "low-speed (ISO 11898-3) transceivers are for classic CAN buses (kind = \"can\")");
      } else if (*low && bus.bitrate > 125'000) {
        c.error(*t.get("transceiver"), path + ".transceiver",
                fmt::format("a low-speed bus runs at up to 125000 bit/s, not {}", bus.bitrate));
      }
    }
    if (auto owner = c.string(t, path, "owner", false)) {
      if (!cfg.distributed.enabled) {
        c.error(*t.get("owner"), path + ".owner",
                "a bus of another daemon needs [distributed] (the installation's DDS domain)");
      } else if (!valid_name(*owner)) {
        c.error(*t.get("owner"), path + ".owner", kNameRule);
      } else if (*owner != cfg.distributed.name && bus.kind == BusKind::lin) {
        c.error(*t.get("owner"), path + ".owner",
                "LIN buses are simulated where they are declared; only CAN and CAN FD buses "
                "may have another daemon as owner");
      } else {
        bus.owner = *owner;
      }
    }
    cfg.buses.push_back(bus);
  });
}

// An X-CAN-2i: two interfaces on classic CAN buses, and a variant for their transceivers (/H
// both high-speed, /F both low-speed, /M interface 0 high-speed and interface 1 low-speed).
void check_xcan(Checker& c, const toml::node& ctl, const std::string& path, const Config& cfg,
                const DeviceConfig& dev) {
  if (dev.controllers.size() != 2) {
    c.error(ctl, path + ".controllers",
            fmt::format("{} controllers; an X-CAN-2i has 2 interfaces", dev.controllers.size()));
    return;
  }
  const BusConfig* b0 = cfg.bus(dev.controllers[0]);
  const BusConfig* b1 = cfg.bus(dev.controllers[1]);
  if (b0 == nullptr || b1 == nullptr) {
    return;  // said above
  }
  for (const BusConfig* b : {b0, b1}) {
    if (b->kind == BusKind::can_fd) {
      c.error(
          ctl, path + ".controllers",
          fmt::format("\"{}\" is a CAN FD bus; the 82527 is a classic CAN controller", b->name));
    }
  }
  if (b0->low_speed && !b1->low_speed) {
    c.error(ctl, path + ".controllers",
            "interface 0 low-speed and interface 1 high-speed: no X-CAN-2i variant has that "
            "(/M has interface 0 high-speed)");
  }
}

// `lin = ["lin0", ...]`: an IXXAT adapter's LIN controllers, each on a LIN bus; with the CAN
// controllers at most ipc::kMaxDeviceControllers in all.
void read_lin_controllers(Checker& c, const toml::table& t, const std::string& path,
                          const Config& cfg, DeviceConfig& dev) {
  const toml::node* lin = t.get("lin");
  if (lin == nullptr) {
    return;
  }
  auto buses = c.strings(t, path, "lin");
  if (!buses) {
    return;
  }
  if (dev.model == DeviceModel::sorcus_x_can_2i || dev.model == DeviceModel::sorcus_sl_cani) {
    c.error(*lin, path + ".lin", "only IXXAT adapters have LIN controllers");
    return;
  }
  for (const std::string& b : *buses) {
    const BusConfig* bus = cfg.bus(b);
    if (bus == nullptr) {
      c.error(*lin, path + ".lin", fmt::format("no bus is named \"{}\"", b));
    } else if (bus->kind != BusKind::lin) {
      c.error(*lin, path + ".lin", fmt::format("\"{}\" is not a LIN bus (kind = \"lin\")", b));
    }
  }
  if (dev.controllers.size() + buses->size() > ipc::kMaxDeviceControllers) {
    c.error(*lin, path + ".lin",
            fmt::format("{} CAN and {} LIN controllers; an adapter has at most {} in all",
                        dev.controllers.size(), buses->size(), ipc::kMaxDeviceControllers));
  }
  dev.lin = *buses;
}

// An SL-CANi: one 82527 on a classic CAN bus, in a slot of its own, maybe with a state file.
void check_slcan(Checker& c, const toml::table& t, const std::string& path, const Config& cfg,
                 std::set<int64_t>& slots, DeviceConfig& dev) {
  if (auto slot = c.integer(t, path, "slot", true, 0, 5)) {
    if (!slots.insert(*slot).second) {
      c.error(*t.get("slot"), path + ".slot",
              fmt::format("slot {} is another SL-CANi's (one S-Link per slot)", *slot));
    }
    dev.slot = static_cast<int>(*slot);
  }
  if (auto file = c.string(t, path, "eeprom", false)) {
    if (file->empty()) {
      c.error(*t.get("eeprom"), path + ".eeprom", "an empty path; leave the key out instead");
    }
    dev.eeprom = *file;
  }
  const toml::node* ctl = t.get("controllers");
  if (ctl == nullptr) {
    return;
  }
  if (dev.controllers.size() != 1) {
    c.error(*ctl, path + ".controllers",
            fmt::format("{} controllers; an SL-CANi has 1 interface", dev.controllers.size()));
    return;
  }
  const BusConfig* b = cfg.bus(dev.controllers[0]);
  if (b != nullptr && b->kind == BusKind::can_fd) {
    c.error(*ctl, path + ".controllers",
            fmt::format("\"{}\" is a CAN FD bus; the 82527 is a classic CAN controller", b->name));
  } else if (b != nullptr && b->low_speed) {
    c.error(*ctl, path + ".controllers",
            fmt::format("\"{}\" is a low-speed bus; the SL-CANi's transceiver is high-speed "
                        "(82C250)",
                        b->name));
  }
}

void read_devices(Checker& c, const toml::table& root, Config& cfg) {
  std::set<std::string> names;
  std::set<int64_t> slots;
  c.for_each_table(root, "device", [&](const toml::table& t, const std::string& path) {
    c.only_keys(t, path,
                {"name", "model", "controllers", "lin", "mdd_version", "buffer_load_time", "slot",
                 "eeprom"});
    DeviceConfig dev;
    dev.line = static_cast<uint32_t>(t.source().begin.line);
    if (auto name = read_name(c, t, path, names, "device")) {
      dev.name = *name;
    }
    if (auto model = c.choice(t, path, "model", true, kDeviceModels, "device model")) {
      dev.model = *model;
    }
    const toml::node* ctl = t.get("controllers");
    if (ctl == nullptr) {
      c.error(t.source(), path + ".controllers", "missing (the bus of each controller)");
    } else if (auto buses = c.strings(t, path, "controllers")) {
      if (buses->empty() || buses->size() > 4) {
        c.error(*ctl, path + ".controllers",
                fmt::format("{} controllers; an adapter has 1 to 4", buses->size()));
      }
      for (const std::string& b : *buses) {
        const BusConfig* bus = cfg.bus(b);
        if (bus == nullptr) {
          c.error(*ctl, path + ".controllers", fmt::format("no bus is named \"{}\"", b));
        } else if (bus->kind == BusKind::lin) {
          c.error(*ctl, path + ".controllers",
                  fmt::format("\"{}\" is a LIN bus; a CAN controller cannot sit on it", b));
        } else if (cfg.remote(*bus) && dev.model != DeviceModel::ixxat_usb_to_can &&
                   dev.model != DeviceModel::ixxat_usb_to_can_fd) {
          c.error(*ctl, path + ".controllers",
                  fmt::format("\"{}\" is simulated by daemon \"{}\"; SORCUS adapters need a "
                              "bus of this daemon (their 82527 drives the bus itself)",
                              b, bus->owner));
        }
      }
      dev.controllers = *buses;
      if (dev.model == DeviceModel::sorcus_x_can_2i) {
        check_xcan(c, *ctl, path, cfg, dev);
      }
    }
    if (auto version = c.string(t, path, "mdd_version", false)) {
      const toml::node& n = *t.get("mdd_version");
      if (dev.model != DeviceModel::sorcus_x_can_2i) {
        c.error(n, path + ".mdd_version", "only an X-CAN-2i (sorcus-x-can-2i) has an MDD");
      } else if (!model::sorcus::MddVersion::parse(*version)) {
        c.error(n, path + ".mdd_version",
                fmt::format("\"{}\": a version as the manual writes it, a digit, a dot and a "
                            "capital letter (\"3.C\")",
                            *version));
      } else {
        dev.mdd_version = *version;
      }
    }
    if (auto load = c.string(t, path, "buffer_load_time", false)) {
      const toml::node& n = *t.get("buffer_load_time");
      const std::optional<int64_t> ns = parse_duration(*load);
      if (dev.model != DeviceModel::sorcus_x_can_2i) {
        c.error(n, path + ".buffer_load_time", "only an X-CAN-2i (sorcus-x-can-2i) loads buffers");
      } else if (!ns || *ns > 1'000'000) {
        c.error(n, path + ".buffer_load_time",
                fmt::format("\"{}\": a duration from \"0us\" to \"1ms\" (\"5us\")", *load));
      } else {
        dev.buffer_load_ns = *ns;
      }
    }
    read_lin_controllers(c, t, path, cfg, dev);
    if (dev.model == DeviceModel::sorcus_sl_cani) {
      check_slcan(c, t, path, cfg, slots, dev);
    } else {
      for (const char* key : {"slot", "eeprom"}) {
        if (const toml::node* n = t.get(key)) {
          c.error(*n, path + "." + key, "only a sorcus-sl-cani device has this key");
        }
      }
    }
    cfg.devices.push_back(dev);
  });
}

}  // namespace

namespace detail {
std::string beside_config(const Config& cfg, const std::string& file) {
  const std::size_t slash = cfg.source.find_last_of('/');
  const bool relative = !file.empty() && file[0] != '/';
  return relative && slash != std::string::npos ? cfg.source.substr(0, slash + 1) + file : file;
}
}  // namespace detail

std::string_view to_string(BusKind kind) {
  return name_of(kind, kBusKinds);
}

std::string_view to_string(DeviceModel model) {
  return name_of(model, kDeviceModels);
}

tl::expected<TimeSetting, std::string> parse_time_setting(std::string_view text) {
  if (text == "realtime") {
    return TimeSetting{TimeMode::realtime, 1.0};
  }
  if (text == "stepped") {
    return TimeSetting{TimeMode::stepped, 1.0};
  }
  if (text.substr(0, 7) == "scaled:") {
    const std::string number(text.substr(7));
    char* end = nullptr;
    const double f = std::strtod(number.c_str(), &end);
    if (!number.empty() && end == number.c_str() + number.size() && f >= 1e-6 && f <= 1e6) {
      return TimeSetting{TimeMode::scaled, f};
    }
    return tl::unexpected(fmt::format(
        "\"{}\": the factor after \"scaled:\" must be a number from 0.000001 to 1000000", text));
  }
  return tl::unexpected(
      fmt::format("\"{}\" is not a time mode (realtime, stepped, scaled:F)", text));
}

std::optional<int64_t> parse_duration(std::string_view text) {
  return ipc::parse_duration(text);
}

bool valid_name(std::string_view s) {
  return !s.empty() && s.size() <= 28 && std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
}

std::string to_string(const TimeSetting& time) {
  switch (time.mode) {
    case TimeMode::realtime:
      return "realtime";
    case TimeMode::stepped:
      return "stepped";
    case TimeMode::scaled:
      return fmt::format("scaled:{}", time.scale);
  }
  return "?";
}

const BusConfig* Config::bus(std::string_view name) const {
  for (const BusConfig& b : buses) {
    if (b.name == name) {
      return &b;
    }
  }
  return nullptr;
}

tl::expected<Config, ConfigErrors> parse_config(std::string_view text, std::string source) {
  Checker c(source);
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    c.error(e.source(), "syntax", e.description());
    return tl::unexpected(c.errors());
  }
  Config cfg;
  cfg.source = std::move(source);
  c.only_keys(root, "",
              {"simulation", "security", "distributed", "bus", "device", "lin_node", "can_node",
               "scenario", "recorder", "bridge"});
  read_simulation(c, root, cfg);
  read_security(c, root, cfg);
  read_distributed(c, root, cfg);
  read_buses(c, root, cfg);
  if (cfg.simulation.time.mode == TimeMode::stepped) {
    // One time authority: stepped time follows the owner of the remote buses.
    const BusConfig* first = nullptr;
    for (const BusConfig& b : cfg.buses) {
      if (!cfg.remote(b)) {
        continue;
      }
      if (first == nullptr) {
        first = &b;
      } else if (b.owner != first->owner) {
        c.error(root.source(), "bus",
                fmt::format("in stepped time the remote buses must have one owner (its steps are "
                            "this daemon's): \"{}\" is daemon {}'s, \"{}\" daemon {}'s",
                            first->name, first->owner, b.name, b.owner));
        break;
      }
    }
  }
  read_devices(c, root, cfg);
  detail::read_lin_nodes(c, root, cfg);
  detail::read_can_nodes(c, root, cfg);
  detail::read_recorders(c, root, cfg);
  detail::read_bridges(c, root, cfg);
  c.for_each_table(root, "scenario", [&](const toml::table& t, const std::string& path) {
    c.only_keys(t, path, {"file"});
    if (auto file = c.string(t, path, "file", true)) {
      cfg.scenario_files.push_back(detail::beside_config(cfg, *file));
    }
  });
  std::size_t controllers = 0;
  for (const DeviceConfig& d : cfg.devices) {
    controllers += d.controllers.size() + d.lin.size();
  }
  if (cfg.buses.size() > kMaxBuses) {
    c.error(root.source(), "bus", fmt::format("{} buses; at most {}", cfg.buses.size(), kMaxBuses));
  }
  if (controllers > kMaxControllers) {
    c.error(root.source(), "device",
            fmt::format("{} controllers in all; at most {}", controllers, kMaxControllers));
  }
  if (!c.errors().empty()) {
    return tl::unexpected(c.errors());
  }
  return cfg;
}

tl::expected<std::string, std::string> read_text_file(const std::string& path) {
  return ipc::read_text_file(path, kMaxConfigFileBytes);
}

tl::expected<Config, ConfigErrors> load_config_file(const std::string& path) {
  auto text = read_text_file(path);
  if (!text) {
    return tl::unexpected(ConfigErrors{text.error()});
  }
  return parse_config(*text, path);
}

std::string_view embedded_default_config() {
  return detail::default_config_text();
}

tl::expected<Config, ConfigErrors> load_default_config() {
  return parse_config(embedded_default_config(), "<embedded default>");
}

}  // namespace canemu::daemon
