// A VCI channel's FIFOs in shared memory, as the adapter firmware (model::ixxat::CanLine) sees
// them: the receive FIFO it writes and the transmit FIFO it reads. Elements are the vendor
// structs themselves: CANMSG (20 bytes) for v1 channels, CANMSG2 (80 bytes) for v2 channels, so
// the client library hands them to the application as they are.
//
// Like the ephemeral channels (channel.hpp), the daemon sleeps on the transmit ring's doorbell
// only while the ring is empty; everything read from the rings is checked, and a ring the
// client corrupted marks the port broken (the server then drops the client).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/base/doorbell.hpp"
#include "canemu/daemon/base/error.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/ring_pair.hpp"

namespace canemu::daemon {

class VciPort final : public model::ixxat::ChannelPort, public Doorbell {
 public:
  // Rings of at least `rx_capacity` / `tx_capacity` elements (at most 65535 each).
  static Result<std::unique_ptr<VciPort>> create(bool v2, uint32_t rx_capacity,
                                                 uint32_t tx_capacity, const std::string& name);
  // The line the port's transmit ring feeds (told when the doorbell rings).
  void attach(model::ixxat::CanLine* line) { line_ = line; }

  uint32_t element_size() const { return rings_.element_size(); }
  uint32_t rx_capacity() const { return rings_.rx().memory().capacity(); }
  uint32_t tx_capacity() const { return rings_.tx().memory().capacity(); }
  std::size_t bytes() const { return rings_.element_bytes(); }
  // What goes to the client, in the order of ipc::OpenChannelReply's descriptors.
  std::array<int, ipc::kChannelFdCount> client_fds() const { return rings_.fds(); }

  // --- model::ixxat::ChannelPort ---
  bool put(const CANMSG2& msg) override;
  std::optional<CANMSG2> peek() override;
  void pop() override;
  void defer() override;

  // --- Doorbell ---
  int doorbell_fd() const override { return rings_.tx().reader_event(); }
  void kick() override;
  int64_t take_rung_ns() override { return tx_.take_woken_ns(); }
  void set_arming(bool arming) override { arming_ = arming; }
  bool broken() const override { return rx_.corrupted_after_writes() || tx_.corrupted(); }

 private:
  VciPort(bool v2, ipc::RingPair rings);

  bool v2_;
  model::ixxat::CanLine* line_ = nullptr;
  ipc::RingPair rings_;
  ipc::RingWriter rx_;  // canemud's views: it writes the receive FIFO, reads the transmit FIFO
  ipc::RingReader tx_;
  bool armed_ = false;  // sleeping on the doorbell
  bool arming_ = true;  // whether an empty ring arms it (Doorbell::set_arming)
};

// CANMSG <-> CANMSG2 (a v1 channel's elements): the first 8 data bytes.
CANMSG to_canmsg(const CANMSG2& m);
CANMSG2 to_canmsg2(const CANMSG& m);

}  // namespace canemu::daemon
