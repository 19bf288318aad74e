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

void SocketCanTransport::receive(Bridge& bridge) {
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
        bridge.counters().kernel_dropped = dropped;
      }
    }
    // Anything but a frame (a short read, an error frame, a bad length or identifier) is
    // counted and skipped by the bridge.
    const auto f = ipc::socketcan::from_struct(buffer, static_cast<std::size_t>(n));
    std::string error;
    const auto m = f ? ipc::socketcan::to_message(*f, error) : std::nullopt;
    bridge.offer(m ? &*m : nullptr);
  }
}

Delivery SocketCanTransport::write_out(const ipc::ChannelMessage& m) {
  if (const auto f = ipc::socketcan::from_message(m)) {
    return write_frame(*f);
  }
  return Delivery::none;
}

Delivery SocketCanTransport::write_frame(const ipc::socketcan::Frame& f) {
  const std::vector<uint8_t> bytes = ipc::socketcan::to_struct(f);
  const ssize_t n = ::send(port_.get(), bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  return n == static_cast<ssize_t>(bytes.size()) ? Delivery::sent : Delivery::refused;
}

Delivery SocketCanTransport::frame(SimTime at, const Frame& frame, bool) {
  return write_out(to_message(at, frame, ipc::ChannelMessageKind::frame));
}

Delivery SocketCanTransport::error(const BusErrorEvent& event, ErrorState state) {
  return write_out(to_error_message(event, state));
}

Delivery SocketCanTransport::state(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) {
  return write_out(to_state_message(at, state, tec, rec));
}

Delivery SocketCanTransport::restarted(SimTime, uint16_t, uint16_t) {
  return write_frame(ipc::socketcan::restarted_frame());
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
    const int error = errno;
    const auto refused = error == EAFNOSUPPORT ? refused_family(AF_CAN) : std::nullopt;
    return tl::unexpected(interface + ": " +
                          refused.value_or(std::string("socket(PF_CAN): ") + std::strerror(error)));
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
