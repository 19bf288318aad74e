// A VCI LIN monitor's receive FIFO in shared memory, as the adapter firmware
// (model::ixxat::LinLine) sees it. The rings are a channel's (ipc::RingPair, LINMSG elements of
// 16 bytes), so that the client library reads a monitor with the code that reads a CAN
// channel; the transmit ring (one page) stays unused: a monitor only receives.
//
// Not modelled: a receive ring the client corrupted is not reported to the server (a CAN
// channel's port is): what canemud puts into it is lost, nothing else happens.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/firmware_model/adapters/ixxat/lin_line.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/ring_pair.hpp"

namespace canemu::daemon {

class VciLinPort final : public model::ixxat::LinMonitorPort {
 public:
  // A receive ring of at least `capacity` elements (at most 65535).
  static Result<std::unique_ptr<VciLinPort>> create(uint32_t capacity, const std::string& name);

  uint32_t capacity() const { return rings_.rx().memory().capacity(); }
  std::size_t bytes() const { return rings_.element_bytes(); }
  // What goes to the client, in the order of a channel_init reply's descriptors.
  std::array<int, ipc::kChannelFdCount> client_fds() const { return rings_.fds(); }

  // --- model::ixxat::LinMonitorPort ---
  std::size_t room() const override { return rx_.free_count(); }
  void put(const LINMSG& msg) override;

 private:
  explicit VciLinPort(ipc::RingPair rings) : rings_(std::move(rings)), rx_(rings_.rx().writer()) {}

  ipc::RingPair rings_;
  ipc::RingWriter rx_;  // canemud's view: it writes the receive FIFO
};

}  // namespace canemu::daemon
