// A client's channel on an ephemeral device: one node (model::HostedNode: an SJA1000 on a
// classic bus, the CAN FD controller on a CAN FD bus) on a bus,
// joined to the client by two rings in shared memory. The receive ring gets every frame the
// node receives (and, when asked for, transmit confirmations, bus errors and state changes), at
// its exact simulated instant; the node takes frames to send from the transmit ring whenever its
// transmit buffer is free, so a full bus makes the client's ring fill up rather than the daemon
// queue frames.
//
// The daemon sleeps on the transmit ring's doorbell only while its node is idle and the ring is
// empty; under load no system call is made per frame. Everything read from the rings is checked;
// a ring the client corrupted marks the channel broken and the server drops the client.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/base/doorbell.hpp"
#include "canemu/daemon/base/error.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/ring_pair.hpp"

namespace canemu::daemon {

struct ChannelStats {
  uint64_t rx_lost = 0;      // messages the receive ring had no room for
  uint64_t tx_rejected = 0;  // transmit ring elements that were not frames the node can send
};

class Channel final : private model::ControllerEvents, public Doorbell {
 public:
  struct Options {
    uint16_t flags = 0;  // ipc::kChannel*
    uint32_t rx_capacity = 1024;
    uint32_t tx_capacity = 256;
  };

  // Makes the rings and starts `node` with `settings`. The error names what failed.
  static Result<std::unique_ptr<Channel>> open(uint32_t id, std::string device, std::size_t bus,
                                               model::HostedNode& node,
                                               const model::HostedNodeSettings& settings,
                                               const Options& options);
  // Stops the node (it can then be reused) and unmaps the rings.
  ~Channel() override;
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  uint32_t id() const { return id_; }
  const std::string& device() const { return device_; }
  std::size_t bus() const { return bus_; }
  model::HostedNode& node() { return node_; }
  const ChannelStats& stats() const { return stats_; }
  uint32_t rx_capacity() const { return rings_.rx().memory().capacity(); }
  uint32_t tx_capacity() const { return rings_.tx().memory().capacity(); }
  uint32_t rx_fill() const { return rx_.fill_count(); }

  // What goes to the client with the OpenChannelReply, in the protocol's order.
  std::array<int, ipc::kChannelFdCount> client_fds() const { return rings_.fds(); }
  // The daemon's doorbell: readable when the client put frames while the node was idle.
  int doorbell_fd() const override { return rings_.tx().reader_event(); }
  // Called when the doorbell rang, or at any time (before a time step): the node takes a frame
  // if it is idle.
  void kick() override;
  int64_t take_rung_ns() override { return tx_.take_woken_ns(); }
  void set_arming(bool arming) override { arming_ = arming; }
  // The client broke a ring (positions out of range); the server drops the client.
  bool broken() const override { return rx_.corrupted_after_writes() || tx_.corrupted(); }

 private:
  Channel(uint32_t id, std::string device, std::size_t bus, model::HostedNode& node, uint16_t flags,
          ipc::RingPair rings);

  std::optional<model::TxFrame> next_tx();
  // Counts and reports a transmit element the node cannot send; false when this kick has
  // skipped enough of them and the loop should get its turn.
  bool reject(ipc::ChannelMessage& m);
  void deliver(ipc::ChannelMessage& m);

  void frame_received(model::SimTime at, const model::Frame& frame, bool own) override;
  void frame_transmitted(model::SimTime at, const model::Frame& frame) override;
  void transmission_dropped(model::SimTime at, const model::Frame& frame) override;
  void bus_error(const model::BusErrorEvent& event) override;
  void state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                     uint16_t rec) override;

  uint32_t id_;
  std::string device_;
  std::size_t bus_;
  model::HostedNode& node_;
  uint16_t flags_;
  ipc::RingPair rings_;
  ipc::RingWriter rx_;  // canemud's views: it writes the receive ring, reads the transmit ring
  ipc::RingReader tx_;
  ChannelStats stats_;
  uint32_t lost_pending_ = 0;  // lost since the last message that made it into the ring
  bool armed_ = false;         // sleeping on the doorbell
  bool arming_ = true;         // whether an empty ring arms it (Doorbell::set_arming)
  // Invalid transmit elements skipped per kick before the loop gets back to other work.
  static constexpr uint32_t kMaxRejectsPerKick = 256;
  uint32_t rejects_left_ = kMaxRejectsPerKick;
};

// Frames and channel messages, both ways.
ipc::ChannelMessage to_message(model::SimTime at, const model::Frame& frame,
                               ipc::ChannelMessageKind kind, bool own = false);
model::Result<model::TxFrame> to_tx_frame(const ipc::ChannelMessage& m);
// A node's bus error (with its error state after it) and state change as channel messages: the
// error's location as the SJA1000's error code capture gives it (CAN_ERR_PROT_LOC_*).
ipc::ChannelMessage to_error_message(const model::BusErrorEvent& e, model::ErrorState state);
ipc::ChannelMessage to_state_message(model::SimTime at, model::ErrorState state, uint16_t tec,
                                     uint16_t rec);

}  // namespace canemu::daemon
