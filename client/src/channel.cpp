#include "canemu/client/channel.hpp"

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
    if (k % 64 == 0 && ipc::monotonic_ns() >= until) {
      return false;
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
  auto rx = ipc::RingMemory::map(std::move(fds[0]));
  if (!rx) {
    return tl::unexpected(rx.error());
  }
  auto tx = ipc::RingMemory::map(std::move(fds[1]));
  if (!tx) {
    return tl::unexpected(tx.error());
  }
  if (rx->element_size() != sizeof(ipc::ChannelMessage) ||
      tx->element_size() != sizeof(ipc::ChannelMessage)) {
    return tl::unexpected(IpcError{EPROTO, "ring element size is not a ChannelMessage"});
  }
  Channel c;
  c.connection_ = &connection;
  c.id_ = reply->channel;
  c.device_ = ipc::name_of(reply->device);
  c.info_ = *reply;
  c.rx_memory_ = std::make_unique<ipc::RingMemory>(std::move(*rx));
  c.tx_memory_ = std::make_unique<ipc::RingMemory>(std::move(*tx));
  c.rx_event_ = std::move(fds[2]);
  c.tx_writer_event_ = std::move(fds[3]);
  c.tx_doorbell_ = std::move(fds[4]);
  // The daemon never waits on the receive ring's writer side: no eventfd there.
  c.rx_ = std::make_unique<ipc::RingReader>(*c.rx_memory_, -1, c.rx_event_.get());
  c.tx_ = std::make_unique<ipc::RingWriter>(*c.tx_memory_, c.tx_doorbell_.get(),
                                            c.tx_writer_event_.get());
  c.mutex_ = std::make_unique<std::mutex>();
  c.spin_ns_ = int64_t{o.spin_us} * 1000;
  return c;
}

Channel::Channel(Channel&& o) noexcept
    : connection_(std::exchange(o.connection_, nullptr)),
      id_(o.id_),
      spin_ns_(o.spin_ns_),
      device_(std::move(o.device_)),
      info_(o.info_),
      rx_memory_(std::move(o.rx_memory_)),
      tx_memory_(std::move(o.tx_memory_)),
      rx_event_(std::move(o.rx_event_)),
      tx_writer_event_(std::move(o.tx_writer_event_)),
      tx_doorbell_(std::move(o.tx_doorbell_)),
      rx_(std::move(o.rx_)),
      tx_(std::move(o.tx_)),
      mutex_(std::move(o.mutex_)) {}

Channel& Channel::operator=(Channel&& o) noexcept {
  if (this != &o) {
    if (connection_ != nullptr) {
      (void)close();
    }
    connection_ = std::exchange(o.connection_, nullptr);
    id_ = o.id_;
    spin_ns_ = o.spin_ns_;
    device_ = std::move(o.device_);
    info_ = o.info_;
    rx_memory_ = std::move(o.rx_memory_);
    tx_memory_ = std::move(o.tx_memory_);
    rx_event_ = std::move(o.rx_event_);
    tx_writer_event_ = std::move(o.tx_writer_event_);
    tx_doorbell_ = std::move(o.tx_doorbell_);
    rx_ = std::move(o.rx_);
    tx_ = std::move(o.tx_);
    mutex_ = std::move(o.mutex_);
  }
  return *this;
}

Channel::~Channel() {
  if (connection_ != nullptr) {
    (void)close();
  }
}

Result<void> Channel::send(const ipc::ChannelMessage& message, int timeout_ms) {
  ipc::RingStatus status = tx_->put(&message);
  if (status == ipc::RingStatus::full && timeout_ms != 0) {
    spin(spin_ns_, [&] { return (status = tx_->put(&message)) != ipc::RingStatus::full; });
    while (status == ipc::RingStatus::full) {
      if (!tx_->wait(timeout_ms) && tx_->free_count() == 0) {
        return tl::unexpected(IpcError{ETIMEDOUT, "transmit ring still full"});
      }
      status = tx_->put(&message);
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
  ipc::ChannelMessage m;
  ipc::RingStatus status = rx_->get(&m);
  if (status == ipc::RingStatus::empty && timeout_ms != 0) {
    spin(spin_ns_, [&] { return (status = rx_->get(&m)) != ipc::RingStatus::empty; });
    while (status == ipc::RingStatus::empty) {
      if (!rx_->wait(timeout_ms)) {
        status = rx_->get(&m);
        break;
      }
      status = rx_->get(&m);
    }
  }
  if (status == ipc::RingStatus::ok) {
    return m;
  }
  return std::nullopt;
}

Result<ipc::ChannelStatusReply> Channel::status() {
  auto m = ipc::make_message<ipc::ChannelStatusRequest>();
  m.channel = id_;
  return connection_->call<ipc::ChannelStatusRequest, ipc::ChannelStatusReply>(m);
}

Result<void> Channel::close() {
  if (connection_ == nullptr) {
    return {};
  }
  auto m = ipc::make_message<ipc::CloseChannelRequest>();
  m.channel = id_;
  auto r = connection_->call<ipc::CloseChannelRequest, ipc::CloseChannelReply>(m);
  connection_ = nullptr;
  if (!r) {
    return tl::unexpected(r.error());
  }
  return {};
}

}  // namespace canemu::client
