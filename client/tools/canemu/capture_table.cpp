#include "capture_table.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>

#include <fmt/format.h>

#include "canemu/client/lists.hpp"
#include "canemu/ipc/capture_writer.hpp"
#include "command.hpp"

namespace canemu::cli {

namespace {

std::string format_name(uint8_t format) {
  return std::string(ipc::to_string(static_cast<ipc::CaptureFormat>(format)));
}

}  // namespace

tl::expected<CaptureLists, std::string> capture_lists(client::Connection& c) {
  auto recorders = client::fetch_recorder_list(c);
  auto bridges = client::fetch_bridge_list(c);
  if (!recorders || !bridges) {
    return tl::unexpected(!recorders ? recorders.error().message : bridges.error().message);
  }
  return CaptureLists{std::move(*recorders), std::move(*bridges)};
}

void print_recorders(const std::vector<ipc::RecorderEntry>& r) {
  std::printf("%-12s %-7s %10s %12s %7s %8s %s\n", "RECORDER", "FORMAT", "FRAMES", "BYTES",
              "ROTATED", "LOST", "FILE");
  for (const ipc::RecorderEntry& e : r) {
    const std::string error = ipc::name_of(e.error);
    std::printf("%-12s %-7s %10llu %12llu %7u %8llu %s%s\n", ipc::name_of(e.bus).c_str(),
                format_name(e.format).c_str(), static_cast<unsigned long long>(e.frames),
                static_cast<unsigned long long>(e.bytes), e.rotations,
                static_cast<unsigned long long>(e.lost), ipc::name_of(e.path).c_str(),
                error.empty() ? "" : ("  (" + error + ")").c_str());
  }
}

toml::array recorders_array(const std::vector<ipc::RecorderEntry>& r) {
  const auto i64 = [](uint64_t v) { return static_cast<int64_t>(v); };
  toml::array out;
  for (const ipc::RecorderEntry& e : r) {
    out.push_back(toml::table{{"bus", ipc::name_of(e.bus)},
                              {"path", ipc::name_of(e.path)},
                              {"format", format_name(e.format)},
                              {"errors", e.errors != 0},
                              {"frames", i64(e.frames)},
                              {"bytes", i64(e.bytes)},
                              {"rotations", i64(e.rotations)},
                              {"lost", i64(e.lost)},
                              {"error", ipc::name_of(e.error)}});
  }
  return out;
}

namespace {

// LCM and DDS bridges (by bus): PUBLISHED frames on FRAMES, EVENTS on ERRORS and STATES,
// PUB-FAIL what LCM or DDS refused; RECEIVED on TX, SENT of them on the bus, Q-DROP, REJECTED,
// FAILED as for SocketCAN; WHERE: LCM's URL, DDS's domain/partition.
void print_bus_bridges(const std::vector<ipc::BridgeEntry>& r, uint8_t kind) {
  const auto n = [](uint64_t v) { return static_cast<unsigned long long>(v); };
  bool any = false;
  for (const ipc::BridgeEntry& e : r) {
    any = any || e.kind == kind;
  }
  if (!any) {
    return;
  }
  const bool lcm = kind == ipc::kBridgeLcm;
  std::printf("%-12s %-20s %-14s %4s %4s %8s %10s %8s %8s %10s %10s %8s %8s %8s  %s\n",
              lcm ? "LCM-BRIDGE" : "DDS-BRIDGE", lcm ? "CHANNELS" : "TOPICS", "STATE", "TEC", "REC",
              "RESTARTS", "PUBLISHED", "EVENTS", "PUB-FAIL", "RECEIVED", "SENT", "Q-DROP",
              "REJECTED", "FAILED", lcm ? "URL" : "DOMAIN/PARTITION");
  for (const ipc::BridgeEntry& e : r) {
    if (e.kind != kind) {
      continue;
    }
    std::printf(
        "%-12s %-20s %-14s %4u %4u %8llu %10llu %8llu %8llu %10llu %10llu %8llu %8llu %8llu  "
        "%s\n",
        ipc::name_of(e.bus).c_str(), (ipc::name_of(e.channel_prefix) + "*").c_str(),
        error_state_name(e.state).c_str(), e.tec, e.rec, n(e.restarts), n(e.to_interface),
        n(e.error_frames_written), n(e.to_interface_dropped), n(e.received), n(e.from_interface),
        n(e.queue_dropped), n(e.rejected), n(e.tx_failed), ipc::name_of(e.url).c_str());
  }
}

}  // namespace

void print_bridges(const std::vector<ipc::BridgeEntry>& r) {
  const auto n = [](uint64_t v) { return static_cast<unsigned long long>(v); };
  bool socketcan = false;
  bool by_bus = false;
  for (const ipc::BridgeEntry& e : r) {
    (e.kind == ipc::kBridgeSocketCan ? socketcan : by_bus) = true;
  }
  if (socketcan || !by_bus) {
    std::printf("%-12s %-10s %-14s %4s %4s %8s %10s %10s %7s %8s %8s %8s %8s %8s\n", "BRIDGE",
                "INTERFACE", "STATE", "TEC", "REC", "RESTARTS", "TO-IF", "FROM-IF", "ERRORS",
                "IF-DROP", "K-DROP", "Q-DROP", "REJECTED", "FAILED");
  }
  for (const ipc::BridgeEntry& e : r) {
    if (e.kind != ipc::kBridgeSocketCan) {
      continue;
    }
    std::printf(
        "%-12s %-10s %-14s %4u %4u %8llu %10llu %10llu %7llu %8llu %8llu %8llu %8llu "
        "%8llu\n",
        ipc::name_of(e.bus).c_str(), ipc::name_of(e.interface).c_str(),
        error_state_name(e.state).c_str(), e.tec, e.rec, n(e.restarts), n(e.to_interface),
        n(e.from_interface), n(e.error_frames_written), n(e.to_interface_dropped),
        n(e.kernel_dropped), n(e.queue_dropped), n(e.rejected), n(e.tx_failed));
  }
  print_bus_bridges(r, ipc::kBridgeLcm);
  print_bus_bridges(r, ipc::kBridgeDds);
}

namespace {

// Why the bridge rejected what it rejected: "rejected_by" with a count per reason, and
// "last_rejected" with the last one's rule and place ("" while none was).
void add_rejections(toml::table& entry, const ipc::BridgeEntry& e) {
  toml::table by;
  for (std::size_t k = 0; k < ipc::kBridgeRejectReasons; ++k) {
    by.insert(ipc::kBridgeRejectNames[k], static_cast<int64_t>(e.rejected_by[k]));
  }
  entry.insert("rejected_by", std::move(by));
  entry.insert("last_rejected", ipc::printable_name_of(e.last_rejected));
}

}  // namespace

toml::array bridges_array(const std::vector<ipc::BridgeEntry>& r) {
  const auto i64 = [](uint64_t v) { return static_cast<int64_t>(v); };
  toml::array out;
  for (const ipc::BridgeEntry& e : r) {
    if (e.kind == ipc::kBridgeLcm || e.kind == ipc::kBridgeDds) {
      const bool lcm = e.kind == ipc::kBridgeLcm;
      const std::string prefix = ipc::name_of(e.channel_prefix);
      toml::table where;
      if (lcm) {
        where.insert("url", ipc::name_of(e.url));
        where.insert("channel_prefix", prefix);
        where.insert("channels", toml::table{{"frames", prefix + "FRAMES"},
                                             {"errors", prefix + "ERRORS"},
                                             {"states", prefix + "STATES"},
                                             {"tx", prefix + "TX"}});
      } else {
        const std::string locator = ipc::name_of(e.url);
        const auto slash = locator.find('/');
        const bool ros2 = locator.ends_with("+ros2");
        const std::string partition =
            slash == std::string::npos
                ? std::string()
                : locator.substr(slash + 1, locator.size() - slash - 1 - (ros2 ? 5 : 0));
        int64_t domain = -1;  // as the daemon wrote it: DOMAIN/PARTITION[+ros2]
        std::from_chars(locator.data(), locator.data() + std::min(slash, locator.size()), domain);
        where.insert("domain", domain);
        where.insert("partition", partition);
        where.insert("topic_prefix", prefix);
        toml::table topics{{"frames", prefix + "frames"},
                           {"errors", prefix + "errors"},
                           {"states", prefix + "states"},
                           {"tx", prefix + "tx"}};
        if (ros2) {
          topics.insert("ros2_from_can_bus", "rt/" + ipc::name_of(e.bus) + "/from_can_bus");
          topics.insert("ros2_to_can_bus", "rt/" + ipc::name_of(e.bus) + "/to_can_bus");
        }
        where.insert("ros2", ros2);
        where.insert("topics", std::move(topics));
      }
      toml::table entry{
          {"kind", lcm ? "lcm" : "dds"},
          {"bus", ipc::name_of(e.bus)},
          {"restart_ms", i64(e.restart_ms)},
          {"restarts", i64(e.restarts)},
          {"state", error_state_name(e.state)},
          {"tec", i64(e.tec)},
          {"rec", i64(e.rec)},
          {"queued", i64(e.queued)},
          {"published", i64(e.to_interface)},
          {"published_events", i64(e.error_frames_written)},
          {"publish_failed", i64(e.to_interface_dropped)},
          {"received", i64(e.received)},
          {"sent", i64(e.from_interface)},
          {"queue_dropped", i64(e.queue_dropped)},
          {"rejected", i64(e.rejected)},
          {"tx_failed", i64(e.tx_failed)},
          {"dropped", i64(e.to_interface_dropped + e.queue_dropped + e.rejected + e.tx_failed)}};
      for (auto&& [key, value] : where) {
        entry.insert(key, value);
      }
      add_rejections(entry, e);
      out.push_back(std::move(entry));
      continue;
    }
    toml::table entry{{"kind", "socketcan"},
                      {"bus", ipc::name_of(e.bus)},
                      {"interface", ipc::name_of(e.interface)},
                      {"error_frames", e.error_frames != 0},
                      {"restart_ms", i64(e.restart_ms)},
                      {"restarts", i64(e.restarts)},
                      {"state", error_state_name(e.state)},
                      {"tec", i64(e.tec)},
                      {"rec", i64(e.rec)},
                      {"queued", i64(e.queued)},
                      {"to_interface", i64(e.to_interface)},
                      {"from_interface", i64(e.from_interface)},
                      {"error_frames_written", i64(e.error_frames_written)},
                      {"to_interface_dropped", i64(e.to_interface_dropped)},
                      {"kernel_dropped", i64(e.kernel_dropped)},
                      {"queue_dropped", i64(e.queue_dropped)},
                      {"rejected", i64(e.rejected)},
                      {"tx_failed", i64(e.tx_failed)}};
    add_rejections(entry, e);
    out.push_back(std::move(entry));
  }
  return out;
}

}  // namespace canemu::cli
