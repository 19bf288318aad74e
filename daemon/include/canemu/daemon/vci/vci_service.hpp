// The VCI requests of the control protocol (ipc::VciRequest), answered: each client's handles
// on the adapter firmware of configured devices (the control unit, channels with their rings,
// the cyclic transmit list), checked against the client that owns them, and closed when the
// client closes them or goes away.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "canemu/daemon/base/ring_budget.hpp"
#include "canemu/daemon/vci/vci_fifos.hpp"
#include "canemu/daemon/vci/vci_lin_port.hpp"
#include "canemu/daemon/vci/vci_port.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

inline constexpr std::size_t kMaxVciHandlesPerClient = 64;
inline constexpr std::size_t kMaxVciChannelsPerClient = 16;

// One object a client opened. Closing it (destruction) releases it on the line.
class VciHandle {
 public:
  enum class Kind : uint8_t { control, channel, scheduler, lin_control, lin_monitor };
  VciHandle(Kind kind, std::shared_ptr<model::ixxat::CanLine> line, model::ixxat::ChannelId channel,
            bool v2)
      : kind_(kind), line_(std::move(line)), channel_(channel), v2_(v2) {}
  // A LIN control unit (lin_control) or monitor `monitor` (lin_monitor).
  VciHandle(Kind kind, std::shared_ptr<model::ixxat::LinLine> lin, model::ixxat::MonitorId monitor)
      : kind_(kind), channel_(0), v2_(false), lin_(std::move(lin)), monitor_(monitor) {}
  ~VciHandle();
  VciHandle(const VciHandle&) = delete;
  VciHandle& operator=(const VciHandle&) = delete;
  uint32_t uid = 0;   // the owner's: its ring memory counts against that user's quota
  std::string where;  // the line, for the log: "ADAPTER CAN n"

  Kind kind() const { return kind_; }
  bool is_lin() const { return kind_ == Kind::lin_control || kind_ == Kind::lin_monitor; }
  model::ixxat::CanLine& line() { return *line_; }  // CAN handles only
  model::ixxat::LinLine& lin() { return *lin_; }    // LIN handles only
  model::ixxat::MonitorId monitor() const { return monitor_; }
  VciLinPort* lin_port() { return lin_port_.get(); }
  // A monitor's new receive FIFO (initialization); the old one goes.
  void replace_lin_port(std::unique_ptr<VciLinPort> port, RingBudget budget) {
    lin_port_ = std::move(port);
    lin_budget_ = std::move(budget);
  }
  model::ixxat::ChannelId channel() const { return channel_; }
  bool v2() const { return v2_; }
  VciPort* port() { return port_.get(); }
  // A new port (channel initialization); returns the one it replaces.
  std::unique_ptr<VciPort> replace_port(std::unique_ptr<VciPort> port, RingBudget budget);

 private:
  Kind kind_;
  std::shared_ptr<model::ixxat::CanLine> line_;
  model::ixxat::ChannelId channel_;
  bool v2_;
  std::unique_ptr<VciPort> port_;
  RingBudget budget_;
  std::shared_ptr<model::ixxat::LinLine> lin_;
  model::ixxat::MonitorId monitor_ = 0;
  std::unique_ptr<VciLinPort> lin_port_;
  RingBudget lin_budget_;
};

inline constexpr std::size_t kMaxVciDevicesPerClient = 16;

struct VciSession {
  uint32_t next_handle = 1;
  std::map<uint32_t, std::unique_ptr<VciHandle>> handles;
  // Ephemeral adapters this client created, by name.
  std::map<std::string, Simulation::DeviceLease> devices;
  uint32_t pid = 0;
  uint32_t uid = 0;
};

// The session's CAN channels and LIN monitors (each has rings): at most kMaxVciChannelsPerClient.
inline std::size_t receivers(const VciSession& session) {
  std::size_t n = 0;
  for (const auto& [id, h] : session.handles) {
    n += h->kind() == VciHandle::Kind::channel || h->kind() == VciHandle::Kind::lin_monitor ? 1 : 0;
  }
  return n;
}

class VciService {
 public:
  using Send = std::function<void(const void* data, std::size_t size, std::span<const int> fds)>;
  // `bells` is told of every VCI channel's doorbell as it opens and before it closes.
  VciService(Simulation& sim, RingLedger& rings, DoorbellWatch& bells)
      : sim_(sim), rings_(rings), bells_(bells), fifos_(rings) {}

  void handle(VciSession& session, const ipc::VciRequest& m, const Send& send);
  // Everything the session opened, closed (the client went away).
  void close_all(VciSession& session);

 private:
  void close(VciSession& session, uint32_t handle);
  void open(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r);
  void create_device(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r);
  void init_channel(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r,
                    std::array<int, ipc::kChannelFdCount>& fds);
  void control(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r);
  void scheduler(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r);
  // LIN (vci_lin.cpp): opening a control unit or monitor, and the calls on them. `fds` gets a
  // monitor's descriptors (lin_monitor_init), `with_fds` says so.
  static bool is_lin(ipc::VciOp op);
  void lin(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r,
           std::array<int, ipc::kChannelFdCount>& fds, bool& with_fds);
  void lin_open(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r);
  void lin_call(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r,
                std::array<int, ipc::kChannelFdCount>& fds, bool& with_fds);
  void lin_monitor_init(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r,
                        std::array<int, ipc::kChannelFdCount>& fds, bool& with_fds);
  // A new handle of `session` for `h`; its number in r.handle.
  static void add_handle(VciSession& session, std::unique_ptr<VciHandle> h, ipc::VciReply& r);

  Simulation& sim_;
  RingLedger& rings_;
  DoorbellWatch& bells_;
  VciFifos fifos_;  // stand-alone FIFOs, held by sessions
};

}  // namespace canemu::daemon
