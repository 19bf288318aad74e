#include "canemu/daemon/bridges/bridge.hpp"

#include <linux/can.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/base/channel.hpp"
#include "canemu/daemon/base/log.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::daemon {

using namespace canemu::model;

Result<ipc::ChannelMessage> frame_message(const FrameFields& f) {
  if (f.id < 0 || f.id > (f.extended ? 0x1FFFFFFF : 0x7FF)) {
    return fail(Errc::bad_argument,
                fmt::format("id {} is no {} identifier", f.id, f.extended ? "29-bit" : "11-bit"));
  }
  if (f.dlc < 0 || f.dlc > 15) {
    return fail(Errc::bad_argument, fmt::format("dlc {} is outside 0..15", f.dlc));
  }
  const auto dlc = static_cast<uint8_t>(f.dlc);
  const std::size_t bytes = f.remote ? 0 : dlc_to_length(dlc, f.fd);
  if (f.len < 0 || static_cast<std::size_t>(f.len) != bytes) {
    return fail(Errc::bad_argument,
                fmt::format("len {} is not the {} bytes a{} frame of dlc {} has", f.len, bytes,
                            f.remote ? " remote"
                            : f.fd   ? " CAN FD"
                                     : " classic",
                            f.dlc));
  }
  ipc::ChannelMessage m;
  m.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::frame);
  m.id = static_cast<uint32_t>(f.id);
  m.dlc = dlc;
  m.flags = static_cast<uint8_t>((f.extended ? ipc::kMsgExtended : 0) |
                                 (f.remote ? ipc::kMsgRemote : 0) | (f.fd ? ipc::kMsgFd : 0) |
                                 (f.brs ? ipc::kMsgBrs : 0) | (f.esi ? ipc::kMsgEsi : 0));
  if (bytes != 0) {
    std::memcpy(m.data, f.data, bytes);
  }
  return m;
}

Result<> refused_family(int family) {
  const bool can = family == AF_CAN;
  const ipc::UniqueFd probe(
      ::socket(family, (can ? SOCK_RAW : SOCK_DGRAM) | SOCK_CLOEXEC, can ? CAN_RAW : 0));
  if (probe.valid() || errno != EAFNOSUPPORT) {
    return {};
  }
  return fail(Errc::unavailable, can ? "AF_CAN refused (no CAN in the kernel, or no drop-in "
                                       "socketcan.conf)"
                                     : "AF_INET refused (no drop-in ip.conf)");
}

std::unique_ptr<Bridge> Bridge::start(BridgeOptions options, std::size_t bus, HostedNode& node,
                                      const HostedNodeSettings& settings,
                                      std::unique_ptr<BridgeTransport> transport) {
  std::unique_ptr<Bridge> b(new Bridge(std::move(options), bus, node, std::move(transport)));
  Bridge* self = b.get();
  HostedNodeSettings s = settings;
  s.listen_only = false;
  node.start(s, self, [self] { return self->next_tx(); });
  return b;
}

Bridge::~Bridge() {
  if (restart_event_) {
    node_.scheduler().cancel(*restart_event_);
  }
  node_.stop();
}

Result<> Bridge::restart() {
  const FaultConfinement& fc = node_.controller().confinement();
  if (!fc.bus_off()) {
    return fail(Errc::bad_argument, transport_->name() + " is " +
                                        std::string(to_string(fc.state())) +
                                        ", not bus-off: nothing to restart");
  }
  if (fc.recovering()) {
    return fail(Errc::bad_argument, transport_->name() +
                                        " restarts already (waits for 128 x 11 recessive bits, " +
                                        std::to_string(fc.recovery_sequences_left()) + " left)");
  }
  if (restart_event_) {
    node_.scheduler().cancel(*restart_event_);
    restart_event_.reset();
  }
  node_.restart();
  ++stats_.restarts;
  if (options_.error_frames) {
    count(transport_->restarted(node_.now(), fc.tec(), fc.rec()), stats_.error_frames);
  }
  return {};
}

void Bridge::restart_after_bus_off() {
  restart_event_.reset();
  restart();  // nothing to do if it was restarted by hand in the meantime
}

void Bridge::kick() {
  transport_->receive(*this);
  node_.kick();
}

void Bridge::reject(BridgeReject why, const std::string& detail, uint64_t n) {
  stats_.received += n;
  stats_.rejected += n;
  rejections_.add(static_cast<std::size_t>(why), detail, n);
}

void Bridge::offer(const ipc::ChannelMessage* m) {
  if (m == nullptr) {
    reject(BridgeReject::not_a_frame, "rejected a message that is no frame");
    return;
  }
  const auto frame = to_tx_frame(*m);
  if (!frame) {
    reject(BridgeReject::bad_fields, fmt::format("rejected a frame with id 0x{:X}, dlc {}: {}",
                                                 m->id, m->dlc, frame.error().message));
    return;
  }
  if (frame->frame.fd() && !options_.fd) {
    reject(BridgeReject::fd_on_classic,
           fmt::format("rejected a CAN FD frame (id 0x{:X}, dlc {}): {} is a classic CAN bus",
                       frame->frame.id(), frame->frame.dlc(), options_.bus));
    return;
  }
  ++stats_.received;
  if (queue_.size() >= options_.queue_frames) {
    ++stats_.queue_dropped;
    return;
  }
  queue_.push_back(*frame);
}

std::optional<TxFrame> Bridge::next_tx() {
  if (queue_.empty()) {
    return std::nullopt;
  }
  TxFrame f = queue_.front();
  queue_.pop_front();
  return f;
}

void Bridge::count(Delivery d, uint64_t& counter) {
  if (d == Delivery::sent) {
    ++counter;
  } else if (d == Delivery::refused) {
    ++stats_.to_interface_dropped;
  }
}

void Bridge::frame_received(SimTime at, const Frame& frame, bool own) {
  if (!own) {
    count(transport_->frame(at, frame, false), stats_.to_interface);
  }
}

void Bridge::frame_transmitted(SimTime at, const Frame& frame) {
  ++stats_.from_interface;
  if (transport_->carries_own_frames()) {
    count(transport_->frame(at, frame, true), stats_.to_interface);
  }
}

void Bridge::transmission_dropped(SimTime, const Frame&) {
  ++stats_.tx_failed;
}

void Bridge::bus_error(const BusErrorEvent& event) {
  if (options_.error_frames) {
    count(transport_->error(event, node_.controller().confinement().state()), stats_.error_frames);
  }
}

void Bridge::state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) {
  if (options_.error_frames) {
    count(transport_->state(at, state, tec, rec), stats_.error_frames);
  }
  if (state == ErrorState::bus_off && options_.restart_ms != 0 && !restart_event_) {
    restart_event_ =
        node_.scheduler().schedule_at(at + SimDuration(int64_t{options_.restart_ms} * 1'000'000),
                                      [this](SimTime) { restart_after_bus_off(); });
  }
}

}  // namespace canemu::daemon
