#include "canemu/client/lists.hpp"

#include <algorithm>
#include <memory>
#include <utility>

namespace canemu::client {

namespace {

// Pages of one list that changed under us this often in a row: give up.
constexpr int kAttempts = 8;

IpcError kept_changing(const char* what) {
  return IpcError{0, std::string(what) + " kept changing while it was read; try again"};
}

}  // namespace

std::string Status::bus_name(const ipc::StatusNode& node) const {
  return node.bus < buses.size() ? ipc::name_of(buses[node.bus].name) : std::string("?");
}

Result<Status> fetch_status(Connection& c) {
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    Status s;
    bool changed = false;
    std::size_t bus_total = 0;
    std::size_t node_total = 0;
    for (bool first_page = true;; first_page = false) {
      auto m = ipc::make_message<ipc::StatusRequest>();
      m.first_bus = static_cast<uint16_t>(std::min(s.buses.size(), bus_total));
      m.first_node = static_cast<uint16_t>(std::min(s.nodes.size(), node_total));
      auto r = c.call<ipc::StatusRequest, ipc::StatusReply>(m);
      if (!r) {
        return tl::unexpected(r.error());
      }
      if (first_page) {
        s.sim_time_ns = r->sim_time_ns;
        s.time_scale = r->time_scale;
        s.time_mode = r->time_mode;
        s.client_count = r->client_count;
        s.ring_bytes = r->ring_bytes;
        s.lag_ns = r->lag_ns;
        s.achieved_scale = r->achieved_scale;
        s.pacing = r->pacing;
        s.generation = r->generation;
        bus_total = r->bus_total;
        node_total = r->node_total;
      } else if (r->generation != s.generation || r->bus_total != bus_total ||
                 r->node_total != node_total) {
        changed = true;
        break;
      }
      const uint16_t buses = std::min<uint16_t>(r->bus_count, ipc::kStatusPageBuses);
      const uint16_t nodes = std::min<uint16_t>(r->node_count, ipc::kStatusPageNodes);
      s.buses.insert(s.buses.end(), r->buses, r->buses + buses);
      s.nodes.insert(s.nodes.end(), r->nodes, r->nodes + nodes);
      const bool done = s.buses.size() >= bus_total && s.nodes.size() >= node_total;
      if (done || (buses == 0 && nodes == 0)) {  // nothing more: never ask forever
        break;
      }
    }
    if (!changed) {
      return s;
    }
  }
  return tl::unexpected(kept_changing("the status"));
}

namespace {

// Page after page of a list without a generation, `Reply::*entries` holding up to `page`.
template <class Request, class Reply, class Entry, std::size_t N>
Result<std::vector<Entry>> every_page(Connection& c, Entry (Reply::*entries)[N]) {
  std::vector<Entry> all;
  while (true) {
    auto m = ipc::make_message<Request>();
    m.first = static_cast<uint16_t>(all.size());
    auto r = c.template call<Request, Reply>(m);
    if (!r) {
      return tl::unexpected(r.error());
    }
    const std::size_t count = std::min<std::size_t>(r->count, N);
    const Entry* got = (*r).*entries;
    all.insert(all.end(), got, got + count);
    if (count == 0 || all.size() >= r->total) {
      return all;
    }
  }
}

// Page after page of a list with a generation (Reply::generation): pages of different
// generations do not fit together, and the reading starts over. The generation and the entries.
template <class Request, class Reply, class Entry, std::size_t N>
Result<std::pair<uint32_t, std::vector<Entry>>> one_generation(Connection& c,
                                                               Entry (Reply::*entries)[N],
                                                               const char* what) {
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    std::vector<Entry> all;
    uint32_t generation = 0;
    bool changed = false;
    for (bool first_page = true;; first_page = false) {
      auto m = ipc::make_message<Request>();
      m.first = static_cast<uint16_t>(all.size());
      auto r = c.template call<Request, Reply>(m);
      if (!r) {
        return tl::unexpected(r.error());
      }
      if (first_page) {
        generation = r->generation;
      } else if (r->generation != generation) {
        changed = true;
        break;
      }
      const std::size_t count = std::min<std::size_t>(r->count, N);
      const Entry* got = (*r).*entries;
      all.insert(all.end(), got, got + count);
      if (count == 0 || all.size() >= r->total) {
        break;
      }
    }
    if (!changed) {
      return std::make_pair(generation, std::move(all));
    }
  }
  return tl::unexpected(kept_changing(what));
}

}  // namespace

Result<DeviceList> fetch_device_list(Connection& c) {
  auto r = one_generation<ipc::DeviceListRequest, ipc::DeviceListReply>(
      c, &ipc::DeviceListReply::devices, "the device list");
  if (!r) {
    return tl::unexpected(r.error());
  }
  return DeviceList{r->first, std::move(r->second)};
}

Result<std::vector<ipc::ClientEntry>> fetch_client_list(Connection& c) {
  // Clients have no generation: one that comes or goes between pages may be missed or listed
  // twice, which a list of who is connected right now can live with.
  return every_page<ipc::ClientListRequest, ipc::ClientListReply>(c,
                                                                  &ipc::ClientListReply::clients);
}

Result<std::vector<ipc::RecorderEntry>> fetch_recorder_list(Connection& c) {
  return every_page<ipc::RecorderListRequest, ipc::RecorderListReply>(
      c, &ipc::RecorderListReply::recorders);
}

Result<std::vector<ipc::BridgeEntry>> fetch_bridge_list(Connection& c) {
  return every_page<ipc::BridgeListRequest, ipc::BridgeListReply>(c,
                                                                  &ipc::BridgeListReply::bridges);
}

Result<std::vector<ipc::FaultEntry>> fetch_fault_list(Connection& c) {
  auto r = one_generation<ipc::FaultListRequest, ipc::FaultListReply>(
      c, &ipc::FaultListReply::faults, "the fault list");
  if (!r) {
    return tl::unexpected(r.error());
  }
  return std::move(r->second);
}

Result<PeerList> fetch_peer_list(Connection& c) {
  PeerList list;
  std::size_t peer_total = 0;
  std::size_t bus_total = 0;
  for (bool first_page = true;; first_page = false) {
    auto m = ipc::make_message<ipc::PeerListRequest>();
    m.first_peer = static_cast<uint16_t>(std::min(list.peers.size(), peer_total));
    m.first_bus = static_cast<uint16_t>(std::min(list.remote_buses.size(), bus_total));
    auto r = c.call<ipc::PeerListRequest, ipc::PeerListReply>(m);
    if (!r) {
      return tl::unexpected(r.error());
    }
    if (first_page) {
      list.enabled = r->enabled != 0;
      list.name = ipc::printable_name_of(r->name);
      list.domain = r->domain;
      list.partition = ipc::printable_name_of(r->partition);
      list.heartbeat_ms = r->heartbeat_ms;
      list.timeout_ms = r->timeout_ms;
      list.counters = r->counters;
    }
    peer_total = r->peer_total;
    bus_total = r->bus_total;
    const uint16_t peers = std::min<uint16_t>(r->peer_count, ipc::kPeerPage);
    const uint16_t buses = std::min<uint16_t>(r->bus_count, ipc::kRemoteBusPage);
    list.peers.insert(list.peers.end(), r->peers, r->peers + peers);
    list.remote_buses.insert(list.remote_buses.end(), r->buses, r->buses + buses);
    const bool done = list.peers.size() >= peer_total && list.remote_buses.size() >= bus_total;
    if (done || (peers == 0 && buses == 0)) {  // nothing more: never ask forever
      return list;
    }
  }
}

}  // namespace canemu::client
