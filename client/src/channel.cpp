#include "canemu/client/channel.hpp"

#include <sched.h>

#include <fmt/format.h>

#include "canemu/ipc/clock.hpp"

namespace canemu::client {

namespace {

// Calls `attempt` until it succeeds or `spin_ns` has passed (the clock is read every 64 tries).
template <class Attempt>
bool spin(int64_t spin_ns, Attempt attempt) {
  if (spin_ns <= 0) {
    return false;
  }
  const int64_t until = ipc::monotonic_ns() + spin_ns;
  for (uint32_t k = 1;; ++k) {
    if (attempt()) {
      return true;
    }
    if (k % 64 == 0) {
      if (ipc::monotonic_ns() >= until) {
        return false;
      }
      ::sched_yield();
    }
  }
}

}  // namespace

Result<Channel> Channel::open(Connection& connection, const ChannelOptions& o) {
  auto m = ipc::make_message<ipc::OpenChannelRequest>();
  ipc::copy_name(m.bus, o.bus);
  ipc::copy_name(m.device, o.device);
  m.bitrate = o.bitrate;
  m.sample_point = o.sample_point;
  m.flags = o.flags;
  m.rx_capacity = o.rx_capacity;
  m.tx_capacity = o.tx_capacity;
  m.restart_ms = o.restart_ms;
  m.data_bitrate = o.data_bitrate;
  auto reply = connection.call<ipc::OpenChannelRequest, ipc::OpenChannelReply>(m);
  if (!reply) {
    return tl::unexpected(reply.error());
  }
  std::vector<ipc::UniqueFd> fds = connection.take_fds();
  if (fds.size() != ipc::kChannelFdCount || reply->element_size != sizeof(ipc::ChannelMessage)) {
    return tl::unexpected(IpcError{EPROTO, fmt::format("canemud sent {} descriptors and {}-byte "
                                                       "elements for a channel",
                                                       fds.size(), reply->element_size)});
  }
  auto rings = ipc::RingPair::map(std::move(fds), sizeof(ipc::ChannelMessage));
  if (!rings) {
    return tl::unexpected(rings.error());
  }
  return Channel(
      std::make_unique<State>(&connection, *reply, int64_t{o.spin_us} * 1000, std::move(*rings)));
}

Channel::State::State(Connection* c, const ipc::OpenChannelReply& reply, int64_t spin,
                      ipc::RingPair pair)
    : connection(c),
      info(reply),
      device(ipc::name_of(reply.device)),
      spin_ns(spin),
      rings(std::move(pair)),
      rx(rings.rx().reader()),
      tx(rings.tx().writer()) {}

Channel::Channel(Channel&& o) noexcept = default;

Channel& Channel::operator=(Channel&& o) noexcept {
  if (this != &o) {
    (void)close();
    s_ = std::move(o.s_);
  }
  return *this;
}

Channel::~Channel() {
  (void)close();
}

Result<void> Channel::send(const ipc::ChannelMessage& message, int timeout_ms) {
  ipc::RingWriter& tx = s_->tx;
  ipc::RingStatus status = tx.put(&message);
  if (status == ipc::RingStatus::full && timeout_ms != 0) {
    spin(s_->spin_ns, [&] { return (status = tx.put(&message)) != ipc::RingStatus::full; });
    while (status == ipc::RingStatus::full) {
      if (!tx.wait(timeout_ms) && tx.free_count() == 0) {
        return tl::unexpected(IpcError{ETIMEDOUT, "transmit ring still full"});
      }
      status = tx.put(&message);
    }
  }
  switch (status) {
    case ipc::RingStatus::ok:
      return {};
    case ipc::RingStatus::full:
      return tl::unexpected(IpcError{EAGAIN, "transmit ring full"});
    default:
      return tl::unexpected(IpcError{EIO, "transmit ring corrupted"});
  }
}

std::optional<ipc::ChannelMessage> Channel::receive(int timeout_ms) {
  ipc::RingReader& rx = s_->rx;
  ipc::ChannelMessage m;
  ipc::RingStatus status = rx.get(&m);
  if (status == ipc::RingStatus::empty && timeout_ms != 0) {
    spin(s_->spin_ns, [&] { return (status = rx.get(&m)) != ipc::RingStatus::empty; });
    while (status == ipc::RingStatus::empty) {
      const bool woken = rx.wait(timeout_ms);
      status = rx.get(&m);
      if (!woken) {
        break;
      }
    }
  }
  if (status == ipc::RingStatus::ok) {
    return m;
  }
  return std::nullopt;
}

Result<ipc::ChannelStatusReply> Channel::status() {
  if (!s_ || s_->connection == nullptr) {
    return tl::unexpected(IpcError{EBADF, "the channel is closed"});
  }
  auto m = ipc::make_message<ipc::ChannelStatusRequest>();
  m.channel = id();
  return s_->connection->call<ipc::ChannelStatusRequest, ipc::ChannelStatusReply>(m);
}

Result<void> Channel::close() {
  if (!s_ || s_->connection == nullptr) {
    return {};
  }
  auto m = ipc::make_message<ipc::CloseChannelRequest>();
  m.channel = id();
  auto r = s_->connection->call<ipc::CloseChannelRequest, ipc::CloseChannelReply>(m);
  s_->connection = nullptr;
  if (!r) {
    return tl::unexpected(r.error());
  }
  return {};
}

}  // namespace canemu::client
