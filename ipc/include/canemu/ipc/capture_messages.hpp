// The control protocol's messages about canemud's recorders ([[recorder]]: their list with what
// they wrote and lost, for `canemu status`) and bridges, SocketCAN and LCM ([[bridge]]: added,
// removed, restarted after bus-off and listed at run time by `canemu bridge`). Gathered with the
// others by protocol.hpp.
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

inline constexpr std::size_t kRecorderPage = 32;  // the list comes in pages of this many
inline constexpr std::size_t kPathSize = 128;

// One page of the recorder list: recorders from `first` on.
struct RecorderListRequest {
  MsgHeader header;
  uint16_t first = 0;
  uint16_t reserved = 0;
  uint32_t reserved2 = 0;
};
static_assert(sizeof(RecorderListRequest) == 24);

struct RecorderEntry {
  char bus[kNameSize] = {};
  char path[kPathSize] = {};  // cut to 127 bytes
  uint8_t format = 0;         // CaptureFormat
  uint8_t errors = 0;         // error frames recorded too
  uint16_t reserved = 0;
  uint32_t rotations = 0;
  uint64_t frames = 0;  // written to disk
  uint64_t bytes = 0;   // in all files, headers included
  uint64_t lost = 0;    // frames failed writes took with them
  char error[96] = {};  // the last failure ("write /x.log: No space left on device"), or empty
};
static_assert(sizeof(RecorderEntry) == 32 + 128 + 8 + 24 + 96);

struct RecorderListReply {
  MsgHeader header;
  uint16_t count = 0;  // in this page
  uint16_t total = 0;  // recorders that exist
  uint16_t first = 0;  // index of recorders[0] among all (the request's)
  uint16_t reserved = 0;
  RecorderEntry recorders[kRecorderPage];
};
static_assert(sizeof(RecorderListReply) <= kMaxMessageSize);

inline constexpr std::size_t kBridgePage = 32;           // the list comes in pages of this many
inline constexpr uint32_t kMaxBridgeRestartMs = 60'000;  // as a channel's restart_ms
inline constexpr std::size_t kLcmUrlSize = 128;
inline constexpr std::size_t kLcmPrefixSize = 64;

// Why a bridge rejected what came from outside: BridgeEntry::rejected_by's order, and the names
// `canemu bridge list --json` gives them.
inline constexpr std::size_t kBridgeRejectReasons = 4;
inline constexpr const char* kBridgeRejectNames[kBridgeRejectReasons] = {
    "not_a_frame",        // another type, bytes that do not decode, a DDS sample Cyclone could not
    "bad_fields",         // an identifier or DLC out of range, a length other than the DLC's
    "fd_on_classic_bus",  // a CAN FD frame for a classic bus
    "error_frame"};       // an error frame
inline constexpr std::size_t kBridgeReasonSize = 96;  // texts are cut to 95 bytes

// BridgeAddRequest.kind and the others
inline constexpr uint8_t kBridgeSocketCan = 0;
inline constexpr uint8_t kBridgeLcm = 1;
inline constexpr uint8_t kBridgeDds = 2;

// Joins bus `bus` to the Linux CAN interface `interface` (a SocketCAN bridge), or to the LCM
// channels `channel_prefix`* on `url` (an LCM bridge; empty: the defaults), or to the DDS topics
// `channel_prefix`* at `url` = "DOMAIN/PARTITION", "+ros2" appended for ROS 2's topics too (a DDS
// bridge; empty: the defaults).
struct BridgeAddRequest {
  MsgHeader header;
  char bus[kNameSize] = {};
  char interface[kNameSize] = {};
  uint8_t error_frames = 0;  // 1: the bridge node's errors and states as CAN_ERR_* frames
  uint8_t kind = kBridgeSocketCan;
  uint8_t reserved[2] = {};
  uint32_t restart_ms = 0;  // restart the node this long after bus-off; 0: it stays bus-off
  char url[kLcmUrlSize] = {};
  char channel_prefix[kLcmPrefixSize] = {};
};
static_assert(sizeof(BridgeAddRequest) == 16 + 64 + 8 + 128 + 64);

// `warning`: what the bridge will not do although it was added (empty: nothing), for the user:
// a CAN FD bus on an interface whose MTU is not 72 (its FD frames cannot pass there).
inline constexpr std::size_t kBridgeWarningSize = 384;
struct BridgeAddReply {
  MsgHeader header;
  char warning[kBridgeWarningSize] = {};
};
static_assert(sizeof(BridgeAddReply) == 16 + kBridgeWarningSize);

// The SocketCAN bridge on `interface`, or the LCM bridge of bus `bus`.
struct BridgeRemoveRequest {
  MsgHeader header;
  char interface[kNameSize] = {};
  uint8_t kind = kBridgeSocketCan;
  uint8_t reserved[7] = {};
  char bus[kNameSize] = {};
};

struct BridgeRemoveReply {
  MsgHeader header;
};

// Restarts the bus-off node of the bridge on `interface` (as `ip link set canX type can
// restart` does); refused when the node is not bus-off or restarts already.
struct BridgeRestartRequest {
  MsgHeader header;
  char interface[kNameSize] = {};
  uint8_t kind = kBridgeSocketCan;  // kBridgeLcm: the LCM bridge of `bus`
  uint8_t reserved[7] = {};
  char bus[kNameSize] = {};
};

struct BridgeRestartReply {
  MsgHeader header;
};

// One page of the bridge list: bridges from `first` on.
struct BridgeListRequest {
  MsgHeader header;
  uint16_t first = 0;
  uint16_t reserved = 0;
  uint32_t reserved2 = 0;
};
static_assert(sizeof(BridgeListRequest) == 24);

struct BridgeEntry {
  char bus[kNameSize] = {};
  char interface[kNameSize] = {};
  uint8_t error_frames = 0;
  uint8_t state = 0;  // WireErrorState of the bridge's node
  uint16_t tec = 0;
  uint16_t rec = 0;
  uint8_t kind = kBridgeSocketCan;
  uint8_t reserved = 0;
  uint32_t queued = 0;      // frames from the interface waiting for the bus
  uint32_t restart_ms = 0;  // the automatic restart after bus-off; 0: none
  uint64_t to_interface = 0;
  uint64_t from_interface = 0;
  uint64_t error_frames_written = 0;
  uint64_t to_interface_dropped = 0;
  uint64_t queue_dropped = 0;
  uint64_t rejected = 0;
  uint64_t tx_failed = 0;
  uint64_t kernel_dropped = 0;  // dropped by the kernel before the bridge read them
  uint64_t restarts = 0;        // restarts after bus-off (automatic and asked for)
  // LCM: what arrived on TX (frames or not); the URL and the channels' prefix
  uint64_t received = 0;
  char url[kLcmUrlSize] = {};
  char channel_prefix[kLcmPrefixSize] = {};
  // `rejected` by reason, in the order of kBridgeRejectNames; the last rejection, why and where.
  uint64_t rejected_by[kBridgeRejectReasons] = {};
  char last_rejected[kBridgeReasonSize] = {};
};
static_assert(sizeof(BridgeEntry) ==
              64 + 16 + 80 + 128 + 64 + 8 * kBridgeRejectReasons + kBridgeReasonSize);

struct BridgeListReply {
  MsgHeader header;
  uint16_t count = 0;  // in this page
  uint16_t total = 0;  // bridges that exist
  uint16_t first = 0;  // index of bridges[0] among all (the request's)
  uint16_t reserved = 0;
  BridgeEntry bridges[kBridgePage];
};
static_assert(sizeof(BridgeListReply) <= kMaxMessageSize);

}  // namespace canemu::ipc
