// canemu bridge add|list|remove: SocketCAN bridges while canemud runs (docs/socketcan.md).
#include <cstdio>
#include <memory>
#include <string>

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
  bool json = false;
};

int run_add(const std::string& socket, const BridgeArgs& a) {
  auto c = connect(socket, "canemu bridge");
  if (!c) {
    return fail(c.error().message);
  }
  auto req = ipc::make_message<ipc::BridgeAddRequest>();
  ipc::copy_name(req.bus, a.bus);
  ipc::copy_name(req.interface, a.interface);
  req.error_frames = a.error_frames ? 1 : 0;
  auto r = c->call<ipc::BridgeAddRequest, ipc::BridgeAddReply>(req);
  if (!r) {
    return fail(r.error().message);
  }
  std::printf("%s bridged to %s%s\n", a.bus.c_str(), a.interface.c_str(),
              a.error_frames ? " (with error frames)" : "");
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
  auto* bridge = app.add_subcommand("bridge", "SocketCAN bridges: add, list, remove");
  bridge->require_subcommand(1);
  auto a = std::make_shared<BridgeArgs>();
  auto* add = bridge->add_subcommand("add", "join BUS to the Linux CAN interface INTERFACE");
  add->add_option("BUS", a->bus, "bus name")->required();
  add->add_option("INTERFACE", a->interface, "vcan0, vxcan1, can0, ...")->required();
  add->add_flag("-e,--error-frames", a->error_frames,
                "the bridge node's errors and states as CAN_ERR_* frames on the interface");
  auto* list = bridge->add_subcommand("list", "bridges with their node's state and counts");
  list->add_flag("--json", a->json, "a JSON array instead of a table");
  auto* remove = bridge->add_subcommand("remove", "take the bridge off INTERFACE");
  remove->add_option("INTERFACE", a->interface, "the bridged interface")->required();
  return {
      bridge, [&socket, a, add, remove] {
        return *add ? run_add(socket, *a) : *remove ? run_remove(socket, *a) : run_list(socket, *a);
      }};
}

}  // namespace canemu::cli
