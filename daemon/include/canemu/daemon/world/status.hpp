// What the control protocol reports of the world: `canemu status` (buses with their load and
// counts, every device's nodes with their error state and counts) and the device list (the VCI
// device manager's view: configured adapters, then ephemeral devices). Both come in pages: a
// reply holds the entries from the first one asked for on, as many as it has room for, and
// says how many there are in all.
#pragma once

#include <cstddef>
#include <string>

#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

class Simulation;
class Bridge;

// A bridge's node in the NODE table: "socketcan:IFACE", "lcm:BUS", "dds:BUS".
std::string bridge_node_name(const Bridge& b);

void fill_status(const Simulation& sim, ipc::StatusReply& reply, std::size_t first_bus = 0,
                 std::size_t first_node = 0);
void fill_device_list(const Simulation& sim, ipc::DeviceListReply& reply, std::size_t first = 0);
// The recorders ([[recorder]]) with what they wrote and lost.
void fill_recorder_list(const Simulation& sim, ipc::RecorderListReply& reply,
                        std::size_t first = 0);
// The bridges (SocketCAN and LCM) with their node's state and their counts.
void fill_bridge_list(const Simulation& sim, ipc::BridgeListReply& reply, std::size_t first = 0);
// [distributed]: this daemon's name, domain, partition and counters, a page of the other
// daemons it heard (from first_peer on) and of its buses another daemon simulates (from
// first_bus on). Without [distributed], `enabled` 0 and nothing else.
void fill_peer_list(const Simulation& sim, ipc::PeerListReply& reply, std::size_t first_peer = 0,
                    std::size_t first_bus = 0);

}  // namespace canemu::daemon
