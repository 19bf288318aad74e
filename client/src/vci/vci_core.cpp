// The requests of the VCI libraries to canemud (see vci_core.hpp): one connection per
// process, serialized on one mutex, dropped when it breaks and made again by the next call.
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

HRESULT Library::connect() {
  std::lock_guard lock(mutex_);
  return connect_locked();
}

HRESULT Library::failed(const ipc::IpcError& e) {
  set_detail(e.message);
  if (e.message.rfind("canemud: ", 0) == 0) {
    return VCI_E_UNEXPECTED;  // the daemon refused the request; the connection is fine
  }
  drop_locked(e.message);  // gone: the next call connects again
  return VCI_E_DISCONNECTED;
}

void Library::drop_locked(std::string why) {
  if (connection_) {
    connection_.reset();
    lost_reason_ = std::move(why);
  }
}

HRESULT Library::reconnect(const std::string& socket) {
  std::lock_guard lock(mutex_);
  drop_locked("the connection to canemud it was opened on was closed by canemuConnect");
  socket_ = socket;
  return connect_locked();
}

HRESULT Library::link(uint64_t generation, std::string& why) {
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) {
    return VCI_OK;
  }
  if (generation == generation_ && connection_) {
    auto gone = connection_->lost();
    if (!gone) {
      return VCI_OK;
    }
    drop_locked(gone->message);
  }
  why = generation == generation_ ? lost_reason_
                                  : "the connection to canemud it was opened on is closed";
  return VCI_E_DISCONNECTED;
}

HRESULT Library::step(int64_t ns, int64_t& now) {
  std::lock_guard lock(mutex_);
  if (HRESULT hr = connect_locked(); hr != VCI_OK) {
    return hr;
  }
  // canemud takes steps of up to a minute; a longer one goes in pieces.
  constexpr int64_t kMaxStep = int64_t{60} * 1'000'000'000;
  while (ns > 0) {
    auto m = ipc::make_message<ipc::TimeStepRequest>();
    m.step_ns = std::min(ns, kMaxStep);
    auto r = connection_->call<ipc::TimeStepRequest, ipc::TimeStepReply>(m, -1);
    if (!r) {
      return r.error().message.find("not_stepped") != std::string::npos
                 ? (set_detail(r.error().message), VCI_E_INVALID_STATE)
                 : failed(r.error());
    }
    ns -= m.step_ns;
    now = r->sim_time_ns;
  }
  return VCI_OK;
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

}  // namespace

HRESULT Library::connect_locked() {
  if (connection_) {
    return VCI_OK;
  }
  auto c = Connection::open(ipc::socket_path(socket_), client_name());
  if (!c) {
    set_detail(c.error().message);
    return VCI_E_DISCONNECTED;
  }
  connection_.emplace(std::move(*c));
  ++generation_;
  lost_reason_.clear();
  return VCI_OK;
}

HRESULT Library::call(ipc::VciRequest& request, ipc::VciReply& reply,
                      std::vector<ipc::UniqueFd>* fds, uint64_t* generation) {
  std::lock_guard lock(mutex_);
  if (HRESULT hr = connect_locked(); hr != VCI_OK) {
    return hr;
  }
  if (generation != nullptr) {
    *generation = generation_;
  }
  request.header = ipc::make_message<ipc::VciRequest>().header;
  auto r = connection_->call<ipc::VciRequest, ipc::VciReply>(request);
  if (!r) {
    return failed(r.error());
  }
  reply = *r;
  if (fds != nullptr) {
    *fds = connection_->take_fds();
  }
  return reply.hresult;
}

HRESULT Library::list_devices(std::vector<DeviceDesc>& out, uint32_t* generation) {
  std::lock_guard lock(mutex_);
  if (HRESULT hr = connect_locked(); hr != VCI_OK) {
    return hr;
  }
  auto r = client::fetch_device_list(*connection_);
  if (!r) {
    return failed(r.error());
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
  std::lock_guard lock(mutex_);
  if (HRESULT hr = connect_locked(); hr != VCI_OK) {
    return hr;
  }
  auto r = client::fetch_status(*connection_);
  if (!r) {
    return failed(r.error());
  }
  out = std::move(*r);
  return VCI_OK;
}

HRESULT Library::wait_device_change(uint32_t generation, int timeout_ms) {
  // A connection of its own: waiting must not hold the shared one.
  std::string socket;
  {
    std::lock_guard lock(mutex_);
    socket = socket_;
  }
  auto c = Connection::open(ipc::socket_path(socket), "vci-enum");
  if (!c) {
    set_detail(c.error().message);
    return VCI_E_DISCONNECTED;
  }
  if (auto s = c->subscribe(ipc::kEventDevices); !s) {
    set_detail(s.error().message);
    return VCI_E_DISCONNECTED;
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

HRESULT Library::open_remote(ipc::VciOp op, uint16_t flags, const DeviceDesc& device,
                             uint32_t controller, uint32_t& handle) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(op);
  m.flags = flags;
  ipc::copy_name(m.device, device.name);
  m.controller = controller;
  ipc::VciReply r{};
  const HRESULT hr = call(m, r);
  handle = r.handle;
  return hr;
}

HRESULT Library::simple(const Remote& object, ipc::VciOp op, std::initializer_list<uint32_t> args,
                        ipc::VciReply* reply) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(op);
  m.handle = object.handle;
  std::size_t i = 0;
  for (uint32_t a : args) {
    m.args[i++] = a;
  }
  ipc::VciReply r{};
  const HRESULT hr = call(m, r);
  if (reply != nullptr) {
    *reply = r;
  }
  return hr;
}

HRESULT Library::line_info(const Remote& object, ipc::VciReply& reply) {
  return simple(object, ipc::VciOp::line_info, {}, &reply);
}

HRESULT Library::filter(const Remote& object, ipc::VciOp op, uint32_t kind, bool extended,
                        uint8_t mode, uint32_t code, uint32_t mask, uint8_t* mode_out) {
  ipc::VciReply r{};
  const HRESULT hr = simple(
      object, op,
      {kind, static_cast<uint32_t>(extended ? CAN_FILTER_EXT : CAN_FILTER_STD), mode, code, mask},
      &r);
  if (mode_out != nullptr && hr == VCI_OK) {
    *mode_out = static_cast<uint8_t>(r.values[0]);
  }
  return hr;
}

HRESULT Library::detect(const Remote& control, bool v2, const void* table, std::size_t size,
                        uint16_t timeout_ms, uint8_t op_mode, uint8_t ex_mode, uint32_t& index) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::control_detect);
  m.flags = v2 ? ipc::kVciV2 : 0;
  m.handle = control.handle;
  m.args[0] = timeout_ms;
  m.args[1] = op_mode;
  m.args[2] = ex_mode;
  std::memcpy(m.payload, table, std::min(size, sizeof m.payload));
  ipc::VciReply r{};
  if (HRESULT hr = call(m, r); hr != VCI_OK) {
    return hr;
  }
  while (true) {
    const HRESULT hr = simple(control, ipc::VciOp::control_detect_result, {}, &r);
    if (hr != VCI_E_PENDING) {
      index = r.values[0];
      return hr;
    }
    const timespec pause{0, 1'000'000};
    ::nanosleep(&pause, nullptr);
  }
}

HRESULT Library::init_channel(ChannelObj& channel, uint32_t rx, uint32_t rx_threshold, uint32_t tx,
                              uint32_t tx_threshold, uint32_t filter_size, uint8_t filter_mode) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::channel_init);
  m.handle = channel.handle;
  m.args[0] = rx;
  m.args[1] = tx;
  m.args[2] = filter_size;
  m.args[3] = filter_mode;
  return map_rings(channel, m, tx != 0, rx_threshold, tx_threshold);
}

HRESULT Library::init_lin_monitor(ChannelObj& monitor, uint32_t rx, uint32_t rx_threshold) {
  ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(ipc::VciOp::lin_monitor_init);
  m.handle = monitor.handle;
  m.args[0] = rx;
  return map_rings(monitor, m, false, rx_threshold, 1);
}

HRESULT Library::map_rings(ChannelObj& channel, ipc::VciRequest& m, bool has_tx,
                           uint32_t rx_threshold, uint32_t tx_threshold) {
  ipc::VciReply r{};
  std::vector<ipc::UniqueFd> fds;
  uint64_t generation = 0;
  if (HRESULT hr = call(m, r, &fds, &generation); hr != VCI_OK) {
    return hr;
  }
  const uint32_t element = channel.element_size();
  if (fds.size() != ipc::kChannelFdCount || r.values[2] != element) {
    set_detail(
        fmt::format("canemud sent {} descriptors and {}-byte elements", fds.size(), r.values[2]));
    return VCI_E_UNEXPECTED;
  }
  auto mapped = ipc::RingPair::map(std::move(fds), element);
  if (!mapped) {
    set_detail("the channel's rings could not be mapped");
    return VCI_E_UNEXPECTED;
  }
  auto rings = std::make_shared<Rings>(std::move(*mapped), has_tx);
  rings->can_fd = channel.controller < channel.device.controller_fd.size() &&
                  channel.device.controller_fd[channel.controller];
  rings->rx.set_threshold(std::max<uint32_t>(rx_threshold, 1));
  rings->tx.set_threshold(std::max<uint32_t>(tx_threshold, 1));
  rings->generation = generation;
  channel.rings = std::move(rings);
  return VCI_OK;
}

}  // namespace canemu::client::vci
