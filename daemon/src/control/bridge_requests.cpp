// Bridges added, removed and restarted at run time (`canemu bridge`).
#include <cstring>
#include <memory>

#include <fmt/format.h>

#include "canemu/daemon/bridges/dds_bridge.hpp"
#include "canemu/daemon/bridges/lcm_bridge.hpp"
#include "canemu/daemon/control/control_dispatcher.hpp"
#include "config/capture_config_reader.hpp"
#include "control/requests.hpp"

namespace canemu::daemon {

namespace {

// A request's bridge kind (an unknown one: SocketCAN, whose names it will not find).
BridgeKind bridge_kind(uint8_t kind) {
  return kind == ipc::kBridgeLcm   ? BridgeKind::lcm
         : kind == ipc::kBridgeDds ? BridgeKind::dds
                                   : BridgeKind::socketcan;
}

std::string no_bridge(BridgeKind kind, const std::string& name) {
  switch (kind) {
    case BridgeKind::lcm:
      return fmt::format("no LCM bridge on bus \"{}\"", name);
    case BridgeKind::dds:
      return fmt::format("no DDS bridge on bus \"{}\"", name);
    case BridgeKind::socketcan:
      break;
  }
  return fmt::format("no bridge on interface \"{}\"", name);
}

}  // namespace

void ControlDispatcher::add_bridge(const ipc::BridgeAddRequest& m, const Send& send,
                                   uint32_t request_id) {
  BridgeConfig b;
  b.bus = ipc::name_of(m.bus);
  b.restart_ms = m.restart_ms;
  if (m.restart_ms > ipc::kMaxBridgeRestartMs) {
    error(send, request_id, ipc::ErrorCode::bad_argument,
          fmt::format("restart_ms {} is outside 0..{}", m.restart_ms, ipc::kMaxBridgeRestartMs));
    return;
  }
  if (m.kind == ipc::kBridgeLcm) {
    b.kind = "lcm";
    b.url = ipc::name_of(m.url);
    b.channel_prefix = ipc::name_of(m.channel_prefix);
    if (b.url.empty()) {
      b.url = std::string(kDefaultLcmUrl);
    } else if (auto problem = lcm_url_problem(b.url)) {
      error(send, request_id, ipc::ErrorCode::bad_argument, *problem);
      return;
    }
    if (b.channel_prefix.empty()) {
      b.channel_prefix = default_lcm_prefix(b.bus);
    } else if (auto problem = lcm_prefix_problem(b.channel_prefix)) {
      error(send, request_id, ipc::ErrorCode::bad_argument, *problem);
      return;
    }
  } else if (m.kind == ipc::kBridgeDds) {
    b.kind = "dds";
    const std::string locator = ipc::name_of(m.url);
    const auto o =
        locator.empty() ? std::optional<DdsOptions>(DdsOptions{}) : parse_dds_locator(locator);
    if (!o) {
      error(send, request_id, ipc::ErrorCode::bad_argument,
            fmt::format("\"{}\" is not DOMAIN/PARTITION (a domain id 0..{}, a partition of up "
                        "to {} printable characters, +ros2 for ROS 2's topics too)",
                        locator, kMaxDdsDomain, kMaxDdsPartition));
      return;
    }
    b.domain = o->domain;
    b.partition = o->partition;
    b.ros2 = o->ros2;
    b.channel_prefix = ipc::name_of(m.channel_prefix);
    if (b.channel_prefix.empty()) {
      b.channel_prefix = default_dds_prefix(b.bus);
    } else if (auto problem = dds_prefix_problem(b.channel_prefix)) {
      error(send, request_id, ipc::ErrorCode::bad_argument, *problem);
      return;
    }
  } else if (m.kind == ipc::kBridgeSocketCan) {
    b.interface = ipc::name_of(m.interface);
    b.error_frames = m.error_frames != 0;
    if (auto problem = detail::interface_name_problem(b.interface)) {
      error(send, request_id, ipc::ErrorCode::bad_argument, *problem);
      return;
    }
  } else {
    error(send, request_id, ipc::ErrorCode::bad_argument,
          fmt::format("bridge kind {} is none of SocketCAN (0), LCM (1), DDS (2)", m.kind));
    return;
  }
  if (!sim_.bus_index(b.bus)) {
    error(send, request_id, ipc::ErrorCode::no_such_bus, fmt::format("no bus named \"{}\"", b.bus));
    return;
  }
  auto added = sim_.add_bridge(b);
  if (!added) {
    error(send, request_id, ipc::ErrorCode::bad_argument, added.error().what());
    return;
  }
  loop_.watch(**added);
  auto reply = ipc::make_message<ipc::BridgeAddReply>(request_id);
  if (m.kind == ipc::kBridgeSocketCan) {
    const Bridge& bridge = **added;
    const auto mtu = interface_mtu((*added)->transport().fd(), b.interface);
    if (const auto warning =
            mtu ? mtu_warning(b.interface, b.bus, bridge.options().fd, *mtu) : std::nullopt) {
      ipc::copy_name(reply.warning, *warning);
    }
  }
  send_reply(send, reply);
}

void ControlDispatcher::on_bridge_add(Session&, const uint8_t* data, uint32_t request_id,
                                      const Send& send) {
  add_bridge(read_as<ipc::BridgeAddRequest>(data), send, request_id);
}

void ControlDispatcher::on_bridge_remove(Session&, const uint8_t* data, uint32_t request_id,
                                         const Send& send) {
  const auto& m = read_as<ipc::BridgeRemoveRequest>(data);
  const auto kind = bridge_kind(m.kind);
  const bool by_bus = kind != BridgeKind::socketcan;
  const std::string name = by_bus ? ipc::name_of(m.bus) : ipc::name_of(m.interface);
  const auto closing = [this](Bridge& b) { loop_.unwatch(b); };
  const bool removed =
      by_bus ? sim_.remove_bus_bridge(kind, name, closing) : sim_.remove_bridge(name, closing);
  if (!removed) {
    error(send, request_id, ipc::ErrorCode::bad_argument, no_bridge(kind, name));
    return;
  }
  send_reply(send, ipc::make_message<ipc::BridgeRemoveReply>(request_id));
}

void ControlDispatcher::on_bridge_restart(Session&, const uint8_t* data, uint32_t request_id,
                                          const Send& send) {
  const auto& m = read_as<ipc::BridgeRestartRequest>(data);
  const auto kind = bridge_kind(m.kind);
  const std::string name =
      kind != BridgeKind::socketcan ? ipc::name_of(m.bus) : ipc::name_of(m.interface);
  Bridge* bridge = sim_.find_bridge(kind, name);
  if (bridge == nullptr) {
    error(send, request_id, ipc::ErrorCode::bad_argument, no_bridge(kind, name));
    return;
  }
  if (auto restarted = bridge->restart(); !restarted) {
    error(send, request_id, ipc::ErrorCode::bad_argument, restarted.error().what());
    return;
  }
  send_reply(send, ipc::make_message<ipc::BridgeRestartReply>(request_id));
}

}  // namespace canemu::daemon
