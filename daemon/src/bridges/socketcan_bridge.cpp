#include "canemu/daemon/bridges/socketcan_bridge.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/base/channel.hpp"
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
    // Anything but a frame this bus carries (a short read, an error frame, CAN FD on a classic
    // bus, a bad length) is counted as rejected and logged with the reason by the bridge.
    const auto m = frame_from_interface(buffer, static_cast<std::size_t>(n), bridge.options().fd);
    if (m) {
      bridge.offer(&*m);
    } else {
      bridge.reject(m.error().why, "rejected " + m.error().detail);
    }
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

tl::expected<ipc::ChannelMessage, InterfaceReject> frame_from_interface(const uint8_t* bytes,
                                                                        std::size_t size,
                                                                        bool fd_bus) {
  namespace sc = ipc::socketcan;
  const auto f = sc::from_struct(bytes, size);
  if (!f) {
    return tl::unexpected(InterfaceReject{
        BridgeReject::not_a_frame,
        fmt::format("a read of {} bytes, neither a struct can_frame ({}) nor a canfd_frame ({})",
                    size, sc::kCanMtu, sc::kCanFdMtu)});
  }
  const uint8_t len = bytes[4];  // as the program wrote it (from_struct keeps what fits)
  const std::string text = sc::candump_text(*f);
  if (f->can_id & sc::kErrFlag) {
    return tl::unexpected(InterfaceReject{
        BridgeReject::error_frame,
        "the error frame " + text +
            " (an error frame reports what a controller saw; it is no frame to send on a bus)"});
  }
  if (f->fd && !fd_bus) {
    return tl::unexpected(
        InterfaceReject{BridgeReject::fd_on_classic,
                        "the CAN FD frame " + text + " (the bus is a classic CAN bus)"});
  }
  if (len > (f->fd ? 64 : 8)) {
    return tl::unexpected(
        InterfaceReject{BridgeReject::bad_fields,
                        fmt::format("{} (its length {} is above {})", text, len, f->fd ? 64 : 8)});
  }
  std::string error;
  auto m = sc::to_message(*f, error);
  if (!m) {
    return tl::unexpected(InterfaceReject{BridgeReject::bad_fields, text + " (" + error + ")"});
  }
  return *m;
}

std::optional<std::string> mtu_warning(const std::string& interface, const std::string& bus,
                                       bool fd_bus, int mtu) {
  if (!fd_bus || mtu == static_cast<int>(ipc::socketcan::kCanFdMtu)) {
    return std::nullopt;
  }
  return fmt::format(
      "{} has MTU {}, not {} (CAN FD): the CAN FD frames of {} cannot be written to it (counted "
      "as IF-DROP) and programs cannot send CAN FD frames on it; classic frames pass. For CAN FD: "
      "ip link set {} down; ip link set {} mtu 72 up",
      interface, mtu, ipc::socketcan::kCanFdMtu, bus, interface, interface);
}

std::optional<int> interface_mtu(int fd, const std::string& interface) {
  ifreq ifr{};
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    return std::nullopt;
  }
  std::memcpy(ifr.ifr_name, interface.data(), interface.size());
  if (::ioctl(fd, SIOCGIFMTU, &ifr) != 0) {
    return std::nullopt;
  }
  return ifr.ifr_mtu;
}

Result<ipc::UniqueFd> open_can_raw(const std::string& interface) {
  const auto failed = [&](const char* call) {
    return fail(Errc::io, interface + ": " + call + ": " + std::strerror(errno));
  };
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    return fail(Errc::bad_argument, "\"" + interface + "\" is not an interface name (1 to " +
                                        std::to_string(IFNAMSIZ - 1) + " characters)");
  }
  ipc::UniqueFd s(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!s.valid()) {
    const int error = errno;
    if (auto family = error == EAFNOSUPPORT ? refused_family(AF_CAN) : Result<>(); !family) {
      return fail(Errc::unavailable, interface + ": " + family.error().text);
    }
    return fail(Errc::io, interface + ": socket(PF_CAN): " + std::strerror(error));
  }
  const unsigned index = ::if_nametoindex(interface.c_str());
  if (index == 0) {
    return fail(errno == ENODEV ? Errc::not_found : Errc::io,
                interface + ": if_nametoindex: " + std::strerror(errno));
  }
  // CAN FD frames and every error class arrive whatever the bus, so that what a classic bus
  // cannot carry is read, counted as rejected and logged rather than filtered out unseen by the
  // kernel (a socket without CAN_RAW_FD_FRAMES does not receive FD frames; one without an
  // error mask no error frames).
  const int on = 1;
  if (::setsockopt(s.get(), SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0) {
    return failed("setsockopt CAN_RAW_FD_FRAMES");
  }
  const can_err_mask_t every_error = CAN_ERR_MASK;
  if (::setsockopt(s.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &every_error, sizeof every_error) !=
      0) {
    return failed("setsockopt CAN_RAW_ERR_FILTER");
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
