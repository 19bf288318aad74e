#include "vci_core.hpp"

#include <algorithm>
#include <cstring>
#include <map>
#include <set>

#include <time.h>
#include <unistd.h>

#include <fmt/format.h>

#include "canemu/ipc/clock.hpp"

namespace canemu::client::vci {

namespace {

thread_local std::string t_detail;

struct Registry {
  std::mutex mutex;
  std::set<Object*> live;
  std::map<const void*, Remote*> aliases;
};

Registry& registry() {
  static Registry* r = new Registry;  // never destroyed: handles may outlive static teardown
  return *r;
}

int64_t now_ms() {
  return ipc::monotonic_ns() / 1'000'000;
}

// Milliseconds left until `deadline_ms` (-1: forever).
int left_ms(int64_t deadline_ms) {
  if (deadline_ms < 0) {
    return -1;
  }
  return static_cast<int>(std::max<int64_t>(0, deadline_ms - now_ms()));
}

}  // namespace

void set_detail(std::string detail) {
  t_detail = std::move(detail);
}

std::string format_error(HRESULT hr) {
  const auto code = static_cast<uint32_t>(hr);
  std::string text;
  switch (code) {
    case static_cast<uint32_t>(VCI_OK):
      text = "success";
      break;
    case static_cast<uint32_t>(VCI_E_UNEXPECTED):
      text = "unexpected error";
      break;
    case static_cast<uint32_t>(VCI_E_NOT_IMPLEMENTED):
      text = "function not implemented";
      break;
    case static_cast<uint32_t>(VCI_E_OUTOFMEMORY):
      text = "not enough memory or resources";
      break;
    case static_cast<uint32_t>(VCI_E_INVALIDARG):
      text = "invalid argument";
      break;
    case static_cast<uint32_t>(VCI_E_NOINTERFACE):
      text = "interface not supported";
      break;
    case static_cast<uint32_t>(VCI_E_INVPOINTER):
      text = "invalid pointer";
      break;
    case static_cast<uint32_t>(VCI_E_INVHANDLE):
      text = "invalid handle";
      break;
    case static_cast<uint32_t>(VCI_E_ABORT):
      text = "operation aborted";
      break;
    case static_cast<uint32_t>(VCI_E_FAIL):
      text = "operation failed";
      break;
    case static_cast<uint32_t>(VCI_E_ACCESSDENIED):
      text = "access denied: the object is in use";
      break;
    case static_cast<uint32_t>(VCI_E_TIMEOUT):
      text = "timeout";
      break;
    case static_cast<uint32_t>(VCI_E_BUSY):
      text = "busy";
      break;
    case static_cast<uint32_t>(VCI_E_PENDING):
      text = "pending";
      break;
    case static_cast<uint32_t>(VCI_E_NO_DATA):
      text = "no data";
      break;
    case static_cast<uint32_t>(VCI_E_NO_MORE_ITEMS):
      text = "no more items";
      break;
    case static_cast<uint32_t>(VCI_E_NOT_INITIALIZED):
      text = "not initialized";
      break;
    case static_cast<uint32_t>(VCI_E_ALREADY_INITIALIZED):
      text = "already initialized";
      break;
    case static_cast<uint32_t>(VCI_E_RXQUEUE_EMPTY):
      text = "receive queue empty";
      break;
    case static_cast<uint32_t>(VCI_E_TXQUEUE_FULL):
      text = "transmit queue full";
      break;
    case static_cast<uint32_t>(VCI_E_BUFFER_OVERFLOW):
      text = "buffer too small";
      break;
    case static_cast<uint32_t>(VCI_E_INVALID_STATE):
      text = "invalid state";
      break;
    case static_cast<uint32_t>(VCI_E_OBJECT_ALREADY_EXISTS):
      text = "object already exists";
      break;
    case static_cast<uint32_t>(VCI_E_INVALID_INDEX):
      text = "invalid index";
      break;
    case static_cast<uint32_t>(VCI_E_END_OF_FILE):
      text = "end of file";
      break;
    case static_cast<uint32_t>(VCI_E_DISCONNECTED):
      text = "disconnected: canemud cannot be reached";
      break;
    case static_cast<uint32_t>(VCI_E_WRONG_FLASHFWVERSION):
      text = "wrong flash firmware version";
      break;
    default:
      text = fmt::format("unknown error {:#010x}", code);
      break;
  }
  if (hr != VCI_OK && !t_detail.empty()) {
    text += " (" + t_detail + ")";
  }
  return text;
}

// ---------------------------------------------------------------- devices

GUID device_class(uint8_t model) {
  // canemu's own class identifiers, one per emulated adapter model.
  GUID g{0x6a4c1e3bU, 0x2c0d, 0x4e7a, {0x9b, 0x41, 0x5d, 0x3f, 0x10, 0x8e, 0x77, 0xa2}};
  g.Data4[7] = static_cast<UINT8>(g.Data4[7] + model);
  return g;
}

VCIDEVICEINFO DeviceDesc::info() const {
  VCIDEVICEINFO d{};
  d.VciObjectId.AsInt64 = static_cast<INT64>(vci_id);
  d.DeviceClass = device_class(model);
  d.DriverMajorVersion = 1;
  d.DriverMinorVersion = 0;
  d.DriverBuildVersion = 0;
  d.HardwareBranchVersion = 0;
  d.HardwareMajorVersion = 1;
  d.HardwareMinorVersion = 0;
  d.HardwareBuildVersion = 0;
  std::snprintf(d.UniqueHardwareId.AsChar, sizeof d.UniqueHardwareId.AsChar, "%s",
                hardware_id.c_str());
  const char* product = model == static_cast<uint8_t>(ipc::WireDeviceModel::ixxat_usb_to_can_fd)
                            ? "USB-to-CAN FD"
                            : "USB-to-CAN";
  std::snprintf(d.Description, sizeof d.Description, "%s (canemu %s)", product, name.c_str());
  std::snprintf(d.Manufacturer, sizeof d.Manufacturer, "canemu");
  return d;
}

VCIDEVICECAPS DeviceDesc::caps() const {
  VCIDEVICECAPS c{};
  c.BusCtrlCount = static_cast<UINT16>(controller_fd.size());
  for (std::size_t i = 0; i < controller_fd.size() && i < VCI_MAX_BUSCTRL; ++i) {
    c.BusCtrlTypes[i] = static_cast<UINT16>(
        VCI_BUS_CTRL(VCI_BUS_CAN, controller_fd[i] ? CAN_CTRL_IFICFD : CAN_CTRL_SJA1000));
  }
  return c;
}

namespace {
template <class Match>
std::optional<DeviceDesc> device_where(Match match, HRESULT none, HRESULT& hr) {
  std::vector<DeviceDesc> devices;
  hr = Library::get().list_devices(devices);
  if (hr != VCI_OK) {
    return std::nullopt;
  }
  for (DeviceDesc& d : devices) {
    if (match(d)) {
      return std::move(d);
    }
  }
  hr = none;
  return std::nullopt;
}
bool same_guid(const GUID& a, const GUID& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}
}  // namespace

std::optional<DeviceDesc> device_by_id(int64_t vci_id, HRESULT& hr) {
  auto d = device_where(
      [vci_id](const DeviceDesc& x) { return static_cast<int64_t>(x.vci_id) == vci_id; },
      VCI_E_INVALIDARG, hr);
  if (!d && hr == VCI_E_INVALIDARG) {
    set_detail("no device has that VCIID");
  }
  return d;
}

std::optional<DeviceDesc> device_by_hwid(const GUID& hwid, HRESULT& hr) {
  return device_where(
      [&hwid](const DeviceDesc& x) { return same_guid(x.info().UniqueHardwareId.AsGuid, hwid); },
      VCI_E_NO_MORE_ITEMS, hr);
}

std::optional<DeviceDesc> device_by_class(const GUID& cls, uint32_t instance, HRESULT& hr) {
  uint32_t seen = 0;
  return device_where(
      [&](const DeviceDesc& x) {
        return same_guid(device_class(x.model), cls) && seen++ == instance;
      },
      VCI_E_NO_MORE_ITEMS, hr);
}

// ---------------------------------------------------------------- handles

void* register_object(std::unique_ptr<Object> object) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  Object* p = object.release();
  r.live.insert(p);
  return p;
}

Object* lookup(void* handle, Object::Kind kind) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  auto* p = static_cast<Object*>(handle);
  if (r.live.count(p) == 0 || p->kind() != kind) {
    return nullptr;
  }
  return p;
}

bool unregister_object(void* handle, Object::Kind kind) {
  std::unique_ptr<Object> doomed;
  {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    auto* p = static_cast<Object*>(handle);
    if (r.live.count(p) == 0 || p->kind() != kind) {
      return false;
    }
    r.live.erase(p);
    doomed.reset(p);
  }
  return true;  // destroyed here, outside the registry's lock
}

void register_alias(const void* key, Remote* remote) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.aliases[key] = remote;
}

void unregister_alias(const void* key) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.aliases.erase(key);
}

Remote* alias_of(const void* key) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  auto it = r.aliases.find(key);
  return it == r.aliases.end() ? nullptr : it->second;
}

Remote::~Remote() {
  Library::get().simple(*this, ipc::VciOp::close);
}

Rings::Rings(ipc::RingPair mapped, bool with_tx)
    : pair(std::move(mapped)), rx(pair.rx().reader()), tx(pair.tx().writer()), has_tx(with_tx) {}

// ---------------------------------------------------------------- requests

Library& Library::get() {
  static Library* lib = new Library;  // never destroyed: see registry()
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
  connection_.reset();  // gone: the next call connects again
  return VCI_E_DISCONNECTED;
}

HRESULT Library::reconnect(const std::string& socket) {
  std::lock_guard lock(mutex_);
  connection_.reset();
  socket_ = socket;
  return connect_locked();
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
    auto r = connection_->call<ipc::TimeStepRequest, ipc::TimeStepReply>(m);
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

HRESULT Library::connect_locked() {
  if (connection_) {
    return VCI_OK;
  }
  auto c = Connection::open(ipc::socket_path(socket_), "vci");
  if (!c) {
    set_detail(c.error().message);
    return VCI_E_DISCONNECTED;
  }
  connection_.emplace(std::move(*c));
  return VCI_OK;
}

HRESULT Library::call(ipc::VciRequest& request, ipc::VciReply& reply,
                      std::vector<ipc::UniqueFd>* fds) {
  std::lock_guard lock(mutex_);
  if (HRESULT hr = connect_locked(); hr != VCI_OK) {
    return hr;
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
  auto r = connection_->call<ipc::DeviceListRequest, ipc::DeviceListReply>(
      ipc::make_message<ipc::DeviceListRequest>());
  if (!r) {
    return failed(r.error());
  }
  out.clear();
  for (uint16_t i = 0; i < r->count && i < ipc::kMaxDevices; ++i) {
    const ipc::DeviceEntry& e = r->devices[i];
    if (e.vci_id == 0) {
      continue;  // not an adapter the VCI sees (an ephemeral channel's device)
    }
    DeviceDesc d;
    d.name = ipc::name_of(e.name);
    d.vci_id = e.vci_id;
    d.hardware_id = ipc::name_of(e.hardware_id);
    d.model = e.model;
    for (uint8_t k = 0; k < e.controller_count && k < ipc::kMaxDeviceControllers; ++k) {
      d.controller_fd.push_back(e.controller_fd[k] != 0);
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

HRESULT Library::status(ipc::StatusReply& out) {
  std::lock_guard lock(mutex_);
  if (HRESULT hr = connect_locked(); hr != VCI_OK) {
    return hr;
  }
  auto r = connection_->call<ipc::StatusRequest, ipc::StatusReply>(
      ipc::make_message<ipc::StatusRequest>());
  if (!r) {
    return failed(r.error());
  }
  out = *r;
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
  ipc::VciReply r{};
  std::vector<ipc::UniqueFd> fds;
  if (HRESULT hr = call(m, r, &fds); hr != VCI_OK) {
    return hr;
  }
  const uint32_t element = channel.v2 ? sizeof(CANMSG2) : sizeof(CANMSG);
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
  auto rings = std::make_shared<Rings>(std::move(*mapped), tx != 0);
  rings->rx.set_threshold(std::max<uint32_t>(rx_threshold, 1));
  rings->tx.set_threshold(std::max<uint32_t>(tx_threshold, 1));
  channel.rings = std::move(rings);
  return VCI_OK;
}

// ---------------------------------------------------------------- data path

int timeout_of(uint32_t ms) {
  return ms == 0xFFFFFFFFU ? -1 : static_cast<int>(std::min<uint32_t>(ms, 0x7FFFFFFF));
}

namespace {
// A pollable channel after a read found its ring empty or a blocking wait drained the eventfd:
// arms the eventfd when the ring is empty (the next put writes it), makes it readable when
// messages wait.
void keep_pollable(ChannelObj& c) {
  if (!c.pollable.load(std::memory_order_relaxed)) {
    return;
  }
  ipc::RingReader& rx = c.rings->rx;
  if (rx.fill_count() == 0) {
    rx.disarm();  // drops stale wake-ups
    if (rx.arm_unless_filled()) {
      return;
    }
  }
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(c.rings->pair.rx().reader_event(), &one, sizeof one);
}
}  // namespace

int channel_poll_fd(ChannelObj& c) {
  c.pollable.store(true, std::memory_order_relaxed);
  keep_pollable(c);
  return c.rings->pair.rx().reader_event();
}

HRESULT channel_peek(ChannelObj& c, void* msg) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  switch (c.rings->rx.get(msg)) {
    case ipc::RingStatus::ok:
      return VCI_OK;
    case ipc::RingStatus::empty:
      keep_pollable(c);
      return VCI_E_RXQUEUE_EMPTY;
    default:
      set_detail("the receive ring is corrupted");
      return VCI_E_UNEXPECTED;
  }
}

HRESULT channel_read(ChannelObj& c, uint32_t timeout_ms, void* msg) {
  HRESULT hr = channel_peek(c, msg);
  if (hr != VCI_E_RXQUEUE_EMPTY || timeout_ms == 0) {
    return hr == VCI_E_RXQUEUE_EMPTY ? VCI_E_TIMEOUT : hr;
  }
  ipc::RingReader& rx = c.rings->rx;
  const int timeout = timeout_of(timeout_ms);
  const int64_t deadline = timeout < 0 ? -1 : now_ms() + timeout;
  // Waiting for one message whatever the application's threshold.
  const uint32_t threshold = rx.threshold();
  rx.set_threshold(1);
  while (true) {
    hr = channel_peek(c, msg);
    if (hr != VCI_E_RXQUEUE_EMPTY) {
      break;
    }
    const int left = left_ms(deadline);
    if (left == 0 || !rx.wait(left)) {
      hr = channel_peek(c, msg);
      if (hr == VCI_E_RXQUEUE_EMPTY) {
        hr = VCI_E_TIMEOUT;
      }
      break;
    }
  }
  rx.set_threshold(threshold);
  keep_pollable(c);
  return hr;
}

HRESULT channel_post(ChannelObj& c, const void* msg) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  if (!c.rings->has_tx) {
    return VCI_E_ACCESSDENIED;  // initialized without a transmit FIFO
  }
  switch (c.rings->tx.put(msg)) {
    case ipc::RingStatus::ok:
      return VCI_OK;
    case ipc::RingStatus::full:
      return VCI_E_TXQUEUE_FULL;
    default:
      set_detail("the transmit ring is corrupted");
      return VCI_E_UNEXPECTED;
  }
}

HRESULT channel_send(ChannelObj& c, uint32_t timeout_ms, const void* msg) {
  HRESULT hr = channel_post(c, msg);
  if (hr != VCI_E_TXQUEUE_FULL || timeout_ms == 0) {
    return hr;
  }
  ipc::RingWriter& tx = c.rings->tx;
  const int timeout = timeout_of(timeout_ms);
  const int64_t deadline = timeout < 0 ? -1 : now_ms() + timeout;
  const uint32_t threshold = tx.threshold();
  tx.set_threshold(1);
  while (true) {
    hr = channel_post(c, msg);
    if (hr != VCI_E_TXQUEUE_FULL) {
      break;
    }
    const int left = left_ms(deadline);
    if (left == 0 || !tx.wait(left)) {
      hr = channel_post(c, msg);
      if (hr == VCI_E_TXQUEUE_FULL) {
        hr = VCI_E_TIMEOUT;
      }
      break;
    }
  }
  tx.set_threshold(threshold);
  return hr;
}

HRESULT channel_read_many(ChannelObj& c, uint32_t timeout_ms, void* msgs, uint32_t count,
                          uint32_t& done) {
  done = 0;
  if (count == 0) {
    return VCI_OK;
  }
  auto* out = static_cast<uint8_t*>(msgs);
  HRESULT hr = timeout_ms == 0 ? channel_peek(c, out) : channel_read(c, timeout_ms, out);
  if (hr != VCI_OK) {
    return hr;
  }
  const std::size_t size = c.rings->pair.element_size();
  for (done = 1; done < count; ++done) {
    if (channel_peek(c, out + done * size) != VCI_OK) {
      break;
    }
  }
  return VCI_OK;
}

HRESULT channel_send_many(ChannelObj& c, uint32_t timeout_ms, const void* msgs, uint32_t count,
                          uint32_t& done) {
  done = 0;
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  const auto* in = static_cast<const uint8_t*>(msgs);
  const std::size_t size = c.rings->pair.element_size();
  for (; done < count; ++done) {
    const HRESULT hr = timeout_ms == 0 ? channel_post(c, in + done * size)
                                       : channel_send(c, timeout_ms, in + done * size);
    if (hr != VCI_OK) {
      return hr;
    }
  }
  return VCI_OK;
}

HRESULT channel_wait_rx(ChannelObj& c, uint32_t timeout_ms) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  const bool signalled = c.rings->rx.wait(timeout_of(timeout_ms));
  keep_pollable(c);
  return signalled ? VCI_OK : VCI_E_TIMEOUT;
}

HRESULT channel_wait_tx(ChannelObj& c, uint32_t timeout_ms) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  return c.rings->tx.wait(timeout_of(timeout_ms)) ? VCI_OK : VCI_E_TIMEOUT;
}

uint8_t rx_load(const ChannelObj& c) {
  if (!c.rings) {
    return 0;
  }
  return static_cast<uint8_t>(uint64_t{c.rings->rx.fill_count()} * 100 /
                              c.rings->pair.rx().memory().capacity());
}

uint8_t tx_load(const ChannelObj& c) {
  if (!c.rings || !c.rings->has_tx) {
    return 0;
  }
  return static_cast<uint8_t>(uint64_t{c.rings->tx.fill_count()} * 100 /
                              c.rings->pair.tx().memory().capacity());
}

}  // namespace canemu::client::vci
