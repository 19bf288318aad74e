// Ephemeral channels: a node of its own on a bus for a client, with its rings.
#include <cstring>
#include <memory>

#include <fmt/format.h>

#include "canemu/daemon/control/control_dispatcher.hpp"
#include "control/requests.hpp"

namespace canemu::daemon {

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
  const bool fd = bc.kind == BusKind::can_fd;
  const NodeRates rates = node_rates(bc, fd, {m.bitrate, m.data_bitrate, m.sample_point});
  const uint32_t bitrate = rates.bitrate;
  const uint32_t data_bitrate = rates.data_bitrate;
  const uint32_t sample_point = rates.sample_point;
  if (sample_point >= 1000) {
    error(send, rid, ipc::ErrorCode::bad_argument,
          fmt::format("sample point {} is not below 1000 per mille", sample_point));
    return;
  }
  const auto timing = node_timing(fd, rates);
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
    error(send, rid, ipc::ErrorCode::no_resources, channel.error().what());
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

void ControlDispatcher::on_open_channel(Session& c, const uint8_t* data, uint32_t,
                                        const Send& send) {
  open_channel(c, read_as<ipc::OpenChannelRequest>(data), send);
}

void ControlDispatcher::on_close_channel(Session& c, const uint8_t* data, uint32_t request_id,
                                         const Send& send) {
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
}

void ControlDispatcher::on_channel_status(Session& c, const uint8_t* data, uint32_t,
                                          const Send& send) {
  channel_status(c, read_as<ipc::ChannelStatusRequest>(data), send);
}

}  // namespace canemu::daemon
