// The machinery behind the VCI C libraries (libvcinpl.so, libvcinpl2.so) and the VCI C++ API:
// one connection to canemud per process, the objects an application opened (a HANDLE is a
// pointer to one; every HANDLE is checked against the live objects before use), and the
// channels' rings in shared memory. The libraries only convert their structs and arguments.
//
// Thread safety: requests to canemud go one at a time (client::DaemonLink's turns); a channel's
// rings follow the VCI rule (one reader and one writer thread at a time, the FIFO Lock/Unlock for
// more).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <sched.h>

#include "canemu/client/can_nodes.hpp"
#include "canemu/client/connection.hpp"
#include "canemu/client/daemon_link.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/ring_pair.hpp"
#include "vci/cantype.h"
#include "vci/lintype.h"
#include "vci/vcierr.h"
#include "vci/vcitype.h"

namespace canemu::client::vci {

// Text for a VCI result, with the detail of the last failure of this thread when it has one
// (e.g. where canemud was looked for).
std::string format_error(HRESULT hr);
void set_detail(std::string detail);
// A detail of this call's failure `hr` only: it goes with `hr` and is forgotten when the thread
// next looks up or closes a handle (an argument error of one call is no reason for the next).
void set_call_detail(HRESULT hr, std::string detail);
void forget_call_detail();

// The VCI version all three libraries report (vciGetVersion, vciGetVersionEx, VciGetVersion):
// the VCI 4 interfaces they implement, and canemu's own version as the build number
// (major * 10000 + minor * 100 + patch). docs/vci.md.
inline constexpr uint32_t kVciMajorVersion = 4;
inline constexpr uint32_t kVciMinorVersion = 0;
inline constexpr uint32_t kVciRevisionNumber = 0;
uint32_t vci_build_number();

// A new locally unique identifier (vciCreateLuid, VciCreateLuid): the process id in the high
// half, a counter of the process in the low half; never 0, never a device's VCIID.
int64_t new_luid();

// Identifiers as text: a LUID as 16 upper-case hex digits (its 64-bit value), a GUID in the
// registry form {XXXXXXXX-XXXX-XXXX-XXXX-XXXXXXXXXXXX} (38 characters). The parsers take
// either case and nothing else around the digits.
inline constexpr std::size_t kLuidTextLength = 16;
inline constexpr std::size_t kGuidTextLength = 38;
std::string luid_text(const VCIID& id);
std::string guid_text(const GUID& guid);
std::optional<VCIID> parse_luid(std::string_view text);
std::optional<GUID> parse_guid(std::string_view text);

// UTF-8 to wide text (a wchar_t per code point; bytes that are not UTF-8 become U+FFFD), and
// wide text that is pure ASCII back to bytes (nullopt for anything else).
std::wstring widen(std::string_view utf8);
std::string narrow(std::wstring_view wide);
std::optional<std::string> narrow_ascii(std::wstring_view wide);

// Copies `text` and its NUL into `out`, which holds `size` characters; VCI_E_INVALIDARG for a
// null buffer or a size <= 0, VCI_E_BUFFER_OVERFLOW (nothing written) when it does not fit.
HRESULT copy_text(const std::string& text, char* out, LONG size);
HRESULT copy_text(const std::string& text, wchar_t* out, LONG size);

// A device as canemud lists it.
struct DeviceDesc {
  std::string name;
  uint64_t vci_id = 0;
  std::string hardware_id;
  uint8_t model = 0;                 // ipc::WireDeviceModel
  std::vector<bool> controller_fd;   // per controller (CAN, then LIN)
  std::vector<bool> controller_lin;  // a LIN controller
  std::vector<std::string> buses;    // the bus of each controller
  bool ephemeral = false;
  int64_t epoch_ns = 0;  // simulated time of power-on, the time stamps' zero
  VCIDEVICEINFO info() const;
  VCIDEVICECAPS caps() const;
};

// The device class GUIDs this library reports (ours; documented in docs/vci.md).
GUID device_class(uint8_t model);

// Why `device` has no CAN controller number `asked` (beyond its controllers, or a LIN
// controller), naming the CAN controllers it has with their buses, and its LIN controllers:
// "ixxat0 has no controller 5; its CAN controllers are 0 (can0) and 1 (can1), 2 is its LIN
// controller (lin0)".
std::string no_can_controller(const DeviceDesc& device, uint32_t asked);

// A device of canemud's list by VCIID, by hardware ID, or the `instance`th of a class. `hr`
// says why there is none: VCI_E_INVALIDARG (VCIID), VCI_E_NO_MORE_ITEMS (the others), or the
// failure to reach canemud.
std::optional<DeviceDesc> device_by_id(int64_t vci_id, HRESULT& hr);
std::optional<DeviceDesc> device_by_hwid(const GUID& hwid, HRESULT& hr);
std::optional<DeviceDesc> device_by_class(const GUID& cls, uint32_t instance, HRESULT& hr);

class Object {
 public:
  enum class Kind : uint8_t {
    enumerator,
    device,
    control,
    channel,
    scheduler,
    event,
    lin_control,
    lin_monitor
  };
  explicit Object(Kind kind) : kind_(kind) {}
  virtual ~Object() = default;
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

// Handles (HANDLE values) of live objects.
void* register_object(std::unique_ptr<Object> object);
// The object behind `handle` if it is live and of `kind`; nullptr otherwise.
Object* lookup(void* handle, Object::Kind kind);
// Destroys it; false if it was not a live handle of `kind`.
bool unregister_object(void* handle, Object::Kind kind);

struct Remote;
// The C++ API's objects (ICanControl*, ICanChannel*, ICanScheduler* values) as names of the
// remote object they hold, for the canemu extension calls that take a HANDLE.
void register_alias(const void* key, Remote* remote);
void unregister_alias(const void* key);
Remote* alias_of(const void* key);

struct Enumerator : Object {
  Enumerator() : Object(Kind::enumerator) {}
  std::vector<DeviceDesc> devices;
  std::size_t next = 0;
  uint32_t generation = 0;
};

struct Device : Object {
  Device() : Object(Kind::device) {}
  DeviceDesc desc;
};

// An object canemud holds for us (control unit, channel, cyclic list); closed on destruction.
struct Remote : Object {
  Remote(Kind kind, uint32_t remote_handle, const DeviceDesc& on_device, uint32_t bus_no)
      : Object(kind), handle(remote_handle), device(on_device), controller(bus_no) {}
  ~Remote() override;
  uint32_t handle;
  DeviceDesc device;
  uint32_t controller;
};

// A program that polls a FIFO in a loop (a look that finds it empty, or full, again and again)
// gives up the processor once per look from the second on: canemud, woken on this CPU by what
// the program sent, would otherwise wait for the end of the program's time slice before it
// could deliver (docs/vci.md, "Latency"). A single empty look (the drain after a wake-up,
// the look before a blocking wait) costs nothing.
class PollYield {
 public:
  void missed() {
    if (misses_.fetch_add(1, std::memory_order_relaxed) > 0) {
      ::sched_yield();
    }
  }
  void hit() {
    if (misses_.load(std::memory_order_relaxed) != 0) {
      misses_.store(0, std::memory_order_relaxed);
    }
  }

 private:
  std::atomic<uint32_t> misses_{0};
};

struct Rings {
  Rings(ipc::RingPair mapped, bool has_tx);
  ipc::RingPair pair;
  ipc::RingReader rx;  // this process's views: it reads the receive FIFO, writes the transmit one
  ipc::RingWriter tx;
  bool has_tx;
  // The channel's controller is a CAN FD one (DeviceDesc::controller_fd): only then may its
  // messages carry EDL/FDR (check_tx_message).
  bool can_fd = false;
  // The C++ API hands out one IFifoReader and one IFifoWriter at a time.
  std::atomic<bool> reader_out{false};
  std::atomic<bool> writer_out{false};
  PollYield rx_looks;  // the C API's looks that found the receive FIFO empty
  PollYield tx_looks;  // ... the transmit FIFO full
  // The connection to canemud the rings came with (numbered by Library::call) and whether it is
  // gone: then nobody serves the rings any more (channel_link).
  uint64_t generation = 0;
  std::atomic<int64_t> link_checked_ms{0};
  std::atomic<bool> link_lost{false};
  std::mutex lost_mutex;
  std::string lost_reason;  // under lost_mutex, set before link_lost
};

// A CAN channel, or (Kind::lin_monitor) a LIN monitor: a channel with LINMSG elements and no
// transmit FIFO, read by the same code.
struct ChannelObj : Remote {
  ChannelObj(uint32_t remote_handle, const DeviceDesc& on_device, uint32_t bus_no, bool is_v2,
             Kind kind = Kind::channel)
      : Remote(kind, remote_handle, on_device, bus_no), v2(is_v2) {}
  bool v2;
  // The elements: LINMSG for a monitor, CANMSG2 (v2) or CANMSG.
  uint32_t element_size() const {
    return kind() == Kind::lin_monitor ? sizeof(LINMSG) : v2 ? sizeof(CANMSG2) : sizeof(CANMSG);
  }
  std::shared_ptr<Rings> rings;  // shared with the C++ API's FIFO objects
  // canemuChannelEventFd was called: the receive eventfd is kept readable while messages wait.
  std::atomic<bool> pollable{false};
};

class Library {
 public:
  static Library& get();

  // Connects if not connected. VCI_E_DISCONNECTED (with a detail saying where canemud was
  // looked for and how to start it) when it cannot be reached.
  HRESULT connect();
  // Drops the connection and connects to `socket` (empty: the usual search) from now on.
  HRESULT reconnect(const std::string& socket);
  // Stepped time: runs the emulation `ns` further; `now` gets the simulated time after it.
  HRESULT step(int64_t ns, int64_t& now);
  // One VCI request. `fds` receives the descriptors of the reply, `generation` the number of
  // the connection it went over.
  HRESULT call(ipc::VciRequest& request, ipc::VciReply& reply,
               std::vector<ipc::UniqueFd>* fds = nullptr, uint64_t* generation = nullptr);
  // Whether connection number `generation` (connections are numbered from 1 as they are made)
  // is still up: VCI_OK, or VCI_E_DISCONNECTED with the reason in `why` (what canemud said
  // before it closed it, or that it went away). Never waits: while another thread's request
  // holds the connection, VCI_OK (that request finds out itself).
  HRESULT link(uint64_t generation, std::string& why);
  HRESULT list_devices(std::vector<DeviceDesc>& out, uint32_t* generation = nullptr);
  // canemud's status, every page of it: buses, nodes, simulated time and time mode.
  HRESULT status(client::Status& out);
  // Requests about simulated CAN nodes (a load's parts, or one request), in one turn: VCI_OK
  // with the last reply; VCI_E_INVALIDARG when canemud refused one (its reason as this call's
  // detail; nothing changed); VCI_E_DISCONNECTED when it could not be asked.
  HRESULT can_nodes(const client::CanNodeRequests& requests, ipc::CanNodeReply& reply);
  // Waits until the device list changes (VCI_OK) or `timeout_ms` passes (VCI_E_TIMEOUT).
  HRESULT wait_device_change(uint32_t generation, int timeout_ms);

 private:
  Library();
  DaemonLink link_;  // one request at a time: a reply may bring descriptors
};

// --- channel data path (no daemon round trip) ---
// Copies the next message (element size bytes) out; VCI_E_RXQUEUE_EMPTY when there is none.
HRESULT channel_peek(ChannelObj& c, void* msg);
// As channel_peek, waiting up to `timeout_ms` (INFINITE: 0xFFFFFFFF) for one.
HRESULT channel_read(ChannelObj& c, uint32_t timeout_ms, void* msg);
// Whether a program may queue `msg` (a CANMSG or CANMSG2, by `element_size`) in a channel's
// transmit FIFO: a data message's identifier must fit its format (11 bits, 29 with `ext`), and
// a CAN FD message (EDL or FDR) needs a CAN FD controller (`can_fd`). VCI_E_INVALIDARG
// otherwise, with vciFormatError's detail naming what is wrong (docs/vci.md: refused, never
// masked or dropped unseen).
HRESULT check_tx_message(const void* msg, std::size_t element_size, bool can_fd);
HRESULT channel_post(ChannelObj& c, const void* msg);
HRESULT channel_send(ChannelObj& c, uint32_t timeout_ms, const void* msg);
// Up to `count` messages into `msgs` (an array of the channel's element type), waiting up to
// `timeout_ms` for the first; `done` gets how many. VCI_E_TIMEOUT (or VCI_E_RXQUEUE_EMPTY
// with no waiting) when none came.
HRESULT channel_read_many(ChannelObj& c, uint32_t timeout_ms, void* msgs, uint32_t count,
                          uint32_t& done);
// Up to `count` messages from `msgs`, waiting up to `timeout_ms` for room; `done` gets how
// many were queued. VCI_OK when at least one was queued (vcinpl.h); VCI_E_TIMEOUT
// (VCI_E_TXQUEUE_FULL with no waiting) when none was.
HRESULT channel_send_many(ChannelObj& c, uint32_t timeout_ms, const void* msgs, uint32_t count,
                          uint32_t& done);
HRESULT channel_wait_rx(ChannelObj& c, uint32_t timeout_ms);
HRESULT channel_wait_tx(ChannelObj& c, uint32_t timeout_ms);
// VCI_OK while the connection the channel's rings came with is up; VCI_E_DISCONNECTED (the
// reason as the detail) once canemud closed it or went away, from then on. With `now` it
// looks at the connection; otherwise at most once every kLinkCheckMs (the data path's calls:
// a clock read, no system call).
inline constexpr int64_t kLinkCheckMs = 10;
HRESULT channel_link(ChannelObj& c, bool now);
// For canemuChannelEventFd: from now on the receive ring's eventfd is readable whenever messages
// wait (and may be readable spuriously); returns it.
int channel_poll_fd(ChannelObj& c);
// Fill levels in percent, for the channel status.
uint8_t rx_load(const ChannelObj& c);
uint8_t tx_load(const ChannelObj& c);

int timeout_of(uint32_t ms);  // INFINITE -> -1

}  // namespace canemu::client::vci
