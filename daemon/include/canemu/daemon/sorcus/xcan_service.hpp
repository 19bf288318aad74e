// The X-CAN-2i requests of the control protocol (ipc::XcanRequest), answered: each client's
// channels on the MDD of configured "sorcus-x-can-2i" devices, checked against the client that
// owns them, and closed when the client closes them or goes away.
//
// A blocking service (Reply::pending) is answered when the module completes it; callbacks go to
// the client that owns the channel. Both wait in the client's session outbox, which the server
// sends after the events that made them (and before a time step's reply), so a client sees the
// callbacks of a step before the step's end.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <span>
#include <utility>
#include <vector>

#include "canemu/daemon/world/simulation.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

inline constexpr std::size_t kMaxXcanChannelsPerClient = 64;
// Blocking services a client may have waiting at once.
inline constexpr std::size_t kMaxXcanPendingPerClient = 64;

struct XcanSession {
  struct Channel {
    std::shared_ptr<XcanDevice> device;
    model::sorcus::ChannelHandle handle = 0;
  };
  uint32_t next_channel = 1;
  std::map<uint32_t, Channel> channels;
  std::size_t pending = 0;
  // Replies to blocking services and callbacks, in the order they were made.
  std::deque<std::vector<uint8_t>> outbox;
};

class XcanService {
 public:
  using Send = std::function<void(const void* data, std::size_t size, std::span<const int> fds)>;
  explicit XcanService(Simulation& sim) : sim_(sim) {}
  ~XcanService();
  XcanService(const XcanService&) = delete;
  XcanService& operator=(const XcanService&) = delete;

  void handle(XcanSession& session, const ipc::XcanRequest& m, const Send& send);
  // Everything the session opened, closed (the client went away).
  void close_all(XcanSession& session);

 private:
  struct Route {
    XcanSession* session;
    uint32_t channel;
  };
  struct Waiting {
    XcanSession* session;
    uint32_t channel;
    uint32_t request_id;
    uint16_t op;
  };
  using Key = std::pair<const XcanDevice*, uint64_t>;

  void hook(const std::shared_ptr<XcanDevice>& device);
  void on_callback(const XcanDevice& device, const model::sorcus::XcanCallback& c);
  void on_completed(const XcanDevice& device, const model::sorcus::XcanCompletion& c);
  void close(XcanSession& session, uint32_t channel);
  // Answers each waiting request on `channel` of `session` with `error` and forgets it.
  void fail_waiting(XcanSession& session, uint32_t channel, uint32_t error);

  Simulation& sim_;
  std::set<std::shared_ptr<XcanDevice>> hooked_;
  std::map<Key, Route> routes_;     // (device, module channel) -> the client's channel
  std::map<Key, Waiting> waiting_;  // (device, request) -> the request to answer
};

}  // namespace canemu::daemon
