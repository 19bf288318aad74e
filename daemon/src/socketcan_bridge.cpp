#include "canemu/daemon/socketcan_bridge.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "canemu/daemon/channel.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::daemon {

using namespace canemu::model;

std::unique_ptr<SocketCanBridge> SocketCanBridge::start(BridgeOptions options, std::size_t bus,
                                                        HostedNode& node,
                                                        const HostedNodeSettings& settings,
                                                        ipc::UniqueFd port) {
  std::unique_ptr<SocketCanBridge> b(
      new SocketCanBridge(std::move(options), bus, node, std::move(port)));
  SocketCanBridge* self = b.get();
  HostedNodeSettings s = settings;
  s.listen_only = false;
  node.start(s, self, [self] { return self->next_tx(); });
  return b;
}

SocketCanBridge::~SocketCanBridge() {
  if (restart_event_) {
    node_.scheduler().cancel(*restart_event_);
  }
  node_.stop();
}

std::optional<std::string> SocketCanBridge::restart() {
  const FaultConfinement& fc = node_.controller().confinement();
  if (!fc.bus_off()) {
    return "bridge on " + options_.interface + " is " + std::string(to_string(fc.state())) +
           ", not bus-off: nothing to restart";
  }
  if (fc.recovering()) {
    return "bridge on " + options_.interface +
           " restarts already (waits for 128 x 11 recessive bits, " +
           std::to_string(fc.recovery_sequences_left()) + " left)";
  }
  if (restart_event_) {
    node_.scheduler().cancel(*restart_event_);
    restart_event_.reset();
  }
  node_.restart();
  ++stats_.restarts;
  if (options_.error_frames) {
    write_frame(ipc::socketcan::restarted_frame(), stats_.error_frames);
  }
  return std::nullopt;
}

void SocketCanBridge::restart_after_bus_off() {
  restart_event_.reset();
  restart();  // nothing to do if it was restarted by hand in the meantime
}

void SocketCanBridge::kick() {
  uint8_t buffer[ipc::socketcan::kCanFdMtu + 1];
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(uint32_t))];
  for (int i = 0; i < kMaxReadsPerKick; ++i) {
    iovec iov{buffer, sizeof buffer};
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(port_.get(), &msg, MSG_DONTWAIT);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      break;  // nothing more (EAGAIN), or the interface went away: nothing to read
    }
    // SO_RXQ_OVFL: the kernel's count of frames it dropped for this socket, so far.
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
        uint32_t dropped = 0;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
        stats_.kernel_dropped = dropped;
      }
    }
    accept(buffer, static_cast<std::size_t>(n));
  }
  node_.kick();
}

void SocketCanBridge::accept(const uint8_t* bytes, std::size_t size) {
  // Anything but a frame of this bus (a short read, an error frame, a bad length or
  // identifier, CAN FD on a classic bus) is counted and skipped.
  const auto f = ipc::socketcan::from_struct(bytes, size);
  std::string error;
  const auto m = f ? ipc::socketcan::to_message(*f, error) : std::nullopt;
  const auto frame = m ? to_tx_frame(*m) : Result<TxFrame>(tl::unexpected(ModelError{}));
  if (!frame || (frame->frame.fd() && !options_.fd)) {
    ++stats_.rejected;
    return;
  }
  if (queue_.size() >= options_.queue_frames) {
    ++stats_.queue_dropped;
    return;
  }
  queue_.push_back(*frame);
}

std::optional<TxFrame> SocketCanBridge::next_tx() {
  if (queue_.empty()) {
    return std::nullopt;
  }
  TxFrame f = queue_.front();
  queue_.pop_front();
  return f;
}

void SocketCanBridge::write_out(const ipc::ChannelMessage& m, uint64_t& counter) {
  if (const auto f = ipc::socketcan::from_message(m)) {
    write_frame(*f, counter);
  }
}

void SocketCanBridge::write_frame(const ipc::socketcan::Frame& f, uint64_t& counter) {
  const std::vector<uint8_t> bytes = ipc::socketcan::to_struct(f);
  const ssize_t n = ::send(port_.get(), bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n == static_cast<ssize_t>(bytes.size())) {
    ++counter;
  } else {
    ++stats_.to_interface_dropped;
  }
}

void SocketCanBridge::frame_received(SimTime at, const Frame& frame, bool own) {
  if (!own) {
    write_out(to_message(at, frame, ipc::ChannelMessageKind::frame), stats_.to_interface);
  }
}

void SocketCanBridge::frame_transmitted(SimTime, const Frame&) {
  ++stats_.from_interface;
}

void SocketCanBridge::transmission_dropped(SimTime, const Frame&) {
  ++stats_.tx_failed;
}

void SocketCanBridge::bus_error(const BusErrorEvent& event) {
  if (options_.error_frames) {
    write_out(to_error_message(event, node_.controller().confinement().state()),
              stats_.error_frames);
  }
}

void SocketCanBridge::state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) {
  if (options_.error_frames) {
    write_out(to_state_message(at, state, tec, rec), stats_.error_frames);
  }
  if (state == ErrorState::bus_off && options_.restart_ms != 0 && !restart_event_) {
    restart_event_ =
        node_.scheduler().schedule_at(at + SimDuration(int64_t{options_.restart_ms} * 1'000'000),
                                      [this](SimTime) { restart_after_bus_off(); });
  }
}

tl::expected<ipc::UniqueFd, std::string> open_can_raw(const std::string& interface, bool fd) {
  const auto failed = [&](const char* call) {
    return tl::unexpected(interface + ": " + call + ": " + std::strerror(errno));
  };
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    return tl::unexpected("\"" + interface + "\" is not an interface name (1 to " +
                          std::to_string(IFNAMSIZ - 1) + " characters)");
  }
  ipc::UniqueFd s(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!s.valid()) {
    return failed("socket(PF_CAN)");
  }
  const unsigned index = ::if_nametoindex(interface.c_str());
  if (index == 0) {
    return failed("if_nametoindex");
  }
  const int on = 1;
  if (fd && ::setsockopt(s.get(), SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0) {
    return failed("setsockopt CAN_RAW_FD_FRAMES");
  }
  if (::setsockopt(s.get(), SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) != 0) {
    return failed("setsockopt SO_RXQ_OVFL");
  }
  // Room for bursts (cangen -g 0) while the loop is busy: 4 MiB where the daemon may raise the
  // limit (CAP_NET_ADMIN), else net.core.rmem_max. Drops beyond it are counted (SO_RXQ_OVFL).
  const int bytes = 4 << 20;
  if (::setsockopt(s.get(), SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof bytes) != 0) {
    ::setsockopt(s.get(), SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(s.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    return failed("bind");
  }
  return s;
}

}  // namespace canemu::daemon
