// A channel on an ephemeral device: one SJA1000 node on a named bus, alive while the connection
// lasts (or until close()), with its receive and transmit rings mapped into this process.
//
// receive() and send() poll for a while (ChannelOptions::spin_us), then block on the ring's
// eventfd; while frames flow no system call is made. The rings themselves (rx(), tx()) offer the
// VCI FIFO operations: get/put, acquire/release runs, fill and free counts, thresholds.
// lock()/unlock() serialise threads that share one channel (the rings are single-producer,
// single-consumer).
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/channel_message.hpp"
#include "canemu/ipc/ring_pair.hpp"

namespace canemu::client {

struct ChannelOptions {
  std::string bus;
  std::string device;         // empty: the daemon names it
  uint32_t bitrate = 0;       // 0: the bus's rate
  uint32_t data_bitrate = 0;  // CAN FD buses: the data-phase rate; 0: the bus's
  uint16_t sample_point = 0;  // per mille; 0: the bus's
  uint16_t flags = 0;         // ipc::kChannel*
  uint32_t rx_capacity = 0;   // 0: 1024
  uint32_t tx_capacity = 0;   // 0: 256
  uint32_t restart_ms = 0;    // restart after bus-off; 0: stay bus-off
  // receive() and send() poll this long before they block on the eventfd: a frame that comes
  // within it costs no system call and no wake-up latency (one frame at 125 kbit/s takes up to
  // about 1 ms, at 1 Mbit/s up to 135 us).
  uint32_t spin_us = 200;
};

class Channel {
 public:
  // Opens a channel through `connection`, which must outlive it.
  static Result<Channel> open(Connection& connection, const ChannelOptions& options);
  Channel(Channel&&) noexcept;
  Channel& operator=(Channel&&) noexcept;
  ~Channel();

  // Puts a frame in the transmit ring; waits up to `timeout_ms` for room (0: not at all).
  // Errors: full after the wait, or the ring is corrupted.
  Result<void> send(const ipc::ChannelMessage& message, int timeout_ms = 0);
  // The next message from the receive ring, waiting up to `timeout_ms` (-1: forever).
  std::optional<ipc::ChannelMessage> receive(int timeout_ms);

  ipc::RingReader& rx() { return s_->rx; }
  ipc::RingWriter& tx() { return s_->tx; }
  // The eventfd signalled when the receive ring reaches its threshold while this side waits
  // (see RingReader::arm_unless_filled for use in a poll loop).
  int rx_event_fd() const { return s_->rings.rx().reader_event(); }
  // The shared headers and the daemon's doorbell, for tools and tests that need the raw ring.
  ipc::RingHeader* rx_header() const { return s_->rings.rx().memory().header(); }
  ipc::RingHeader* tx_header() const { return s_->rings.tx().memory().header(); }
  int tx_doorbell_fd() const { return s_->rings.tx().reader_event(); }

  void lock() { s_->mutex.lock(); }
  void unlock() { s_->mutex.unlock(); }

  Result<ipc::ChannelStatusReply> status();
  // Closes the channel; its device disappears. Also done by the destructor (without waiting
  // for the reply) and when the connection closes.
  Result<void> close();

  uint32_t id() const { return s_->info.channel; }
  const std::string& device() const { return s_->device; }
  const ipc::OpenChannelReply& info() const { return s_->info; }

 private:
  // Everything in one place that does not move, since the ring views point into the mappings.
  struct State {
    State(Connection* c, const ipc::OpenChannelReply& reply, int64_t spin, ipc::RingPair pair);
    Connection* connection;  // nullptr once closed
    ipc::OpenChannelReply info;
    std::string device;
    int64_t spin_ns;
    ipc::RingPair rings;
    ipc::RingReader rx;  // the client's views: it reads the receive ring, writes the transmit ring
    ipc::RingWriter tx;
    std::mutex mutex;
  };
  explicit Channel(std::unique_ptr<State> s) : s_(std::move(s)) {}

  std::unique_ptr<State> s_;  // nullptr once moved from
};

}  // namespace canemu::client
