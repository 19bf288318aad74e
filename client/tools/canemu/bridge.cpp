// canemu bridge add|list|restart|remove: SocketCAN bridges while canemud runs
// (docs/socketcan.md).
#include <cstdio>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
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
};

int run_add(const std::string& socket, const BridgeArgs& a) {
  if (a.restart_ms < 0 || a.restart_ms > ipc::kMaxBridgeRestartMs) {
    return fail(fmt::format("--restart-ms {} is outside 0..{} (ms after bus-off; 0: stay bus-off)",
                            a.restart_ms, ipc::kMaxBridgeRestartMs));
  }
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto req = ipc::make_message<ipc::BridgeAddRequest>();
  ipc::copy_name(req.bus, a.bus);
  ipc::copy_name(req.interface, a.interface);
  req.error_frames = a.error_frames ? 1 : 0;
  req.restart_ms = static_cast<uint32_t>(a.restart_ms);
  auto r = c->call<ipc::BridgeAddRequest, ipc::BridgeAddReply>(req);
  if (!r) {
    return fail(r.error().message);
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
  return 0;
}

int run_restart(const std::string& socket, const BridgeArgs& a) {
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto req = ipc::make_message<ipc::BridgeRestartRequest>();
  ipc::copy_name(req.interface, a.interface);
  auto r = c->call<ipc::BridgeRestartRequest, ipc::BridgeRestartReply>(req);
  if (!r) {
    return fail(r.error().message);
  }
  std::printf("bridge on %s restarted (error-active after 128 x 11 recessive bits)\n",
              a.interface.c_str());
  return 0;
}

int run_remove(const std::string& socket, const BridgeArgs& a) {
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto req = ipc::make_message<ipc::BridgeRemoveRequest>();
  ipc::copy_name(req.interface, a.interface);
  auto r = c->call<ipc::BridgeRemoveRequest, ipc::BridgeRemoveReply>(req);
  if (!r) {
    return fail(r.error().message);
  }
  std::printf("bridge on %s removed\n", a.interface.c_str());
  return 0;
}

int run_list(const std::string& socket, const BridgeArgs& a) {
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = c->call<ipc::BridgeListRequest, ipc::BridgeListReply>(
      ipc::make_message<ipc::BridgeListRequest>());
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
  auto* bridge = app.add_subcommand("bridge", "SocketCAN bridges: add, list, restart, remove");
  bridge->require_subcommand(1);
  auto a = std::make_shared<BridgeArgs>();
  auto* add = bridge->add_subcommand("add", "join BUS to the Linux CAN interface INTERFACE");
  add->add_option("BUS", a->bus, "bus name")->required();
  add->add_option("INTERFACE", a->interface, "vcan0, vxcan1, can0, ...")->required();
  add->add_flag("-e,--error-frames", a->error_frames,
                "the bridge node's errors and states as CAN_ERR_* frames on the interface");
  add->add_option("--restart-ms", a->restart_ms,
                  "restart the bridge's node this many ms after bus-off (0..60000; 0, the "
                  "default: it stays bus-off, as restart-ms 0 of a kernel CAN interface)");
  auto* restart =
      bridge->add_subcommand("restart", "restart the bus-off node of the bridge on INTERFACE");
  restart->add_option("INTERFACE", a->interface, "the bridged interface")->required();
  auto* list = bridge->add_subcommand("list", "bridges with their node's state and counts");
  list->add_flag("--json", a->json, "a JSON array instead of a table");
  auto* remove = bridge->add_subcommand("remove", "take the bridge off INTERFACE");
  remove->add_option("INTERFACE", a->interface, "the bridged interface")->required();
  return {bridge, [&socket, a, add, remove, restart] {
            return *add       ? run_add(socket, *a)
                   : *remove  ? run_remove(socket, *a)
                   : *restart ? run_restart(socket, *a)
                              : run_list(socket, *a);
          }};
}

}  // namespace canemu::cli
