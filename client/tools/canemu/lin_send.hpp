// canemu send on a LIN bus (docs/lin.md, "canemu send"): frames one after another from an
// ephemeral adapter's LIN controller in master mode, each printed as canemu dump shows its
// outcome (the frame, or the error: no response, ...).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "canemu/client/connection.hpp"
#include "command.hpp"
#include "vci/lintype.h"

namespace canemu::cli {

// "ID#DATA" (the sender publishes: header and response, 1..8 bytes), "ID#" (the header alone:
// a responder answers), "sleep" (the go-to-sleep command); ID hex 00..3F. The checksum is
// enhanced unless `classic`. Nothing, with `error` set, for anything else.
std::optional<LINMSG> parse_lin_send(const std::string& text, bool classic, std::string& error);

struct LinSendOptions {
  std::string bus;
  uint32_t bitrate = 0;  // the bus's when 0
  bool classic = false;
  std::optional<int64_t> step_ns;  // stepped time: at most this long, all of it stepped
  int timeout_ms = 2000;           // real time: per frame
};

int run_lin_send(client::Connection& c, const std::vector<LINMSG>& frames, const LinSendOptions& o,
                 const TimeBase& base);

// The kind and bit rate of bus `bus` as canemud reports them; nothing if there is no such bus.
std::optional<std::pair<ipc::WireBusKind, uint32_t>> bus_kind(client::Connection& c,
                                                              const std::string& bus);

}  // namespace canemu::cli
