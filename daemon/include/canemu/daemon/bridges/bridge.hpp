// What every bridge is ([[bridge]], `canemu bridge add`): an emulated bus joined to something
// outside canemud through a node of its own, whatever carries the frames (the transport): a
// Linux CAN interface (socketcan_bridge.hpp) or LCM channels (lcm_bridge.hpp).
//
// The bridge's node (model::HostedNode: an SJA1000 on a classic bus, the CAN FD controller on a
// CAN FD bus) is an ordinary, acknowledging member of the bus. Frames that arrive from outside
// are queued and sent by that node: they arbitrate, wait for the bus and take their exact time
// like any node's. Frames the node receives from the bus go out through the transport; with
// `error_frames`, so do the node's bus errors, state changes and restarts.
//
// After bus-off the node stays off the bus (the kernel's default) unless `restart_ms` is set:
// then the bridge restarts it that long after the bus-off instant, as `ip link set canX type can
// restart-ms N` has a kernel driver do; restart() does it when asked (`ip link set canX type can
// restart`). Either way the node then waits for 128 sequences of 11 recessive bits (ISO
// 11898-1) before it is error-active and sends again; every restart is counted.
//
// Nothing is lost silently: every frame from outside that the bus cannot take (queue full, a
// frame the bus cannot carry, given up after bus-off) and everything the transport refused is
// counted in BridgeStats, which `canemu bridge list` and `canemu status` show.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <tl/expected.hpp>

#include "canemu/daemon/base/doorbell.hpp"
#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/base/reject_log.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/ipc/channel_message.hpp"

namespace canemu::daemon {

enum class BridgeKind : uint8_t { socketcan = 0, lcm = 1, dds = 2 };

// Why something from outside was rejected (BridgeStats::rejected), as counted by reason; the
// numbers are ipc::kBridgeReject*'s.
enum class BridgeReject : uint8_t {
  not_a_frame = 0,    // another type, bytes that do not decode (DDS: a sample Cyclone could not)
  bad_fields = 1,     // an identifier or DLC out of range, a length other than the DLC's
  fd_on_classic = 2,  // a CAN FD frame for a classic bus
  error_frame = 3,    // an error frame (ROS 2's is_error, SocketCAN's CAN_ERR_FLAG)
};
inline constexpr std::size_t kBridgeRejectReasons = 4;
inline constexpr std::array<std::string_view, kBridgeRejectReasons> kBridgeRejectNames = {
    "not_a_frame", "bad_fields", "fd_on_classic_bus", "error_frame"};

// The counters' names are the SocketCAN bridge's; "interface" is whatever the transport
// reaches (for LCM: its channels).
struct BridgeStats {
  uint64_t to_interface = 0;          // frames of the bus written out (LCM: published on FRAMES)
  uint64_t from_interface = 0;        // frames from outside sent on the bus
  uint64_t error_frames = 0;          // errors, states and restarts written out
  uint64_t to_interface_dropped = 0;  // the transport refused them (buffer full, down)
  uint64_t queue_dropped = 0;         // from outside while the queue was full
  uint64_t rejected = 0;              // from outside but not a frame this bus carries (FD on a
                                      // classic bus, error frames, bad lengths, identifiers)
  uint64_t tx_failed = 0;             // queued but given up by the node (bus-off)
  uint64_t kernel_dropped = 0;        // dropped by the kernel before the bridge read them (its
                                      // socket's receive buffer was full: SO_RXQ_OVFL)
  uint64_t restarts = 0;              // restarts after bus-off, automatic and asked for
  uint64_t received = 0;              // everything that arrived from outside (frames or not)
};

struct BridgeOptions {
  std::string bus;
  std::string interface;  // SocketCAN: the interface
  bool error_frames = false;
  bool fd = false;               // the bus is a CAN FD bus: CAN FD frames both ways
  uint32_t queue_frames = 1024;  // frames from outside waiting for the bus
  uint32_t restart_ms = 0;       // restart after bus-off after this long; 0: stay bus-off
  BridgeKind kind = BridgeKind::socketcan;
  std::string url;             // LCM: the provider URL; DDS: domain/partition (dds_locator)
  std::string channel_prefix;  // LCM: the channels' common prefix; DDS: the topics' common prefix
};

class Bridge;

// A frame as a message transport (LCM, DDS) carries it: its fields one by one.
struct FrameFields {
  int64_t id = 0;
  bool extended = false, remote = false, fd = false, brs = false, esi = false;
  int dlc = 0;
  int len = 0;  // data bytes the message says it has
  const uint8_t* data = nullptr;
};
// Those fields as a frame for a bridge to send; what is wrong if they disagree (an identifier or
// DLC out of range, a length other than the DLC's). Bridge::offer() checks the rest.
Result<ipc::ChannelMessage> frame_message(const FrameFields& f);

// Why a bridge cannot open when this process may not create sockets of `family` (AF_CAN for
// SocketCAN; AF_INET for LCM, DDS and [distributed]): socket() fails with EAFNOSUPPORT where a
// sandbox refuses the family (canemud.service without the drop-in that allows it,
// docs/security.md) or the kernel lacks it. Short enough for an error reply with the interface's
// name before it. Nothing when such a socket opens.
Result<> refused_family(int family);

// What a transport did with something the bridge gave it.
enum class Delivery : uint8_t {
  sent,     // counted as written
  refused,  // counted as dropped (to_interface_dropped)
  none,     // the transport has no form for it: not counted
};

// The far side of a bridge: reads what arrives from outside and writes out what happens on the
// bus. Never blocks.
class BridgeTransport {
 public:
  virtual ~BridgeTransport() = default;
  // Readable when something arrived from outside (in canemud's epoll loop).
  virtual int fd() const = 0;
  // How messages name the bridge: "bridge on vcan0".
  virtual std::string name() const = 0;
  // Reads what arrived (a bounded amount, so the loop gets its turn), handing each message to
  // bridge.offer().
  virtual void receive(Bridge& bridge) = 0;
  // Frames the bridge's own node sent go out too (as frame(..., own = true)).
  virtual bool carries_own_frames() const { return false; }
  virtual Delivery frame(model::SimTime at, const model::Frame& frame, bool own) = 0;
  virtual Delivery error(const model::BusErrorEvent& event, model::ErrorState state) = 0;
  virtual Delivery state(model::SimTime at, model::ErrorState state, uint16_t tec,
                         uint16_t rec) = 0;
  // The node was restarted from bus-off.
  virtual Delivery restarted(model::SimTime at, uint16_t tec, uint16_t rec) = 0;
};

class Bridge final : private model::ControllerEvents, public Doorbell {
 public:
  // Starts `node` (a spare node of bus `bus`, acknowledging) with `settings`, joined to the
  // outside through `transport`.
  static std::unique_ptr<Bridge> start(BridgeOptions options, std::size_t bus,
                                       model::HostedNode& node,
                                       const model::HostedNodeSettings& settings,
                                       std::unique_ptr<BridgeTransport> transport);
  ~Bridge() override;  // the node leaves the bus
  Bridge(const Bridge&) = delete;
  Bridge& operator=(const Bridge&) = delete;

  const BridgeOptions& options() const { return options_; }
  BridgeKind kind() const { return options_.kind; }
  std::size_t bus() const { return bus_; }
  const BridgeStats& stats() const { return stats_; }
  std::size_t queued() const { return queue_.size(); }
  model::HostedNode& node() { return node_; }
  const model::HostedNode& node() const { return node_; }
  BridgeTransport& transport() { return *transport_; }

  // The transport's descriptor: readable when something arrived from outside.
  int doorbell_fd() const override { return transport_->fd(); }
  // Reads what arrived into the queue; the node takes the next frame if it is idle. Frames are
  // placed at the current simulated instant.
  void kick() override;
  bool broken() const override { return false; }

  // Restarts the node from bus-off now; a bad_argument error otherwise (it is not bus-off, or it
  // restarts already and waits for the recessive bits).
  Result<> restart();

  // For the transport: a message arrived from outside, as a frame to send, or nullptr when it
  // was no frame at all. Anything the bus cannot carry is counted and skipped, with the reason.
  void offer(const ipc::ChannelMessage* m);
  // For the transport: `n` messages arrived that are no frame to send, for reason `why`;
  // `detail` says which rule (and where from, when the transport knows): counted as received
  // and rejected, logged (rate-limited), and kept as the last reason.
  void reject(BridgeReject why, const std::string& detail, uint64_t n = 1);
  // Rejections by reason (kBridgeRejectNames) and the last one with its details.
  const RejectLog<kBridgeRejectReasons>& rejections() const { return rejections_; }
  // For the transport: its own counters (kernel_dropped).
  BridgeStats& counters() { return stats_; }

 private:
  Bridge(BridgeOptions options, std::size_t bus, model::HostedNode& node,
         std::unique_ptr<BridgeTransport> transport)
      : options_(std::move(options)),
        bus_(bus),
        node_(node),
        transport_(std::move(transport)),
        rejections_(transport_->name(), kBridgeRejectNames) {}

  std::optional<model::TxFrame> next_tx();
  void count(Delivery d, uint64_t& counter);

  void frame_received(model::SimTime at, const model::Frame& frame, bool own) override;
  void frame_transmitted(model::SimTime at, const model::Frame& frame) override;
  void transmission_dropped(model::SimTime at, const model::Frame& frame) override;
  void bus_error(const model::BusErrorEvent& event) override;
  void state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                     uint16_t rec) override;

  void restart_after_bus_off();

  BridgeOptions options_;
  std::size_t bus_;
  model::HostedNode& node_;
  std::unique_ptr<BridgeTransport> transport_;
  std::deque<model::TxFrame> queue_;
  BridgeStats stats_;
  std::optional<model::EventId> restart_event_;  // the automatic restart, while due
  RejectLog<kBridgeRejectReasons> rejections_;
};

}  // namespace canemu::daemon
