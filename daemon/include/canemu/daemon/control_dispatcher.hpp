// The control protocol's requests, answered: checks every message (ipc::check_message), keeps
// each client's session state, and produces the replies. The server owns the sockets and calls
// it with each packet; the fuzz target calls it with arbitrary bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "canemu/daemon/config.hpp"
#include "canemu/daemon/simulation.hpp"

namespace canemu::daemon {

struct Session {
  bool greeted = false;
  std::string name;
};

class ControlDispatcher {
 public:
  using Send = std::function<void(const void* data, std::size_t size)>;

  ControlDispatcher(Simulation& sim, TimeSetting time) : sim_(sim), time_(time) {}

  // Called before a status reply: the server brings simulated time to "now" and forgets
  // clients that went away.
  std::function<void()> before_status;
  std::function<uint16_t()> client_count;

  // Handles one packet of `size` bytes; `send` gets each reply.
  void handle(Session& session, const uint8_t* data, std::size_t size, const Send& send);

 private:
  void error(const Send& send, uint32_t request_id, ipc::ErrorCode code, const std::string& text);

  Simulation& sim_;
  TimeSetting time_;
};

}  // namespace canemu::daemon
