// canemu bridge add|list|restart|remove: SocketCAN, LCM and DDS bridges while canemud runs
// (docs/socketcan.md, docs/bridges.md).
#include <cstdio>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/ipc/protocol.hpp"
#include "capture_table.hpp"
#include "command.hpp"
#include "fault_table.hpp"

namespace canemu::cli {

namespace {

struct BridgeArgs {
  std::string bus;
  std::string interface;
  bool error_frames = false;
  int64_t restart_ms = 0;
  bool json = false;
  CLI::Option* lcm = nullptr;  // --lcm [URL]: an LCM bridge (of BUS, for remove and restart)
  CLI::Option* dds = nullptr;  // --dds [DOMAIN/PARTITION]: a DDS bridge (likewise)
  std::string url;             // LCM: the URL; DDS: DOMAIN/PARTITION
  std::string prefix;
  bool ros2 = false;
};

uint8_t kind_of(const BridgeArgs& a) {
  if (a.lcm != nullptr && a.lcm->count() > 0) {
    return ipc::kBridgeLcm;
  }
  if (a.dds != nullptr && a.dds->count() > 0) {
    return ipc::kBridgeDds;
  }
  return ipc::kBridgeSocketCan;
}

// "LCM bridge of can0", "bridge on vcan0"
std::string bridge_name(uint8_t kind, const std::string& name) {
  return kind == ipc::kBridgeLcm   ? "LCM bridge of " + name
         : kind == ipc::kBridgeDds ? "DDS bridge of " + name
                                   : "bridge on " + name;
}

std::string restart_text(int64_t restart_ms) {
  return restart_ms != 0 ? fmt::format(" (restart {} ms after bus-off)", restart_ms) : "";
}

int run_add(const std::string& socket, const BridgeArgs& a) {
  if (a.restart_ms < 0 || a.restart_ms > ipc::kMaxBridgeRestartMs) {
    return fail(fmt::format("--restart-ms {} is outside 0..{} (ms after bus-off; 0: stay bus-off)",
                            a.restart_ms, ipc::kMaxBridgeRestartMs));
  }
  const uint8_t kind = kind_of(a);
  if (a.lcm->count() > 0 && a.dds->count() > 0) {
    return fail("--lcm or --dds, not both");
  }
  const bool by_bus = kind != ipc::kBridgeSocketCan;
  if (by_bus && (!a.interface.empty() || a.error_frames)) {
    return fail(fmt::format(
        "an {} bridge has no INTERFACE and no --error-frames (it always publishes the node's "
        "errors and states)",
        kind == ipc::kBridgeLcm ? "LCM" : "DDS"));
  }
  if (!by_bus && a.interface.empty()) {
    return fail(
        "which interface? canemu bridge add BUS INTERFACE, or BUS --lcm [URL], or BUS --dds "
        "[DOMAIN/PARTITION]");
  }
  if (!by_bus && !a.prefix.empty()) {
    return fail("--prefix is for LCM and DDS bridges (--lcm, --dds)");
  }
  if (kind != ipc::kBridgeDds && a.ros2) {
    return fail("--ros2 is for DDS bridges (--dds)");
  }
  std::string url = a.url;
  if (kind == ipc::kBridgeDds && a.ros2) {
    url = (url.empty() ? "0/canemu" : url) + "+ros2";
  }
  if (url.size() >= ipc::kLcmUrlSize || a.prefix.size() >= ipc::kLcmPrefixSize) {
    return fail(fmt::format("the URL takes up to {} characters, the prefix up to {}",
                            ipc::kLcmUrlSize - 1, ipc::kLcmPrefixSize - 1));
  }
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto req = ipc::make_message<ipc::BridgeAddRequest>();
  ipc::copy_name(req.bus, a.bus);
  ipc::copy_name(req.interface, a.interface);
  req.kind = kind;
  ipc::copy_name(req.url, url);
  ipc::copy_name(req.channel_prefix, a.prefix);
  req.error_frames = a.error_frames ? 1 : 0;
  req.restart_ms = static_cast<uint32_t>(a.restart_ms);
  auto r = c->call<ipc::BridgeAddRequest, ipc::BridgeAddReply>(req);
  if (!r) {
    return fail(r.error().message);
  }
  if (by_bus) {
    // What the daemon chose: the defaults for what was not given.
    auto list = client::fetch_bridge_list(*c);
    std::string prefix = a.prefix;
    std::string where = url;
    if (list) {
      for (const ipc::BridgeEntry& e : *list) {
        if (e.kind == kind && ipc::name_of(e.bus) == a.bus) {
          prefix = ipc::name_of(e.channel_prefix);
          where = ipc::name_of(e.url);
        }
      }
    }
    if (kind == ipc::kBridgeLcm) {
      std::printf("%s bridged to LCM channels %s* on %s%s\n", a.bus.c_str(), prefix.c_str(),
                  where.c_str(), restart_text(a.restart_ms).c_str());
    } else {
      std::printf("%s bridged to DDS topics %s* in domain/partition %s%s\n", a.bus.c_str(),
                  prefix.c_str(), where.c_str(), restart_text(a.restart_ms).c_str());
    }
    return 0;
  }
  std::string how;
  if (a.error_frames) {
    how += "with error frames";
  }
  if (a.restart_ms != 0) {
    how += fmt::format("{}restart {} ms after bus-off", how.empty() ? "" : ", ", a.restart_ms);
  }
  std::printf("%s bridged to %s%s\n", a.bus.c_str(), a.interface.c_str(),
              how.empty() ? "" : (" (" + how + ")").c_str());
  if (const std::string warning = ipc::name_of(r->warning); !warning.empty()) {
    std::fflush(stdout);
    std::fprintf(stderr, "canemu: warning: %s\n", warning.c_str());
  }
  return 0;
}

// Fills the request's kind and names from --lcm/--dds and INTERFACE (the bus for those).
template <typename Request>
Request by_name(const BridgeArgs& a) {
  auto req = ipc::make_message<Request>();
  req.kind = kind_of(a);
  if (req.kind != ipc::kBridgeSocketCan) {
    ipc::copy_name(req.bus, a.interface);
  } else {
    ipc::copy_name(req.interface, a.interface);
  }
  return req;
}

int run_restart(const std::string& socket, const BridgeArgs& a) {
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = c->call<ipc::BridgeRestartRequest, ipc::BridgeRestartReply>(
      by_name<ipc::BridgeRestartRequest>(a));
  if (!r) {
    return fail(r.error().message);
  }
  std::printf("%s restarted (error-active after 128 x 11 recessive bits)\n",
              bridge_name(kind_of(a), a.interface).c_str());
  return 0;
}

int run_remove(const std::string& socket, const BridgeArgs& a) {
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = c->call<ipc::BridgeRemoveRequest, ipc::BridgeRemoveReply>(
      by_name<ipc::BridgeRemoveRequest>(a));
  if (!r) {
    return fail(r.error().message);
  }
  std::printf("%s removed\n", bridge_name(kind_of(a), a.interface).c_str());
  return 0;
}

int run_list(const std::string& socket, const BridgeArgs& a) {
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = client::fetch_bridge_list(*c);
  if (!r) {
    return fail(r.error().message);
  }
  if (a.json) {
    std::printf("%s\n", one_line_json(bridges_array(*r)).c_str());
  } else {
    print_bridges(*r);
  }
  return 0;
}

}  // namespace

Command add_bridge(CLI::App& app, const std::string& socket) {
  auto* bridge =
      app.add_subcommand("bridge", "SocketCAN, LCM and DDS bridges: add, list, restart, remove");
  bridge->require_subcommand(1);
  auto a = std::make_shared<BridgeArgs>();
  auto* add = bridge->add_subcommand(
      "add",
      "join BUS to the Linux CAN interface INTERFACE, or with --lcm to LCM channels, with --dds "
      "to DDS topics");
  add->add_option("BUS", a->bus, "bus name")->required();
  add->add_option("INTERFACE", a->interface, "vcan0, vxcan1, can0, ... (not with --lcm, --dds)");
  auto* add_lcm = add->add_option("--lcm", a->url,
                                  "an LCM bridge instead, on the LCM URL given (default "
                                  "udpm://239.255.76.67:7667?ttl=0, which stays on this host)");
  add_lcm->expected(0, 1);
  auto* add_dds = add->add_option("--dds", a->url,
                                  "a DDS bridge instead, in DOMAIN/PARTITION (default 0/canemu)");
  add_dds->expected(0, 1);
  add->add_flag("--ros2", a->ros2,
                "DDS: ROS 2's can_msgs/msg/Frame on rt/BUS/from_can_bus and rt/BUS/to_can_bus too");
  add->add_option("--prefix", a->prefix,
                  "LCM: the channels' prefix (default CANEMU_<BUS>_: CANEMU_CAN0_FRAMES, ...); "
                  "DDS: the topics' prefix (default canemu/<bus>/: canemu/can0/frames, ...)");
  add->add_flag("-e,--error-frames", a->error_frames,
                "the bridge node's errors and states as CAN_ERR_* frames on the interface");
  add->add_option("--restart-ms", a->restart_ms,
                  "restart the bridge's node this many ms after bus-off (0..60000; 0, the "
                  "default: it stays bus-off, as restart-ms 0 of a kernel CAN interface)");
  auto* restart = bridge->add_subcommand(
      "restart", "restart the bus-off node of the bridge on INTERFACE (--lcm, --dds: of BUS)");
  restart->add_option("INTERFACE", a->interface, "the bridged interface, or the bus (--lcm, --dds)")
      ->required();
  auto* restart_lcm =
      restart->add_flag("--lcm")->description("the LCM bridge of the bus INTERFACE names");
  auto* restart_dds =
      restart->add_flag("--dds")->description("the DDS bridge of the bus INTERFACE names");
  auto* list = bridge->add_subcommand("list", "bridges with their node's state and counts");
  list->add_flag("--json", a->json, "a JSON array instead of a table");
  auto* remove =
      bridge->add_subcommand("remove", "take the bridge off INTERFACE (--lcm, --dds: off BUS)");
  remove->add_option("INTERFACE", a->interface, "the bridged interface, or the bus (--lcm, --dds)")
      ->required();
  auto* remove_lcm =
      remove->add_flag("--lcm")->description("the LCM bridge of the bus INTERFACE names");
  auto* remove_dds =
      remove->add_flag("--dds")->description("the DDS bridge of the bus INTERFACE names");
  return {bridge, [&socket, a, add, remove, restart, add_lcm, restart_lcm, remove_lcm, add_dds,
                   restart_dds, remove_dds] {
            a->lcm = *add ? add_lcm : *remove ? remove_lcm : restart_lcm;
            a->dds = *add ? add_dds : *remove ? remove_dds : restart_dds;
            return *add       ? run_add(socket, *a)
                   : *remove  ? run_remove(socket, *a)
                   : *restart ? run_restart(socket, *a)
                              : run_list(socket, *a);
          }};
}

}  // namespace canemu::cli
