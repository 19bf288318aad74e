// The daemon's status and its lists of devices, clients, recorders, bridges and other daemons
// ([distributed]) whole: each
// comes in pages (the requests name the first entry they want); these ask for page after page
// until they have every entry. A node or device that comes or goes meanwhile
// (the generation changes) makes them start over, so the pages always fit together.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::client {

struct Status {
  // Simulated time, time mode, clients, ring memory, lag and achieved scale: the first page's.
  int64_t sim_time_ns = 0;
  double time_scale = 1.0;
  uint8_t time_mode = 0;  // ipc::WireTimeMode
  uint16_t client_count = 0;
  uint64_t ring_bytes = 0;
  int64_t lag_ns = 0;
  double achieved_scale = 0.0;
  ipc::WirePacing pacing;  // real and scaled time: how late canemud ran things
  uint32_t generation = 0;
  std::vector<ipc::StatusBus> buses;
  std::vector<ipc::StatusNode> nodes;  // a node's `bus` indexes `buses`

  // The name of a node's bus; "?" if it has none.
  std::string bus_name(const ipc::StatusNode& node) const;
};

struct DeviceList {
  uint32_t generation = 0;
  std::vector<ipc::DeviceEntry> devices;
};

Result<Status> fetch_status(Connection& c);
Result<DeviceList> fetch_device_list(Connection& c);
Result<std::vector<ipc::ClientEntry>> fetch_client_list(Connection& c);
// Recorders and bridges have no generation either: one added or removed between pages may be
// missed or listed twice.
Result<std::vector<ipc::RecorderEntry>> fetch_recorder_list(Connection& c);
Result<std::vector<ipc::BridgeEntry>> fetch_bridge_list(Connection& c);
// The faults applied, in the order they were. A load between pages adds at the end; cleared
// scenarios forgotten meanwhile (the generation changes) make it start over.
Result<std::vector<ipc::FaultEntry>> fetch_fault_list(Connection& c);

// [distributed]: this daemon's name, domain, partition and counters (the first page's), every
// other daemon it heard and every bus of it that another daemon simulates. Without
// [distributed], `enabled` false and the lists empty. No generation either: a daemon heard for
// the first time between pages may make another be missed or listed twice (peers come sorted
// by name; none is ever forgotten, a daemon that left is only marked gone).
struct PeerList {
  bool enabled = false;
  std::string name;
  uint32_t domain = 0;
  std::string partition;
  uint32_t heartbeat_ms = 0;
  uint32_t timeout_ms = 0;
  ipc::WireDistributedCounters counters;
  std::vector<ipc::PeerEntry> peers;
  std::vector<ipc::RemoteBusEntry> remote_buses;
};
Result<PeerList> fetch_peer_list(Connection& c);

}  // namespace canemu::client
