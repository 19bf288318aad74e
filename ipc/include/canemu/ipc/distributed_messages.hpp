// The control protocol's messages about buses across hosts ([distributed], docs/distributed.md),
// for `canemu status` and `canemu metrics`: this daemon's name, DDS domain and partition, its
// counters of what went to and came from other daemons, the other daemons it heard (peers) and
// its buses that another daemon simulates (remote buses). Gathered with the others by
// protocol.hpp.
#pragma once

#include <cstddef>
#include <cstdint>

#include "canemu/ipc/protocol_core.hpp"

namespace canemu::ipc {

inline constexpr std::size_t kPeerPage = 16;       // peers in one reply
inline constexpr std::size_t kRemoteBusPage = 32;  // remote buses in one reply
inline constexpr std::size_t kPeerBuses = 8;       // bus names a PeerEntry carries
inline constexpr std::size_t kReasonSize = 96;     // reasons are cut to 95 bytes
inline constexpr std::size_t kPartitionSize = 64;  // a DDS partition: up to 63 bytes
inline constexpr std::size_t kStateSize = 16;

// One page of the peers (from first_peer on) and of the remote buses (from first_bus on), each
// paged on its own as StatusRequest's buses and nodes.
struct PeerListRequest {
  MsgHeader header;
  uint16_t first_peer = 0;
  uint16_t first_bus = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(PeerListRequest) == 24);

// Another daemon of the installation, as this one heard it. The texts came from that daemon:
// canemud makes every byte outside printable ASCII '?'.
struct PeerEntry {
  char name[kNameSize] = {};
  char version[kNameSize] = {};   // canemu's version there
  char time[kNameSize] = {};      // its time mode: "realtime", "scaled:2", "stepped"
  char state[kStateSize] = {};    // "up", "gone", "refused"
  char reason[kReasonSize] = {};  // refused or gone: why
  uint16_t protocol = 0;          // of the DDS messages between daemons
  uint8_t bus_count = 0;          // names in `buses`, at most kPeerBuses
  uint8_t linked = 0;             // 1: a same-host link with it is up (0: DDS)
  uint32_t bus_total = 0;         // buses it simulates (more than bus_count: the first kPeerBuses)
  int64_t last_heard_ms = 0;      // milliseconds since its last heartbeat
  uint32_t hosted_nodes = 0;      // its nodes on this daemon's buses
  uint32_t reserved2 = 0;
  char buses[kPeerBuses][kNameSize] = {};
};
static_assert(sizeof(PeerEntry) ==
              3 * kNameSize + kStateSize + kReasonSize + 24 + kPeerBuses * kNameSize);

// A bus of this daemon that daemon `owner` simulates.
struct RemoteBusEntry {
  char bus[kNameSize] = {};
  char owner[kNameSize] = {};
  char state[kStateSize] = {};    // "attached", "waiting", "refused"
  char reason[kReasonSize] = {};  // waiting or refused: why
  uint32_t nodes = 0;             // this daemon's nodes on it
  uint32_t reserved = 0;
};
static_assert(sizeof(RemoteBusEntry) == 2 * kNameSize + kStateSize + kReasonSize + 8);

// Messages to and from other daemons since canemud started.
// Why messages were dropped or frames rejected: WireDistributedCounters::by_reason's order, and
// the names `canemu status --json` gives them (docs/distributed.md, "Status and counters").
inline constexpr std::size_t kNetDropReasons = 8;
inline constexpr const char* kNetDropNames[kNetDropReasons] = {
    "unknown_daemon", "not_accepted", "lost",        "no_node",
    "malformed",      "not_written",  "undecodable", "fd_on_classic_bus"};

struct WireDistributedCounters {
  uint64_t requests_sent = 0;      // to owners of this daemon's remote buses
  uint64_t requests_received = 0;  // from daemons with nodes on this daemon's buses
  uint64_t events_sent = 0;
  uint64_t events_received = 0;
  uint64_t dropped = 0;  // lost on the way, not taken by DDS, from no daemon accepted, for no node
  // Real and scaled time: events placed more than late_bound_ns after their instant (the owner's
  // time converted); stepped time: events applied after their instant had passed.
  uint64_t late = 0;
  uint64_t rejected = 0;      // frames of another daemon's node that its controller does not send
  int64_t late_max_ns = 0;    // the largest delay of an event seen, within the bound or beyond
  int64_t late_bound_ns = 0;  // the bound of `late` (real and scaled time)
  uint64_t by_reason[kNetDropReasons] = {};  // dropped and rejected, by reason
  char last_reason[kReasonSize] = {};        // the last one: the rule and the daemon
};
static_assert(sizeof(WireDistributedCounters) == 72 + 8 * kNetDropReasons + kReasonSize);

struct PeerListReply {
  MsgHeader header;
  uint8_t enabled = 0;  // 1: the daemon has [distributed]; 0: every other field is zero
  uint8_t reserved[3] = {};
  uint32_t domain = 0;  // DDS domain id
  char name[kNameSize] = {};
  char partition[kPartitionSize] = {};
  uint32_t heartbeat_ms = 0;
  uint32_t timeout_ms = 0;
  WireDistributedCounters counters;
  uint16_t peer_count = 0;  // in this page, at most kPeerPage
  uint16_t peer_total = 0;  // peers heard
  uint16_t first_peer = 0;  // index of peers[0] among all (the request's)
  uint16_t bus_count = 0;   // in this page, at most kRemoteBusPage
  uint16_t bus_total = 0;   // remote buses
  uint16_t first_bus = 0;
  uint32_t reserved2 = 0;
  PeerEntry peers[kPeerPage];
  RemoteBusEntry buses[kRemoteBusPage];
};
static_assert(sizeof(PeerListReply) ==
              16 + 8 + kNameSize + kPartitionSize + 8 + sizeof(WireDistributedCounters) + 16 +
                  kPeerPage * sizeof(PeerEntry) + kRemoteBusPage * sizeof(RemoteBusEntry));
static_assert(sizeof(PeerListReply) <= kMaxMessageSize);

}  // namespace canemu::ipc
