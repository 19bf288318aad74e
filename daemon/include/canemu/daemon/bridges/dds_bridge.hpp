// A DDS bridge ([[bridge]] kind = "dds", `canemu bridge add BUS --dds`): an emulated bus and DDS
// topics joined through a node of its own (bridge.hpp), on Eclipse Cyclone DDS. docs/bridges.md.
//
// Topics (types in ddstypes/canemu_dds.idl), all starting with the bridge's prefix (default
// canemu/<bus>/), in the bridge's DDS domain and partition (default 0 and "canemu"):
//   <prefix>frames  canemu::dds::Frame: every frame of the bus at the end of its EOF, those the
//                   bridge's node sent for <prefix>tx included (from_tx)
//   <prefix>errors  canemu::dds::BusError: the bridge node's bus errors
//   <prefix>states  canemu::dds::NodeState: its error state changes and restarts after bus-off
//   <prefix>tx      canemu::dds::Frame from programs: queued and sent by the bridge's node
// With ros2, also ROS 2's can_msgs/msg/Frame (ddstypes/ros2_can_msgs.idl) on the topics of
// ros2_socketcan as ROS 2's Cyclone DDS middleware names them, in the default partition:
//   rt/<bus>/from_can_bus  every classic frame of the bus (CAN FD frames have no form there)
//   rt/<bus>/to_can_bus    frames for the bridge's node to send
//
// QoS: reliable and volatile; the writers keep the last 64 samples (writing never waits: a
// reader that falls behind loses the oldest, as DDS defines), the readers keep all up to 1024
// (a writer that outruns canemud is held back by DDS's flow control, never dropped unseen). Cyclone
// delivers on threads of its own; a listener rings an eventfd that wakes canemud's loop, which then
// takes what arrived (a bounded amount per turn).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/bridges/bridge.hpp"
#include "canemu/daemon/config/names.hpp"

namespace canemu::daemon {

inline constexpr uint32_t kDdsDepth = 64;            // keep-last depth of the bridge's writers
inline constexpr uint32_t kDdsReaderSamples = 1024;  // what the bridge's readers hold at most

struct DdsOptions {
  uint32_t domain = 0;
  std::string partition{kDefaultDdsPartition};
  std::string topic_prefix;  // canemu/<bus>/ if empty
  bool ros2 = false;
};

// How bridge lists show where a DDS bridge is: "DOMAIN/PARTITION", "+ros2" when it has the ROS 2
// topics ("0/canemu+ros2"); and back.
std::string dds_locator(const DdsOptions& o);
std::optional<DdsOptions> parse_dds_locator(std::string_view locator);
// canemud was built with Cyclone DDS.
bool dds_available();

// The DDS transport of bus `bus`; the error says why not (built without DDS, a domain Cyclone
// cannot create, ...).
Result<std::unique_ptr<BridgeTransport>> open_dds(const std::string& bus,
                                                  const DdsOptions& options);

}  // namespace canemu::daemon
