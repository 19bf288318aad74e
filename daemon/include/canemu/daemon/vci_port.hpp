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

#include "canemu/daemon/doorbell.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/shm_ring.hpp"

namespace canemu::daemon {

class VciPort final : public model::ixxat::ChannelPort, public Doorbell {
 public:
  // Rings of at least `rx_capacity` / `tx_capacity` elements (at most 65535 each).
  static tl::expected<std::unique_ptr<VciPort>, std::string> create(bool v2, uint32_t rx_capacity,
                                                                    uint32_t tx_capacity,
                                                                    const std::string& name);
  // The line the port's transmit ring feeds (told when the doorbell rings).
  void attach(model::ixxat::CanLine* line) { line_ = line; }

  uint32_t element_size() const { return rx_memory_.element_size(); }
  uint32_t rx_capacity() const { return rx_memory_.capacity(); }
  uint32_t tx_capacity() const { return tx_memory_.capacity(); }
  std::size_t bytes() const;
  // What goes to the client, in the order of ipc::OpenChannelReply's descriptors.
  std::array<int, ipc::kChannelFdCount> client_fds() const;

  // --- model::ixxat::ChannelPort ---
  bool put(const CANMSG2& msg) override;
  std::optional<CANMSG2> peek() override;
  void pop() override;

  // --- Doorbell ---
  int doorbell_fd() const override { return doorbell_.get(); }
  void kick() override;
  bool broken() const override { return rx_.corrupted() || tx_.corrupted(); }

 private:
  VciPort(bool v2, ipc::RingMemory rx_memory, ipc::RingMemory tx_memory, ipc::UniqueFd rx_event,
          ipc::UniqueFd tx_writer_event, ipc::UniqueFd doorbell);

  bool v2_;
  model::ixxat::CanLine* line_ = nullptr;
  ipc::RingMemory rx_memory_;
  ipc::RingMemory tx_memory_;
  ipc::UniqueFd rx_event_;         // the client's reader waits on it
  ipc::UniqueFd tx_writer_event_;  // the client's writer waits on it for room
  ipc::UniqueFd doorbell_;         // the daemon's reader sleeps on it
  ipc::RingWriter rx_;
  ipc::RingReader tx_;
  bool armed_ = false;  // sleeping on the doorbell
};

// CANMSG <-> CANMSG2 (a v1 channel's elements): the first 8 data bytes.
CANMSG to_canmsg(const CANMSG2& m);
CANMSG2 to_canmsg2(const CANMSG& m);

}  // namespace canemu::daemon
