// A SocketCAN bridge ([[bridge]] kind = "socketcan", `canemu bridge add`): an emulated bus and a
// Linux CAN interface (vcan, vxcan or a real adapter) joined through a node of its own.
//
// The bridge's node (model::HostedNode: an SJA1000 on a classic bus, the CAN FD controller on a
// CAN FD bus) is an ordinary, acknowledging member of the bus. Frames that programs write on the
// interface are queued and sent by that node: they arbitrate, wait for the bus and take their
// exact time like any node's. Frames the node receives from the bus are written to the
// interface as struct can_frame / canfd_frame. With `error_frames`, the node's bus errors and
// state changes go to the interface too, as CAN_ERR_* frames (ipc/socketcan.hpp).
//
// No loops: the node never receives its own frames, and the socket (CAN_RAW, own messages not
// received) never reads back what it wrote; two bridges on one interface are refused.
//
// After bus-off the node stays off the bus (the kernel's default) unless `restart_ms` is set:
// then the bridge restarts it that long after the bus-off instant, as `ip link set canX type can
// restart-ms N` has a kernel driver do; restart() does it when asked (`ip link set canX type can
// restart`). Either way the node then waits for 128 sequences of 11 recessive bits (ISO
// 11898-1) before it is error-active and sends again; every restart is counted, and with
// `error_frames` it is written to the interface as the kernel's CAN_ERR_RESTARTED frame.
//
// Nothing is lost silently: the kernel's senders never see a refusal, so every frame from the
// interface that the bus cannot take (queue full, a frame the bus cannot carry, given up after
// bus-off) and every frame the interface refused (socket buffer full, interface down) is counted
// in BridgeStats, which `canemu bridge list` and `canemu status` show.
//
// The socket part is thin: the bridge reads and writes whole frames on a descriptor, which is a
// CAN_RAW socket in canemud (open_can_raw) and one end of a SOCK_SEQPACKET pair in tests.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/doorbell.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/ipc/channel_message.hpp"
#include "canemu/ipc/socketcan.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::daemon {

struct BridgeStats {
  uint64_t to_interface = 0;          // frames of the bus written to the interface
  uint64_t from_interface = 0;        // frames of the interface sent on the bus
  uint64_t error_frames = 0;          // error frames written to the interface
  uint64_t to_interface_dropped = 0;  // the interface refused them (buffer full, down)
  uint64_t queue_dropped = 0;         // from the interface while the queue was full
  uint64_t rejected = 0;        // from the interface but not a frame this bus carries (FD on a
                                // classic bus, error frames, bad lengths, identifiers)
  uint64_t tx_failed = 0;       // queued but given up by the node (bus-off)
  uint64_t kernel_dropped = 0;  // dropped by the kernel before the bridge read them (its
                                // socket's receive buffer was full: SO_RXQ_OVFL)
  uint64_t restarts = 0;        // restarts after bus-off, automatic and asked for
};

struct BridgeOptions {
  std::string bus;
  std::string interface;
  bool error_frames = false;
  bool fd = false;               // the bus is a CAN FD bus: CAN FD frames both ways
  uint32_t queue_frames = 1024;  // frames from the interface waiting for the bus
  uint32_t restart_ms = 0;       // restart after bus-off after this long; 0: stay bus-off
};

class SocketCanBridge final : private model::ControllerEvents, public Doorbell {
 public:
  // Starts `node` (a spare node of bus `bus`, acknowledging) with `settings`; `port` is the
  // interface's socket, non-blocking.
  static std::unique_ptr<SocketCanBridge> start(BridgeOptions options, std::size_t bus,
                                                model::HostedNode& node,
                                                const model::HostedNodeSettings& settings,
                                                ipc::UniqueFd port);
  ~SocketCanBridge() override;  // the node leaves the bus
  SocketCanBridge(const SocketCanBridge&) = delete;
  SocketCanBridge& operator=(const SocketCanBridge&) = delete;

  const BridgeOptions& options() const { return options_; }
  std::size_t bus() const { return bus_; }
  const BridgeStats& stats() const { return stats_; }
  std::size_t queued() const { return queue_.size(); }
  model::HostedNode& node() { return node_; }
  const model::HostedNode& node() const { return node_; }

  // The socket: readable when programs wrote frames on the interface.
  int doorbell_fd() const override { return port_.get(); }
  // Reads what the socket holds (at most kMaxReadsPerKick frames, so the loop gets its turn)
  // into the queue; the node takes the next frame if it is idle. Frames are placed at the
  // current simulated instant.
  void kick() override;
  bool broken() const override { return false; }

  // Restarts the node from bus-off now; what is wrong otherwise (it is not bus-off, or it
  // restarts already and waits for the recessive bits).
  std::optional<std::string> restart();

 private:
  SocketCanBridge(BridgeOptions options, std::size_t bus, model::HostedNode& node,
                  ipc::UniqueFd port)
      : options_(std::move(options)), bus_(bus), node_(node), port_(std::move(port)) {}

  std::optional<model::TxFrame> next_tx();
  void accept(const uint8_t* bytes, std::size_t size);
  void write_out(const ipc::ChannelMessage& m, uint64_t& counter);
  void write_frame(const ipc::socketcan::Frame& f, uint64_t& counter);

  void frame_received(model::SimTime at, const model::Frame& frame, bool own) override;
  void frame_transmitted(model::SimTime at, const model::Frame& frame) override;
  void transmission_dropped(model::SimTime at, const model::Frame& frame) override;
  void bus_error(const model::BusErrorEvent& event) override;
  void state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                     uint16_t rec) override;

  void restart_after_bus_off();

  static constexpr int kMaxReadsPerKick = 256;
  BridgeOptions options_;
  std::size_t bus_;
  model::HostedNode& node_;
  ipc::UniqueFd port_;
  std::deque<model::TxFrame> queue_;
  BridgeStats stats_;
  std::optional<model::EventId> restart_event_;  // the automatic restart, while due
};

// A CAN_RAW socket bound to `interface`, non-blocking and close-on-exec, with CAN FD frames
// when `fd` and every error class readable; the error names the interface and the failing call.
tl::expected<ipc::UniqueFd, std::string> open_can_raw(const std::string& interface, bool fd);

}  // namespace canemu::daemon
