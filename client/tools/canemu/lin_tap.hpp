// What canemu dump and send do on a LIN bus: an ephemeral VCI adapter of their own on the bus
// (gone with the connection), its LIN controller started in `mode` and its monitor, whose
// messages come with their simulated time.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/ring_pair.hpp"
#include "vci/lintype.h"

namespace canemu::cli {

class LinTap {
 public:
  // `bitrate` 0: the rate of each header (a responder only).
  static client::Result<LinTap> open(client::Connection& c, const std::string& bus, uint8_t mode,
                                     uint32_t bitrate);

  const std::string& device() const { return device_; }
  // The control unit's handle, for VciOp::lin_write.
  uint32_t control() const { return control_; }

  struct Message {
    LINMSG msg;
    int64_t at_ns;  // simulated time
  };
  // The next message but time overruns (which it counts), waiting up to `timeout_ms`.
  client::Result<std::optional<Message>> next(int timeout_ms);

 private:
  LinTap(std::string device, uint32_t control, ipc::RingPair rings, int64_t epoch_ns)
      : device_(std::move(device)),
        control_(control),
        rings_(std::move(rings)),
        rx_(rings_.rx().reader()),
        epoch_ns_(epoch_ns) {}

  std::string device_;
  uint32_t control_;
  ipc::RingPair rings_;
  ipc::RingReader rx_;
  int64_t epoch_ns_;
  uint64_t wraps_ = 0;  // of the 32-bit microsecond time stamps
};

// One VCI request on `c`; the VCI result as an error when it is not VCI_OK.
client::Result<ipc::VciReply> vci_call(client::Connection& c, ipc::VciRequest m,
                                       std::vector<ipc::UniqueFd>* fds = nullptr);

}  // namespace canemu::cli
