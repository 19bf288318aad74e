#include "canemu/daemon/control/control_dispatcher.hpp"
#include "canemu/daemon/world/timeline.hpp"

#include <cstring>
#include <memory>

#include <unistd.h>

#include <fmt/format.h>

#include "canemu/daemon/bridges/dds_bridge.hpp"
#include "canemu/daemon/bridges/lcm_bridge.hpp"
#include "canemu/daemon/world/status.hpp"
#include "config/capture_config_reader.hpp"

namespace canemu::daemon {

void ControlDispatcher::error(const Send& send, uint32_t request_id, ipc::ErrorCode code,
                              const std::string& text) {
  auto e = ipc::make_message<ipc::ErrorReply>(request_id);
  e.code = static_cast<uint32_t>(code);
  ipc::copy_name(e.message, text);
  send(&e, sizeof e, {});
}

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

template <class T>
T read_as(const uint8_t* data) {
  T m;
  std::memcpy(&m, data, sizeof m);
  return m;
}

template <class T>
void send_reply(const ControlDispatcher::Send& send, const T& reply) {
  send(&reply, sizeof reply, {});
}

}  // namespace

void ControlDispatcher::open_channel(Session& c, const ipc::OpenChannelRequest& m,
                                     const Send& send) {
  const uint32_t rid = m.header.request_id;
  const std::string bus_name = ipc::name_of(m.bus);
  const auto bus = sim_.bus_index(bus_name);
  if (!bus) {
    error(send, rid, ipc::ErrorCode::no_such_bus, fmt::format("no bus named \"{}\"", bus_name));
    return;
  }
  if (c.channels.size() >= kMaxChannelsPerClient) {
    error(send, rid, ipc::ErrorCode::no_resources,
          fmt::format("a client may open at most {} channels", kMaxChannelsPerClient));
    return;
  }
  std::string device = ipc::name_of(m.device);
  if (device.empty()) {
    device = sim_.devices().unique_name("eph");
  } else if (!valid_name(device)) {
    error(send, rid, ipc::ErrorCode::bad_argument, fmt::format("device names {}", kNameRule));
    return;
  } else if (sim_.devices().exists(device)) {
    error(send, rid, ipc::ErrorCode::name_in_use,
          fmt::format("a device named \"{}\" exists", device));
    return;
  }
  constexpr uint16_t kKnownFlags =
      ipc::kChannelListenOnly | ipc::kChannelReportTx | ipc::kChannelReportErrors;
  if (m.flags & ~kKnownFlags) {
    error(send, rid, ipc::ErrorCode::bad_argument, fmt::format("unknown flags {:#x}", m.flags));
    return;
  }
  if (m.rx_capacity > 65535 || m.tx_capacity > 65535) {
    error(send, rid, ipc::ErrorCode::bad_argument, "ring capacities are at most 65535");
    return;
  }
  if (m.restart_ms > 60'000) {
    error(send, rid, ipc::ErrorCode::bad_argument, "restart_ms is at most 60000");
    return;
  }
  const BusConfig& bc = sim_.bus_config(*bus);
  if (bc.kind == BusKind::lin) {
    error(send, rid, ipc::ErrorCode::bad_argument,
          fmt::format("bus \"{}\" is a LIN bus; CAN channels need a CAN bus", bus_name));
    return;
  }
  const uint32_t bitrate = m.bitrate != 0 ? m.bitrate : bc.bitrate;
  const uint32_t sample_point = m.sample_point != 0 ? m.sample_point : bc.sample_point;
  if (sample_point >= 1000) {
    error(send, rid, ipc::ErrorCode::bad_argument,
          fmt::format("sample point {} is not below 1000 per mille", sample_point));
    return;
  }
  const bool fd = bc.kind == BusKind::can_fd;
  const uint32_t data_bitrate = !fd ? 0
                                : m.data_bitrate != 0
                                    ? m.data_bitrate
                                    : (bc.data_bitrate != 0 ? bc.data_bitrate : bitrate);
  const auto timing = controller_timing(fd, bitrate, data_bitrate, sample_point);
  if (!timing) {
    error(send, rid, ipc::ErrorCode::bad_bit_timing,
          fd ? fmt::format("the CAN FD controller at 80 MHz cannot run at {} / {} bit/s", bitrate,
                           data_bitrate)
             : fmt::format("an SJA1000 at 16 MHz cannot run at {} bit/s", bitrate));
    return;
  }
  model::HostedNodeSettings settings = *timing;
  settings.listen_only = (m.flags & ipc::kChannelListenOnly) != 0;
  settings.restart_delay = model::SimDuration(int64_t{m.restart_ms} * 1'000'000);
  Channel::Options options;
  options.flags = m.flags;
  options.rx_capacity = m.rx_capacity != 0 ? m.rx_capacity : 1024;
  options.tx_capacity = m.tx_capacity != 0 ? m.tx_capacity : 256;
  // Ring memory is limited daemon-wide and per user, so that clients together cannot exhaust
  // the machine and one user cannot take every other user's share.
  const std::size_t ring_bytes =
      (std::size_t{options.rx_capacity} + options.tx_capacity) * sizeof(ipc::ChannelMessage);
  if (const std::string why = rings_.refusal(c.uid, ring_bytes); !why.empty()) {
    error(send, rid, ipc::ErrorCode::no_resources, why);
    return;
  }
  uint32_t id = c.next_channel++;
  while (id == 0 || c.channels.count(id) != 0) {  // after 2^32 opens, skip ids in use
    id = c.next_channel++;
  }
  model::HostedNode& node = sim_.spare_node(*bus);
  auto channel = Channel::open(id, device, *bus, node, settings, options);
  if (!channel) {
    error(send, rid, ipc::ErrorCode::no_resources, channel.error());
    return;
  }
  SessionChannel& sc = c.channels[id];
  sc.lease = sim_.add_ephemeral(device, *bus, node, c.pid);
  sc.channel = std::move(*channel);
  sc.budget = rings_.take(c.uid, ring_bytes);
  loop_.watch(*sc.channel);
  auto r = ipc::make_message<ipc::OpenChannelReply>(rid);
  r.channel = id;
  r.rx_capacity = sc.channel->rx_capacity();
  r.tx_capacity = sc.channel->tx_capacity();
  r.element_size = sizeof(ipc::ChannelMessage);
  ipc::copy_name(r.device, device);
  r.bitrate = bitrate;
  r.sample_point = static_cast<uint16_t>(settings.nominal.sample_point_permille());
  r.btr0 = settings.btr0;
  r.btr1 = settings.btr1;
  r.data_bitrate = data_bitrate;
  r.fd_capable = node.fd_capable() ? 1 : 0;
  const auto fds = sc.channel->client_fds();
  send(&r, sizeof r, fds);
}

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
    error(send, request_id, ipc::ErrorCode::bad_argument, added.error());
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

void ControlDispatcher::channel_status(Session& c, const ipc::ChannelStatusRequest& m,
                                       const Send& send) {
  auto it = c.channels.find(m.channel);
  if (it == c.channels.end()) {
    error(send, m.header.request_id, ipc::ErrorCode::no_such_channel,
          fmt::format("no channel {} on this connection", m.channel));
    return;
  }
  loop_.before_status();
  Channel& ch = *it->second.channel;
  model::HostedNode& node = ch.node();
  auto r = ipc::make_message<ipc::ChannelStatusReply>(m.header.request_id);
  r.channel = m.channel;
  const model::FaultConfinement& fc = node.controller().confinement();
  r.state = static_cast<uint8_t>(fc.state());
  r.tec = fc.tec();
  r.rec = fc.rec();
  r.transmitting = node.transmitting() ? 1 : 0;
  r.rx_fill = ch.rx_fill();
  const model::NodeStats& st = sim_.bus(ch.bus()).stats(node.node());
  r.frames_sent = st.frames_sent;
  r.frames_received = st.frames_received;
  r.errors = st.errors_as_transmitter.total() + st.errors_as_receiver.total();
  r.rx_lost = ch.stats().rx_lost;
  r.tx_rejected = ch.stats().tx_rejected;
  r.sim_time_ns = sim_.scheduler().now().ns();
  send_reply(send, r);
}

void ControlDispatcher::handle(Session& c, const uint8_t* data, std::size_t size,
                               const Send& send) {
  uint32_t request_id = 0;
  if (size >= sizeof(ipc::MsgHeader)) {
    ipc::MsgHeader h;
    std::memcpy(&h, data, sizeof h);
    request_id = h.request_id;
  }
  const ipc::ErrorCode check = ipc::check_message(data, size);
  if (check != ipc::ErrorCode::none) {
    error(send, request_id, check, fmt::format("rejected a {}-byte message", size));
    return;
  }
  ipc::MsgHeader h;
  std::memcpy(&h, data, sizeof h);
  const auto type = static_cast<ipc::MsgType>(h.type);
  if (!c.greeted && type != ipc::MsgType::hello) {
    error(send, request_id, ipc::ErrorCode::not_hello, "say hello first");
    return;
  }
  switch (type) {
    case ipc::MsgType::hello: {
      const auto m = read_as<ipc::Hello>(data);
      c.greeted = true;
      c.name = ipc::printable_name_of(m.client_name);  // shown in tables, JSON and logs
      auto r = ipc::make_message<ipc::HelloReply>(request_id);
      r.server_pid = static_cast<uint32_t>(::getpid());
      send_reply(send, r);
      return;
    }
    case ipc::MsgType::status_request: {
      loop_.before_status();
      const auto m = read_as<ipc::StatusRequest>(data);
      auto r = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>(request_id));
      fill_status(sim_, *r, m.first_bus, m.first_node);
      r->time_mode = static_cast<uint8_t>(time_.mode == TimeMode::realtime ? 0
                                          : time_.mode == TimeMode::scaled ? 1
                                                                           : 2);
      r->time_scale = time_.scale;
      r->client_count = loop_.client_count();
      r->ring_bytes = rings_.in_use();
      loop_.fill_pace(*r);
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::time_step_request: {
      const auto m = read_as<ipc::TimeStepRequest>(data);
      if (time_.mode != TimeMode::stepped) {
        error(send, request_id, ipc::ErrorCode::not_stepped,
              fmt::format("time runs {}; steps need --time stepped", to_string(time_)));
        return;
      }
      // At most a minute per request, so one client cannot hold the loop for long.
      if (m.step_ns <= 0 || m.step_ns > int64_t{60} * 1'000'000'000) {
        error(send, request_id, ipc::ErrorCode::bad_argument,
              fmt::format("step of {} ns is outside 1 ns .. 60 s", m.step_ns));
        return;
      }
      if (loop_.defer_step(m.step_ns, request_id)) {
        return;
      }
      loop_.before_step();
      auto r = ipc::make_message<ipc::TimeStepReply>(request_id);
      model::SimScheduler& s = sim_.scheduler();
      r.events_run = s.run_until(s.now() + model::SimDuration(m.step_ns));
      r.sim_time_ns = s.now().ns();
      loop_.after_step();
      send_reply(send, r);
      return;
    }
    case ipc::MsgType::open_channel_request:
      open_channel(c, read_as<ipc::OpenChannelRequest>(data), send);
      return;
    case ipc::MsgType::close_channel_request: {
      const auto m = read_as<ipc::CloseChannelRequest>(data);
      auto it = c.channels.find(m.channel);
      if (it == c.channels.end()) {
        error(send, request_id, ipc::ErrorCode::no_such_channel,
              fmt::format("no channel {} on this connection", m.channel));
        return;
      }
      loop_.unwatch(*it->second.channel);
      c.channels.erase(it);
      auto r = ipc::make_message<ipc::CloseChannelReply>(request_id);
      r.channel = m.channel;
      send_reply(send, r);
      return;
    }
    case ipc::MsgType::channel_status_request:
      channel_status(c, read_as<ipc::ChannelStatusRequest>(data), send);
      return;
    case ipc::MsgType::lin_node_request:
      send_reply(send, *answer_lin_nodes(sim_, read_as<ipc::LinNodeRequest>(data), request_id));
      return;
    case ipc::MsgType::timeline_request: {
      loop_.before_status();  // simulated time brought to now
      auto answer = answer_timeline(sim_, read_as<ipc::TimelineRequest>(data), request_id);
      if (auto* e = std::get_if<TimelineError>(&answer)) {
        error(send, request_id, e->code, e->text);
      } else if (auto* t = std::get_if<std::unique_ptr<ipc::TimelineReply>>(&answer)) {
        send_reply(send, **t);
      } else {
        send_reply(send, *std::get<std::unique_ptr<ipc::LoadHistoryReply>>(answer));
      }
      return;
    }
    case ipc::MsgType::device_list_request: {
      const auto m = read_as<ipc::DeviceListRequest>(data);
      auto r = std::make_unique<ipc::DeviceListReply>(
          ipc::make_message<ipc::DeviceListReply>(request_id));
      fill_device_list(sim_, *r, m.first);
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::recorder_list_request: {
      loop_.before_status();
      const auto m = read_as<ipc::RecorderListRequest>(data);
      auto r = std::make_unique<ipc::RecorderListReply>(
          ipc::make_message<ipc::RecorderListReply>(request_id));
      fill_recorder_list(sim_, *r, m.first);
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::bridge_add_request:
      add_bridge(read_as<ipc::BridgeAddRequest>(data), send, request_id);
      return;
    case ipc::MsgType::bridge_remove_request: {
      const auto& m = read_as<ipc::BridgeRemoveRequest>(data);
      const auto kind = bridge_kind(m.kind);
      const bool by_bus = kind != BridgeKind::socketcan;
      const std::string name = by_bus ? ipc::name_of(m.bus) : ipc::name_of(m.interface);
      const auto closing = [this](Bridge& b) {
        loop_.unwatch(b);
      };
      const bool removed =
          by_bus ? sim_.remove_bus_bridge(kind, name, closing) : sim_.remove_bridge(name, closing);
      if (!removed) {
        error(send, request_id, ipc::ErrorCode::bad_argument, no_bridge(kind, name));
        return;
      }
      send_reply(send, ipc::make_message<ipc::BridgeRemoveReply>(request_id));
      return;
    }
    case ipc::MsgType::bridge_restart_request: {
      const auto& m = read_as<ipc::BridgeRestartRequest>(data);
      const auto kind = bridge_kind(m.kind);
      const std::string name =
          kind != BridgeKind::socketcan ? ipc::name_of(m.bus) : ipc::name_of(m.interface);
      Bridge* bridge = sim_.find_bridge(kind, name);
      if (bridge == nullptr) {
        error(send, request_id, ipc::ErrorCode::bad_argument, no_bridge(kind, name));
        return;
      }
      if (auto problem = bridge->restart()) {
        error(send, request_id, ipc::ErrorCode::bad_argument, *problem);
        return;
      }
      send_reply(send, ipc::make_message<ipc::BridgeRestartReply>(request_id));
      return;
    }
    case ipc::MsgType::bridge_list_request: {
      const auto m = read_as<ipc::BridgeListRequest>(data);
      auto r = std::make_unique<ipc::BridgeListReply>(
          ipc::make_message<ipc::BridgeListReply>(request_id));
      fill_bridge_list(sim_, *r, m.first);
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::peer_list_request: {
      const auto m = read_as<ipc::PeerListRequest>(data);
      auto r =
          std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>(request_id));
      fill_peer_list(sim_, *r, m.first_peer, m.first_bus);
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::client_list_request: {
      const auto m = read_as<ipc::ClientListRequest>(data);
      auto r = std::make_unique<ipc::ClientListReply>(
          ipc::make_message<ipc::ClientListReply>(request_id));
      r->first = m.first;
      loop_.fill_clients(*r);
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::fault_load_request: {
      auto m = std::make_unique<ipc::FaultLoadRequest>(read_as<ipc::FaultLoadRequest>(data));
      auto r =
          std::make_unique<ipc::FaultLoadReply>(ipc::make_message<ipc::FaultLoadReply>(request_id));
      const std::string source = ipc::name_of(m->source).empty()
                                     ? std::string("<client>")
                                     : ipc::printable_name_of(m->source);
      std::vector<std::string> problems;
      if (m->length > ipc::kMaxScenarioText) {
        problems.push_back(fmt::format("{}: {} bytes of text claimed, at most {}", source,
                                       m->length, ipc::kMaxScenarioText));
      } else {
        auto scenario = parse_scenario(std::string_view(m->text, m->length), source);
        if (!scenario) {
          problems = scenario.error();
        } else if (auto applied = sim_.scenarios().apply(*scenario, sim_.scheduler().now(), c.uid);
                   !applied) {
          problems = applied.error();
        } else {
          r->applied = 1;
          r->faults = static_cast<uint32_t>(scenario->faults.size());
          ipc::copy_name(r->name, scenario->name);
        }
      }
      std::string text;
      for (const std::string& p : problems) {
        text += ipc::printable(p) + "\n";  // a problem may quote the client's text
      }
      ipc::copy_name(r->errors, text);
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::fault_list_request: {
      auto r =
          std::make_unique<ipc::FaultListReply>(ipc::make_message<ipc::FaultListReply>(request_id));
      const auto faults = sim_.scenarios().status();
      r->total = static_cast<uint16_t>(std::min<std::size_t>(faults.size(), UINT16_MAX));
      for (const ScenarioRunner::FaultStatus& f : faults) {
        if (r->count == ipc::kMaxFaults) {
          break;
        }
        ipc::FaultEntry& e = r->faults[r->count++];
        ipc::copy_name(e.scenario, f.scenario);
        ipc::copy_name(e.effect, to_string(f.effect));
        ipc::copy_name(e.target, f.target);
        e.line = f.line;
        e.state = static_cast<uint8_t>(f.state);
        e.has_until = f.until_ns ? 1 : 0;
        e.at_ns = f.at_ns;
        e.until_ns = f.until_ns.value_or(0);
        e.seen = f.seen;
        e.hits = f.hits;
        // The match, so that a rule that never hits shows why.
        const auto flag = [](const std::optional<bool>& v) {
          return static_cast<uint8_t>(!v   ? ipc::WireMatchFlag::any
                                      : *v ? ipc::WireMatchFlag::yes
                                           : ipc::WireMatchFlag::no);
        };
        using Frames = ScenarioRunner::FaultStatus::Frames;
        e.match = static_cast<uint8_t>(f.frames == Frames::can      ? ipc::WireFaultMatch::can
                                       : f.frames == Frames::lin    ? ipc::WireFaultMatch::lin
                                       : f.frames == Frames::babble ? ipc::WireFaultMatch::babble
                                                                    : ipc::WireFaultMatch::none);
        e.match_id = f.match.id;
        e.match_mask = f.match.mask;
        e.match_ext = flag(f.match.ext);
        e.match_rtr = flag(f.match.rtr);
        ipc::copy_name(e.match_from, f.match.from);
      }
      send_reply(send, *r);
      return;
    }
    case ipc::MsgType::fault_clear_request: {
      const auto m = read_as<ipc::FaultClearRequest>(data);
      const std::string name = ipc::name_of(m.scenario);
      // A client clears its own user's scenarios; an admin clears every one.
      const auto may = [&c](const ScenarioRunner::Owner& owner) {
        return c.admin || (owner && *owner == c.uid);
      };
      std::size_t refused = 0;
      const std::size_t cleared = sim_.scenarios().clear(name, may, &refused);
      if (cleared == 0 && refused > 0 && !name.empty()) {
        error(send, request_id, ipc::ErrorCode::permission_denied,
              fmt::format("scenario \"{}\" is not yours to clear: only the user who loaded it, "
                          "root, canemud's own user and members of [security] admin_groups may",
                          name));
        return;
      }
      if (cleared == 0 && !name.empty()) {
        error(send, request_id, ipc::ErrorCode::bad_argument,
              fmt::format("no scenario named \"{}\" to clear", name));
        return;
      }
      auto r = ipc::make_message<ipc::FaultClearReply>(request_id);
      r.cleared = static_cast<uint32_t>(cleared);
      r.refused = static_cast<uint32_t>(refused);
      send_reply(send, r);
      return;
    }
    case ipc::MsgType::subscribe_request: {
      const auto m = read_as<ipc::SubscribeRequest>(data);
      if (m.events & ~ipc::kEventDevices) {
        error(send, request_id, ipc::ErrorCode::bad_argument,
              fmt::format("unknown events {:#x}", m.events));
        return;
      }
      c.events = m.events;
      auto r = ipc::make_message<ipc::SubscribeReply>(request_id);
      r.events = c.events;
      send_reply(send, r);
      return;
    }
    case ipc::MsgType::vci_request:
      vci_.handle(c.vci, read_as<ipc::VciRequest>(data), send);
      return;
    case ipc::MsgType::xcan_request:
      xcan_.handle(c.xcan, read_as<ipc::XcanRequest>(data), send);
      return;
    case ipc::MsgType::slcan_request:
      slcan_.handle(c.slcan, read_as<ipc::SlcanRequest>(data), send);
      return;
    default:
      error(send, request_id, ipc::ErrorCode::unknown_type,
            fmt::format("message type {} is not a request", h.type));
      return;
  }
}

void ControlDispatcher::end_session(Session& session) {
  for (auto& [id, sc] : session.channels) {
    loop_.unwatch(*sc.channel);
  }
  session.channels.clear();
  vci_.close_all(session.vci);
  xcan_.close_all(session.xcan);
  slcan_.close_all(session.slcan);
}

}  // namespace canemu::daemon
