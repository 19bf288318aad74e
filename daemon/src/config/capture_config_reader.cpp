// [[recorder]] tables (a bus recorded by canemud into a candump log or a pcap file; a LIN bus
// into pcap only) and [[bridge]] tables (a bus joined to a Linux CAN interface).
#include <set>
#include <utility>

#include <fmt/format.h>

#include "canemu/daemon/config/names.hpp"
#include "canemu/ipc/capture_messages.hpp"
#include "capture_config_reader.hpp"

namespace canemu::daemon::detail {

namespace {

constexpr NamedValue<bool> kFormats[] = {{false, "candump"}, {true, "pcap"}};
constexpr uint64_t kMinRotationSize = 1024;
constexpr uint64_t kMaxRotationSize = uint64_t{1} << 40;

// A size: an integer of bytes, or a string "<n>", "<n>KiB", "<n>MiB", "<n>GiB".
std::optional<uint64_t> read_size(Checker& c, const toml::table& t, const std::string& path,
                                  std::string_view name) {
  const toml::node* n = t.get(name);
  if (n == nullptr) {
    return std::nullopt;
  }
  const std::string key = Checker::key(path, name);
  uint64_t bytes = 0;
  if (n->is_integer()) {
    const int64_t v = n->as_integer()->get();
    if (v < 0) {
      c.error(*n, key, fmt::format("{} is negative", v));
      return std::nullopt;
    }
    bytes = static_cast<uint64_t>(v);
  } else if (n->is_string()) {
    const std::string text(n->as_string()->get());
    std::size_t digits = 0;
    while (digits < text.size() && text[digits] >= '0' && text[digits] <= '9') {
      ++digits;
    }
    const std::string unit = text.substr(digits);
    const uint64_t scale = unit.empty()    ? 1
                           : unit == "KiB" ? uint64_t{1} << 10
                           : unit == "MiB" ? uint64_t{1} << 20
                           : unit == "GiB" ? uint64_t{1} << 30
                                           : 0;
    if (digits == 0 || digits > 12 || scale == 0) {
      c.error(*n, key,
              fmt::format("\"{}\" is not a size (bytes, or a number with KiB, MiB, GiB)", text));
      return std::nullopt;
    }
    bytes = std::stoull(text.substr(0, digits)) * scale;
  } else {
    c.error(*n, key, "must be a number of bytes or a string such as \"10MiB\"");
    return std::nullopt;
  }
  if (bytes != 0 && (bytes < kMinRotationSize || bytes > kMaxRotationSize)) {
    c.error(*n, key,
            fmt::format("{} bytes is outside {}..{} (or 0: no rotation)", bytes, kMinRotationSize,
                        kMaxRotationSize));
    return std::nullopt;
  }
  return bytes;
}

}  // namespace

void read_recorders(Checker& c, const toml::table& root, Config& cfg) {
  std::set<std::string> paths;
  c.for_each_table(root, "recorder", [&](const toml::table& t, const std::string& path) {
    c.only_keys(t, path, {"bus", "path", "format", "max_size", "max_files", "errors"});
    RecorderConfig r;
    r.line = static_cast<uint32_t>(t.source().begin.line);
    bool lin = false;
    if (auto bus = c.string(t, path, "bus", true)) {
      r.bus = *bus;
      const BusConfig* b = cfg.bus(*bus);
      if (b == nullptr) {
        c.error(*t.get("bus"), path + ".bus", fmt::format("no bus is named \"{}\"", *bus));
      } else {
        lin = b->kind == BusKind::lin;
      }
    }
    if (auto file = c.string(t, path, "path", true)) {
      if (file->empty()) {
        c.error(*t.get("path"), path + ".path", "must name a file");
      } else {
        r.path = beside_config(cfg, *file);
        r.pcap = r.path.size() > 5 && r.path.substr(r.path.size() - 5) == ".pcap";
        if (!paths.insert(r.path).second) {
          c.error(*t.get("path"), path + ".path",
                  fmt::format("another recorder writes \"{}\" already", r.path));
        }
      }
    }
    if (auto pcap = c.choice(t, path, "format", false, kFormats, "recording format")) {
      r.pcap = *pcap;
      if (lin && !*pcap) {
        // A candump log has no LIN; LINKTYPE_LIN in pcap has.
        c.error(*t.get("format"), path + ".format",
                fmt::format("\"{}\" is a LIN bus; a candump log holds CAN frames only, "
                            "format = \"pcap\" records it (LINKTYPE_LIN)",
                            r.bus));
      }
    } else if (lin) {
      r.pcap = true;  // a LIN bus's only format
    }
    if (auto size = read_size(c, t, path, "max_size")) {
      r.max_size = *size;
    }
    if (auto files = c.integer(t, path, "max_files", false, 0, 1000)) {
      r.max_files = static_cast<uint32_t>(*files);
    }
    if (const toml::node* n = t.get("errors")) {
      if (!n->is_boolean()) {
        c.error(*n, path + ".errors", "must be true or false");
      } else {
        r.errors = n->as_boolean()->get();
      }
    }
    cfg.recorders.push_back(r);
  });
}

std::optional<std::string> interface_name_problem(std::string_view name) {
  if (name.empty() || name.size() > 15) {
    return fmt::format("\"{}\" is not an interface name (1 to 15 characters)", name);
  }
  for (char ch : name) {
    if (ch == '/' || ch == ':' || static_cast<unsigned char>(ch) <= ' ') {
      return fmt::format("\"{}\" is not an interface name (no '/', ':' or blanks)", name);
    }
  }
  return std::nullopt;
}

void read_bridges(Checker& c, const toml::table& root, Config& cfg) {
  std::set<std::string> interfaces;
  std::set<std::string> lcm_buses;
  std::set<std::pair<std::string, std::string>> lcm_channels;
  std::set<std::string> dds_buses;
  std::set<std::string> dds_topics;  // domain/partition/prefix
  c.for_each_table(root, "bridge", [&](const toml::table& t, const std::string& path) {
    BridgeConfig b;
    b.line = static_cast<uint32_t>(t.source().begin.line);
    const toml::node* kind_node = t.get("kind");
    const bool lcm = kind_node != nullptr && kind_node->value<std::string>() == "lcm";
    const bool dds = kind_node != nullptr && kind_node->value<std::string>() == "dds";
    if (lcm) {
      c.only_keys(t, path, {"kind", "bus", "url", "channel_prefix", "restart_ms"});
    } else if (dds) {
      c.only_keys(t, path,
                  {"kind", "bus", "domain", "partition", "topic_prefix", "ros2", "restart_ms"});
    } else {
      c.only_keys(t, path, {"kind", "bus", "interface", "error_frames", "restart_ms"});
    }
    if (auto kind = c.string(t, path, "kind", true)) {
      b.kind = *kind;
      if (*kind != "socketcan" && *kind != "lcm" && *kind != "dds") {
        c.error(*t.get("kind"), path + ".kind",
                fmt::format("\"{}\" is not a bridge kind (socketcan, lcm, dds)", *kind));
      }
    }
    if (auto bus = c.string(t, path, "bus", true)) {
      b.bus = *bus;
      const BusConfig* bc = cfg.bus(*bus);
      if (bc == nullptr) {
        c.error(*t.get("bus"), path + ".bus", fmt::format("no bus is named \"{}\"", *bus));
      } else if (bc->kind == BusKind::lin) {
        c.error(*t.get("bus"), path + ".bus",
                fmt::format("\"{}\" is a LIN bus; {} bridges join CAN buses", *bus,
                            lcm   ? "LCM"
                            : dds ? "DDS"
                                  : "SocketCAN"));
      } else if (lcm && !lcm_buses.insert(*bus).second) {
        c.error(*t.get("bus"), path + ".bus",
                fmt::format("another LCM bridge joins \"{}\" already", *bus));
      } else if (dds && !dds_buses.insert(*bus).second) {
        c.error(*t.get("bus"), path + ".bus",
                fmt::format("another DDS bridge joins \"{}\" already", *bus));
      }
    }
    if (lcm) {
      b.url = std::string(kDefaultLcmUrl);
      if (auto url = c.string(t, path, "url", false)) {
        b.url = *url;
        if (auto problem = lcm_url_problem(*url)) {
          c.error(*t.get("url"), path + ".url", *problem);
        }
      }
      b.channel_prefix = default_lcm_prefix(b.bus);
      if (auto prefix = c.string(t, path, "channel_prefix", false)) {
        b.channel_prefix = *prefix;
        if (auto problem = lcm_prefix_problem(*prefix)) {
          c.error(*t.get("channel_prefix"), path + ".channel_prefix", *problem);
        }
      }
      if (!b.bus.empty() && !lcm_channels.insert({b.url, b.channel_prefix}).second) {
        c.error(t, path,
                fmt::format("another LCM bridge uses the channels {}* on {} already (their frames "
                            "would loop)",
                            b.channel_prefix, b.url));
      }
    }
    if (dds) {
      if (auto domain = c.integer(t, path, "domain", false, 0, kMaxDdsDomain)) {
        b.domain = static_cast<uint32_t>(*domain);
      }
      b.partition = std::string(kDefaultDdsPartition);
      if (auto partition = c.string(t, path, "partition", false)) {
        b.partition = *partition;
        if (auto problem = dds_partition_problem(*partition)) {
          c.error(*t.get("partition"), path + ".partition", *problem);
        }
      }
      b.channel_prefix = default_dds_prefix(b.bus);
      if (auto prefix = c.string(t, path, "topic_prefix", false)) {
        b.channel_prefix = *prefix;
        if (auto problem = dds_prefix_problem(*prefix)) {
          c.error(*t.get("topic_prefix"), path + ".topic_prefix", *problem);
        }
      }
      if (const toml::node* n = t.get("ros2")) {
        if (!n->is_boolean()) {
          c.error(*n, path + ".ros2", "must be true or false");
        } else {
          b.ros2 = n->as_boolean()->get();
        }
      }
      const std::string topics = fmt::format("{}/{}/{}", b.domain, b.partition, b.channel_prefix);
      if (!b.bus.empty() && !dds_topics.insert(topics).second) {
        c.error(t, path,
                fmt::format("another DDS bridge uses the topics {}* in domain {}, partition {} "
                            "already (their frames would loop)",
                            b.channel_prefix, b.domain, b.partition));
      }
    }
    if (!lcm && !dds) {
      if (auto name = c.string(t, path, "interface", true)) {
        b.interface = *name;
        if (auto problem = interface_name_problem(*name)) {
          c.error(*t.get("interface"), path + ".interface", *problem);
        } else if (!interfaces.insert(*name).second) {
          c.error(*t.get("interface"), path + ".interface",
                  fmt::format("another bridge uses \"{}\" already (its frames would loop)", *name));
        }
      }
      if (const toml::node* n = t.get("error_frames")) {
        if (!n->is_boolean()) {
          c.error(*n, path + ".error_frames", "must be true or false");
        } else {
          b.error_frames = n->as_boolean()->get();
        }
      }
    }
    if (auto ms = c.integer(t, path, "restart_ms", false, 0, ipc::kMaxBridgeRestartMs)) {
      b.restart_ms = static_cast<uint32_t>(*ms);
    }
    cfg.bridges.push_back(b);
  });
}

}  // namespace canemu::daemon::detail
