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
#include <utility>

#include "canemu/daemon/base/channel.hpp"
#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/base/ring_budget.hpp"
#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/sorcus/slcan_service.hpp"
#include "canemu/daemon/sorcus/xcan_service.hpp"
#include "canemu/daemon/vci/vci_service.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon {

// A channel and the ephemeral device it runs on; the device is unregistered after the channel
// has stopped its node.
struct SessionChannel {
  RingBudget budget;
  Simulation::DeviceLease lease;
  std::unique_ptr<Channel> channel;
};

inline constexpr std::size_t kMaxChannelsPerClient = 16;

// `canemu lin`: the answer to a LinNodeRequest (lin_requests.cpp).
std::unique_ptr<ipc::LinNodeReply> answer_lin_nodes(Simulation& sim, const ipc::LinNodeRequest& m,
                                                    uint32_t request_id);

// `canemu restbus`, `canemu signal`: the answer to a CanNodeRequest (can_node_requests.cpp);
// `pending` gathers a load's parts until its last.
std::unique_ptr<ipc::CanNodeReply> answer_can_nodes(Simulation& sim, std::string& pending,
                                                    const ipc::CanNodeRequest& m,
                                                    uint32_t request_id);

// What the daemon knows of one client.
struct Session {
  bool greeted = false;
  std::string name;
  uint32_t pid = 0;  // from SO_PEERCRED
  uint32_t uid = 0;
  uint32_t gid = 0;     // primary group, from SO_PEERCRED
  bool admin = false;   // may clear every fault scenario ([security] admin_groups)
  uint32_t events = 0;  // subscribed notifications (ipc::kEvent*)
  uint32_t next_channel = 1;
  std::map<uint32_t, SessionChannel> channels;
  VciSession vci;
  XcanSession xcan;
  SlcanSession slcan;
  std::string can_node_text;  // the parts of a [[can_node]] load so far
};

// What the dispatcher asks of the server's loop (loop/server.cpp). The defaults are those of
// a dispatcher alone (the fuzz targets): a step runs at once, doorbells go unwatched, no client
// is counted.
class LoopServices : public DoorbellWatch {
 public:
  // Before a status reply: the server brings simulated time to "now" and writes what the
  // recorders hold.
  virtual void before_status() {}
  virtual uint16_t client_count() { return 0; }
  // Fills what only the server knows of time: the lag and the achieved scale.
  virtual void fill_pace(ipc::StatusReply&) {}
  // Fills the page of clients from the reply's `first` on, and their total.
  virtual void fill_clients(ipc::ClientListReply&) {}
  // Before a time step runs the dispatcher's own way: idle nodes take what their clients put.
  virtual void before_step() {}
  // After it ran, before its reply: what the step made for clients goes out (X-CAN callbacks,
  // the ends of blocking services).
  virtual void after_step() {}
  // Takes a step request over (true) and answers it later: canemud runs steps in slices, and
  // across hosts when every daemon in it is ready. False: the dispatcher runs it at once.
  virtual bool defer_step(int64_t /*step_ns*/, uint32_t /*request_id*/) { return false; }
  // A channel (ephemeral, VCI, a bridge's) was opened or is about to close.
  void watch(Doorbell&) override {}
  void unwatch(Doorbell&) override {}

 protected:
  ~LoopServices() = default;
};

class ControlDispatcher {
 public:
  using Send = std::function<void(const void* data, std::size_t size, std::span<const int> fds)>;

  ControlDispatcher(Simulation& sim, TimeSetting time, LoopServices& loop)
      : sim_(sim), time_(time), loop_(loop), vci_(sim, rings_, loop), xcan_(sim), slcan_(sim) {}

  // The ring memory one user's channels and FIFOs may hold together (root: no quota).
  void set_ring_quota(std::size_t bytes) { rings_.set_user_quota(bytes); }
  const RingLedger& rings() const { return rings_; }

  // Handles one packet of `size` bytes; `send` gets each reply.
  void handle(Session& session, const uint8_t* data, std::size_t size, const Send& send);
  // The client went away: everything it opened is closed (before its session is destroyed).
  void end_session(Session& session);
  // Calls f(doorbell) for every ring pair the session has.
  template <class F>
  static void for_each_ring(Session& session, F&& f) {
    for (auto& [id, sc] : session.channels) {
      f(static_cast<Doorbell&>(*sc.channel));
    }
    for (auto& [id, h] : session.vci.handles) {
      if (VciPort* port = h->port(); port != nullptr) {
        f(static_cast<Doorbell&>(*port));
      }
    }
  }

 private:
  void error(const Send& send, uint32_t request_id, ipc::ErrorCode code, const std::string& text);
  void open_channel(Session& c, const ipc::OpenChannelRequest& m, const Send& send);
  void channel_status(Session& c, const ipc::ChannelStatusRequest& m, const Send& send);
  void add_bridge(const ipc::BridgeAddRequest& m, const Send& send, uint32_t request_id);

  // One handler per request type, each area's in a file of its own: session_requests.cpp (hello,
  // subscribe, clients), world_requests.cpp (status, lists, timeline, time step),
  // channel_requests.cpp, bridge_requests.cpp, fault_requests.cpp, lin_requests.cpp, and the
  // adapters' services (vci/, sorcus/) from control_dispatcher.cpp.
  using Handler = void (ControlDispatcher::*)(Session&, const uint8_t*, uint32_t, const Send&);
  static Handler handler_for(ipc::MsgType type);
  void on_hello(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_subscribe(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_client_list(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_status(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_time_step(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_timeline(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_device_list(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_recorder_list(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_bridge_list(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_peer_list(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_open_channel(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_close_channel(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_channel_status(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_bridge_add(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_bridge_remove(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_bridge_restart(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_fault_load(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_fault_list(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_fault_clear(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_lin_node(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_can_node(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_vci(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_xcan(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);
  void on_slcan(Session& c, const uint8_t* data, uint32_t request_id, const Send& send);

  Simulation& sim_;
  TimeSetting time_;
  LoopServices& loop_;
  RingLedger rings_;
  VciService vci_;
  XcanService xcan_;
  SlcanService slcan_;
};

}  // namespace canemu::daemon
