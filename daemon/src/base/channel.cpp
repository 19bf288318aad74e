#include "canemu/daemon/base/channel.hpp"

#include <cstring>

#include <unistd.h>

#include <fmt/format.h>

#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"

namespace canemu::daemon {

using namespace canemu::model;

ipc::ChannelMessage to_message(SimTime at, const Frame& frame, ipc::ChannelMessageKind kind,
                               bool own) {
  ipc::ChannelMessage m;
  m.timestamp_ns = at.ns();
  m.kind = static_cast<uint8_t>(kind);
  m.id = frame.id();
  m.dlc = frame.dlc();
  m.flags = static_cast<uint8_t>((frame.extended() ? ipc::kMsgExtended : 0) |
                                 (frame.remote() ? ipc::kMsgRemote : 0) |
                                 (frame.fd() ? ipc::kMsgFd : 0) | (frame.brs() ? ipc::kMsgBrs : 0) |
                                 (frame.esi() ? ipc::kMsgEsi : 0) | (own ? ipc::kMsgOwn : 0));
  // All 64 bytes, zero past the length: a copy of fixed size, no call.
  static_assert(sizeof m.data == kMaxFdLength);
  std::memcpy(m.data, frame.padded_data().data(), sizeof m.data);
  return m;
}

model::Result<TxFrame> to_tx_frame(const ipc::ChannelMessage& m) {
  if (m.kind != static_cast<uint8_t>(ipc::ChannelMessageKind::frame)) {
    return model_error(ModelErrc::invalid_flags,
                       fmt::format("message kind {} is not a frame", m.kind));
  }
  FrameSpec spec;
  spec.id = m.id;
  spec.extended = (m.flags & ipc::kMsgExtended) != 0;
  spec.remote = (m.flags & ipc::kMsgRemote) != 0;
  spec.fd = (m.flags & ipc::kMsgFd) != 0;
  spec.brs = (m.flags & ipc::kMsgBrs) != 0;
  spec.esi = (m.flags & ipc::kMsgEsi) != 0;
  if (m.dlc > kMaxDlc) {
    return model_error(ModelErrc::invalid_dlc, fmt::format("DLC {} is above 15", m.dlc));
  }
  spec.dlc = m.dlc;
  spec.data = std::span<const uint8_t>(m.data, spec.remote ? 0 : dlc_to_length(m.dlc, spec.fd));
  auto frame = Frame::create(spec);
  if (!frame) {
    return tl::unexpected(frame.error());
  }
  return TxFrame{*frame, (m.flags & ipc::kMsgSingleShot) != 0,
                 (m.flags & ipc::kMsgSelfReception) != 0};
}

Result<std::unique_ptr<Channel>> Channel::open(uint32_t id, std::string device, std::size_t bus,
                                               HostedNode& node, const HostedNodeSettings& settings,
                                               const Options& options) {
  auto rings = ipc::RingPair::create(options.rx_capacity, options.tx_capacity,
                                     sizeof(ipc::ChannelMessage), "canemu", device);
  if (!rings) {
    return fail(Errc::io, rings.error().message);
  }
  std::unique_ptr<Channel> c(
      new Channel(id, std::move(device), bus, node, options.flags, std::move(*rings)));
  Channel* self = c.get();
  node.start(settings, self, [self] { return self->next_tx(); });
  return c;
}

Channel::Channel(uint32_t id, std::string device, std::size_t bus, HostedNode& node, uint16_t flags,
                 ipc::RingPair rings)
    : id_(id),
      device_(std::move(device)),
      bus_(bus),
      node_(node),
      flags_(flags),
      rings_(std::move(rings)),
      rx_(rings_.rx().writer()),
      tx_(rings_.tx().reader()) {}

Channel::~Channel() {
  node_.stop();
}

void Channel::kick() {
  // Always drained: a client's write can land after the daemon disarmed (or a client can write
  // the doorbell on its own); a doorbell left readable would wake the loop at once, forever.
  tx_.disarm();
  armed_ = false;
  rejects_left_ = kMaxRejectsPerKick;
  node_.kick();
}

std::optional<TxFrame> Channel::next_tx() {
  ipc::ChannelMessage m;
  while (true) {
    const ipc::RingStatus status = tx_.get(&m);
    if (status == ipc::RingStatus::ok) {
      if (armed_) {
        tx_.disarm();  // busy again: the client's puts need not write the eventfd
        armed_ = false;
      }
      auto frame = to_tx_frame(m);
      // An SJA1000 node sends classic frames only.
      if (frame && (!frame->frame.fd() || node_.fd_capable())) {
        return *frame;
      }
      if (!reject(m)) {
        return std::nullopt;
      }
      continue;
    }
    if (status != ipc::RingStatus::empty || armed_ || !arming_) {
      return std::nullopt;  // corrupted (broken() tells the server), asleep already, or stepped
    }
    // Idle with an empty ring: sleep on the doorbell, unless a frame came in meanwhile.
    if (tx_.arm_unless_filled()) {
      armed_ = true;
      return std::nullopt;
    }
  }
}

bool Channel::reject(ipc::ChannelMessage& m) {
  // Not a frame the node can send: counted, reported when the client asked for transmit
  // reports, skipped.
  ++stats_.tx_rejected;
  if (flags_ & ipc::kChannelReportTx) {
    m.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::tx_dropped);
    m.timestamp_ns = node_.now().ns();
    deliver(m);
  }
  if (rejects_left_ == 0 || --rejects_left_ == 0) {
    // A client feeding nothing but junk gets a turn per loop iteration, not the loop: ring its
    // own doorbell so the next iteration goes on from here.
    const uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(doorbell_fd(), &one, sizeof one);
    return false;
  }
  return true;
}

void Channel::deliver(ipc::ChannelMessage& m) {
  m.lost_before = lost_pending_;
  switch (rx_.put(&m)) {
    case ipc::RingStatus::ok:
      lost_pending_ = 0;
      return;
    case ipc::RingStatus::full:
      // Never silent: counted here, in the ring header, and on the next message that fits.
      ++stats_.rx_lost;
      ++lost_pending_;
      rx_.count_overrun();
      return;
    default:
      return;  // corrupted: broken() tells the server
  }
}

void Channel::frame_received(SimTime at, const Frame& frame, bool own) {
  ipc::ChannelMessage m = to_message(at, frame, ipc::ChannelMessageKind::frame, own);
  deliver(m);
}

void Channel::frame_transmitted(SimTime at, const Frame& frame) {
  if (flags_ & ipc::kChannelReportTx) {
    ipc::ChannelMessage m = to_message(at, frame, ipc::ChannelMessageKind::tx_done);
    deliver(m);
  }
}

void Channel::transmission_dropped(SimTime at, const Frame& frame) {
  if (flags_ & ipc::kChannelReportTx) {
    ipc::ChannelMessage m = to_message(at, frame, ipc::ChannelMessageKind::tx_dropped);
    deliver(m);
  }
}

void Channel::bus_error(const BusErrorEvent& e) {
  if (flags_ & ipc::kChannelReportErrors) {
    ipc::ChannelMessage m = to_error_message(e, node_.controller().confinement().state());
    deliver(m);
  }
}

void Channel::state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) {
  if (flags_ & ipc::kChannelReportErrors) {
    ipc::ChannelMessage m = to_state_message(at, state, tec, rec);
    deliver(m);
  }
}

ipc::ChannelMessage to_error_message(const BusErrorEvent& e, ErrorState state) {
  ipc::ChannelMessage m;
  m.timestamp_ns = e.at.ns();
  m.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::bus_error);
  m.error_type = static_cast<uint8_t>(e.type);
  m.error_role = static_cast<uint8_t>(e.role);
  m.error_bit = e.bit;
  m.error_location = sja1000::ecc_segment(e, e.destuffed_bit, e.extended_frame);
  m.tec = e.tec;
  m.rec = e.rec;
  m.state = static_cast<uint8_t>(state);
  return m;
}

ipc::ChannelMessage to_state_message(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) {
  ipc::ChannelMessage m;
  m.timestamp_ns = at.ns();
  m.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::state);
  m.state = static_cast<uint8_t>(state);
  m.tec = tec;
  m.rec = rec;
  return m;
}

}  // namespace canemu::daemon
