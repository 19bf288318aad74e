// A SocketCAN bridge ([[bridge]] kind = "socketcan", `canemu bridge add`): an emulated bus and a
// Linux CAN interface (vcan, vxcan or a real adapter) joined through a node of its own
// (bridge.hpp: the node, its queue, restarts after bus-off and the counters).
//
// Frames that programs write on the interface are queued and sent by the bridge's node. Frames
// the node receives from the bus are written to the interface as struct can_frame /
// canfd_frame. With `error_frames`, the node's bus errors and state changes go to the interface
// too, as CAN_ERR_* frames (ipc/socketcan.hpp), and every restart after bus-off as the kernel's
// CAN_ERR_RESTARTED frame.
//
// No loops: the node never receives its own frames, and the socket (CAN_RAW, own messages not
// received) never reads back what it wrote; two bridges on one interface are refused.
//
// The kernel's senders never see a refusal, so what the bus cannot take and every frame the
// interface refused (socket buffer full, interface down) is counted in BridgeStats.
//
// The socket part is thin: the transport reads and writes whole frames on a descriptor, which is
// a CAN_RAW socket in canemud (open_can_raw) and one end of a SOCK_SEQPACKET pair in tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/bridges/bridge.hpp"
#include "canemu/ipc/socketcan.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::daemon {

// A SocketCAN bridge is a Bridge over a SocketCanTransport.
using SocketCanBridge = Bridge;

class SocketCanTransport final : public BridgeTransport {
 public:
  // `port`: the interface's socket, non-blocking.
  SocketCanTransport(std::string interface, ipc::UniqueFd port)
      : interface_(std::move(interface)), port_(std::move(port)) {}

  int fd() const override { return port_.get(); }
  std::string name() const override { return "bridge on " + interface_; }
  // Reads what the socket holds (at most kMaxReadsPerKick frames).
  void receive(Bridge& bridge) override;
  Delivery frame(model::SimTime at, const model::Frame& frame, bool own) override;
  Delivery error(const model::BusErrorEvent& event, model::ErrorState state) override;
  Delivery state(model::SimTime at, model::ErrorState state, uint16_t tec, uint16_t rec) override;
  Delivery restarted(model::SimTime at, uint16_t tec, uint16_t rec) override;

 private:
  Delivery write_out(const ipc::ChannelMessage& m);
  Delivery write_frame(const ipc::socketcan::Frame& f);

  static constexpr int kMaxReadsPerKick = 256;
  std::string interface_;
  ipc::UniqueFd port_;
};

// What the bridge makes of `size` bytes read from the interface's socket, for a CAN FD bus
// (`fd_bus`) or a classic one: the frame to send, or why the bus cannot carry it (the frame in
// candump's text and the rule): a read that is no struct can_frame or canfd_frame, an error
// frame (the interface's own controller's report, no frame for a bus), a CAN FD frame on a
// classic bus, a CAN FD remote frame, a length above 8 (classic) or 64 (FD). A CAN FD length
// between two DLCs' lengths is sent with the next DLC (ipc::socketcan::to_message).
struct InterfaceReject {
  BridgeReject why;
  std::string detail;  // "the CAN FD frame 123##1AABB (the bus is a classic CAN bus)"
};
tl::expected<ipc::ChannelMessage, InterfaceReject> frame_from_interface(const uint8_t* bytes,
                                                                        std::size_t size,
                                                                        bool fd_bus);

// A CAN_RAW socket bound to `interface`, non-blocking and close-on-exec, that reads CAN FD frames
// and every error class whatever the bus (so that what the bus cannot carry arrives and is
// counted as rejected, never lost unseen); the error names the interface and the failing call.
Result<ipc::UniqueFd> open_can_raw(const std::string& interface);

// What `canemu bridge add` and canemud's log say when a CAN FD bus (`fd_bus`) is bridged to an
// interface whose MTU (`mtu`) is not CANFD_MTU: its FD frames cannot be written there or sent
// from there. Nothing otherwise.
std::optional<std::string> mtu_warning(const std::string& interface, const std::string& bus,
                                       bool fd_bus, int mtu);

// The MTU of `interface` (SIOCGIFMTU on the bridge's socket `fd`); nothing when it cannot be read.
std::optional<int> interface_mtu(int fd, const std::string& interface);

}  // namespace canemu::daemon
