// The requests of the VCI libraries to canemud (see vci_core.hpp): one link per process
// (client::DaemonLink), one request at a time, the connection dropped when it breaks and made
// again by the next call.
#include "vci_core.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <time.h>

#include <fmt/format.h>

namespace canemu::client::vci {

Library& Library::get() {
  static Library* lib = new Library;  // never destroyed: objects may outlive static teardown
  return *lib;
}

namespace {

// How canemu status names this process: the program (argv[0]'s last part), with its script or
// module for an interpreter ("python3 -m can.player", "python3 talk.py"), and the API: "(VCI)".
// Read from /proc/self/cmdline; "vci" when that cannot be read.
std::string client_name() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::vector<std::string> args;
  for (std::string arg; std::getline(in, arg, '\0');) {
    args.push_back(arg);
  }
  if (args.empty()) {
    return "vci";
  }
  const auto base = [](const std::string& path) {
    const std::size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
  };
  std::string name = base(args[0]);
  if (name.rfind("python", 0) == 0 && args.size() > 1) {
    if (args[1] == "-m" && args.size() > 2) {
      name += " -m " + args[2];
    } else if (args[1].empty() || args[1][0] != '-') {
      name += " " + base(args[1]);
    }
  }
  const std::string suffix = " (VCI)";
  const std::size_t room = ipc::kNameSize - 1 - suffix.size();
  return (name.size() > room ? name.substr(0, room) : name) + suffix;
}

// canemud cannot be reached: why, as the detail.
HRESULT unreachable(const ipc::IpcError& e) {
  set_detail(e.message);
  return VCI_E_DISCONNECTED;
}

// A request that failed: its VCI result (the connection is dropped if it broke).
HRESULT failed(DaemonLink::Turn& turn, const ipc::IpcError& e) {
  set_detail(e.message);
  if (e.message.rfind("canemud: ", 0) == 0) {
    return VCI_E_UNEXPECTED;  // the daemon refused the request; the connection is fine
  }
  turn.drop(e.message);  // gone: the next call connects again
  return VCI_E_DISCONNECTED;
}

}  // namespace

Library::Library() : link_(client_name()) {}

HRESULT Library::connect() {
  auto up = link_.connect();
  return up ? VCI_OK : unreachable(up.error());
}

HRESULT Library::reconnect(const std::string& socket) {
  link_.reconnect(socket, "the connection to canemud it was opened on was closed by canemuConnect");
  return connect();
}

HRESULT Library::link(uint64_t generation, std::string& why) {
  if (auto gone = link_.lost(generation)) {
    why = std::move(*gone);
    return VCI_E_DISCONNECTED;
  }
  return VCI_OK;
}

HRESULT Library::step(int64_t ns, int64_t& now) {
  auto turn = link_.turn();
  if (!turn) {
    return unreachable(turn.error());
  }
  // canemud takes steps of up to a minute; a longer one goes in pieces.
  constexpr int64_t kMaxStep = int64_t{60} * 1'000'000'000;
  while (ns > 0) {
    auto m = ipc::make_message<ipc::TimeStepRequest>();
    m.step_ns = std::min(ns, kMaxStep);
    auto r = turn->connection().call<ipc::TimeStepRequest, ipc::TimeStepReply>(m, -1);
    if (!r) {
      return r.error().message.find("not_stepped") != std::string::npos
                 ? (set_detail(r.error().message), VCI_E_INVALID_STATE)
                 : failed(*turn, r.error());
    }
    ns -= m.step_ns;
    now = r->sim_time_ns;
  }
  return VCI_OK;
}

HRESULT Library::call(ipc::VciRequest& request, ipc::VciReply& reply,
                      std::vector<ipc::UniqueFd>* fds, uint64_t* generation) {
  auto turn = link_.turn();
  if (!turn) {
    return unreachable(turn.error());
  }
  if (generation != nullptr) {
    *generation = turn->generation();
  }
  request.header = ipc::make_message<ipc::VciRequest>().header;
  auto r = turn->connection().call<ipc::VciRequest, ipc::VciReply>(request);
  if (!r) {
    return failed(*turn, r.error());
  }
  reply = *r;
  if (fds != nullptr) {
    *fds = turn->connection().take_fds();
  }
  return reply.hresult;
}

HRESULT Library::list_devices(std::vector<DeviceDesc>& out, uint32_t* generation) {
  auto turn = link_.turn();
  if (!turn) {
    return unreachable(turn.error());
  }
  auto r = client::fetch_device_list(turn->connection());
  if (!r) {
    return failed(*turn, r.error());
  }
  out.clear();
  for (const ipc::DeviceEntry& e : r->devices) {
    const auto model = static_cast<ipc::WireDeviceModel>(e.model);
    if (e.vci_id == 0 || (model != ipc::WireDeviceModel::ixxat_usb_to_can &&
                          model != ipc::WireDeviceModel::ixxat_usb_to_can_fd)) {
      continue;  // not an adapter the VCI sees (an ephemeral channel's device, an X-CAN-2i)
    }
    DeviceDesc d;
    d.name = ipc::name_of(e.name);
    d.vci_id = e.vci_id;
    d.hardware_id = ipc::name_of(e.hardware_id);
    d.model = e.model;
    for (uint8_t k = 0; k < e.controller_count && k < ipc::kMaxDeviceControllers; ++k) {
      const auto kind = static_cast<ipc::WireControllerKind>(e.controller_fd[k]);
      d.controller_fd.push_back(kind == ipc::WireControllerKind::can_fd);
      d.controller_lin.push_back(kind == ipc::WireControllerKind::lin);
      d.buses.push_back(ipc::name_of(e.buses[k]));
    }
    d.ephemeral = e.ephemeral != 0;
    d.epoch_ns = e.epoch_ns;
    out.push_back(std::move(d));
  }
  if (generation != nullptr) {
    *generation = r->generation;
  }
  return VCI_OK;
}

HRESULT Library::status(client::Status& out) {
  auto turn = link_.turn();
  if (!turn) {
    return unreachable(turn.error());
  }
  auto r = client::fetch_status(turn->connection());
  if (!r) {
    return failed(*turn, r.error());
  }
  out = std::move(*r);
  return VCI_OK;
}

HRESULT Library::can_nodes(const client::CanNodeRequests& requests, ipc::CanNodeReply& reply) {
  auto turn = link_.turn();
  if (!turn) {
    return unreachable(turn.error());
  }
  client::CanNodeOutcome r = client::call_can_nodes(turn->connection(), requests);
  if (r.error) {
    return failed(*turn, *r.error);
  }
  if (!r.reply) {
    set_call_detail(VCI_E_INVALIDARG, r.refused);
    return VCI_E_INVALIDARG;
  }
  reply = *r.reply;
  return VCI_OK;
}

HRESULT Library::wait_device_change(uint32_t generation, int timeout_ms) {
  // A connection of its own: waiting must not hold the shared one.
  auto c = link_.open_another("vci-enum");
  if (!c) {
    return unreachable(c.error());
  }
  if (auto s = c->subscribe(ipc::kEventDevices); !s) {
    return unreachable(s.error());
  }
  uint32_t now = 0;
  std::vector<DeviceDesc> ignored;
  if (HRESULT hr = list_devices(ignored, &now); hr != VCI_OK) {
    return hr;
  }
  if (now != generation) {
    return VCI_OK;  // changed before we subscribed
  }
  return c->next_notification(timeout_ms) ? VCI_OK : VCI_E_TIMEOUT;
}

}  // namespace canemu::client::vci
