// The control protocol's requests, answered: checks every message (ipc::check_message), keeps
// each client's session state, and produces the replies. The server owns the sockets and calls
// it with each packet; the fuzz target calls it with arbitrary bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>

#include "canemu/daemon/channel.hpp"
#include "canemu/daemon/config.hpp"
#include "canemu/daemon/simulation.hpp"

namespace canemu::daemon {

// A channel and the ephemeral device it runs on; the device is unregistered after the channel
// has stopped its node.
struct SessionChannel {
  Simulation::DeviceLease lease;
  std::unique_ptr<Channel> channel;
};

inline constexpr std::size_t kMaxChannelsPerClient = 16;

// What the daemon knows of one client.
struct Session {
  bool greeted = false;
  std::string name;
  uint32_t pid = 0;  // from SO_PEERCRED
  uint32_t uid = 0;
  uint32_t events = 0;  // subscribed notifications (ipc::kEvent*)
  uint32_t next_channel = 1;
  std::map<uint32_t, SessionChannel> channels;
};

class ControlDispatcher {
 public:
  using Send = std::function<void(const void* data, std::size_t size, std::span<const int> fds)>;

  ControlDispatcher(Simulation& sim, TimeSetting time) : sim_(sim), time_(time) {}

  // Called before a status reply: the server brings simulated time to "now" and forgets
  // clients that went away.
  std::function<void()> before_status;
  std::function<uint16_t()> client_count;
  std::function<void(ipc::ClientListReply&)> fill_clients;
  // Called before a time step runs: the server lets every idle node take what its client put.
  std::function<void()> before_step;
  // A channel was opened or is about to close (the server watches its doorbell).
  std::function<void(Channel&)> channel_opened;
  std::function<void(Channel&)> channel_closing;

  // Handles one packet of `size` bytes; `send` gets each reply.
  void handle(Session& session, const uint8_t* data, std::size_t size, const Send& send);

 private:
  void error(const Send& send, uint32_t request_id, ipc::ErrorCode code, const std::string& text);
  void open_channel(Session& c, const ipc::OpenChannelRequest& m, const Send& send);
  void channel_status(Session& c, const ipc::ChannelStatusRequest& m, const Send& send);

  Simulation& sim_;
  TimeSetting time_;
};

}  // namespace canemu::daemon
