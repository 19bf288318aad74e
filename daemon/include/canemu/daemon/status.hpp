// What the control protocol reports of the world: `canemu status` (buses with their load and
// counts, every device's nodes with their error state and counts) and the device list (the VCI
// device manager's view: configured adapters, then ephemeral devices). Entries beyond the
// replies' fixed arrays are left out; the device list's total counts them all.
#pragma once

#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

class Simulation;

void fill_status(const Simulation& sim, ipc::StatusReply& reply);
void fill_device_list(const Simulation& sim, ipc::DeviceListReply& reply);
// The recorders ([[recorder]]) with what they wrote and lost.
void fill_recorder_list(const Simulation& sim, ipc::RecorderListReply& reply);
// The bridges (SocketCAN and LCM) with their node's state and their counts.
void fill_bridge_list(const Simulation& sim, ipc::BridgeListReply& reply);

}  // namespace canemu::daemon
