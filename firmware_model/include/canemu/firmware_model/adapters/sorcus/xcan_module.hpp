// The SORCUS X-CAN-2i module device driver (MDD, mxcan2) on its two Intel 82527 controllers: the
// channel services of the manual's chapter 10.9.2, one call per generic service, so that a
// client library can forward max_* calls 1:1 (../shared/spec/sorcus-digest.md §1, §3.1, §4).
//
// What it models:
// - two CAN interfaces (usChannel 0 and 1), each an I82527 at the 8 MHz / 125 ns system clock
//   (16 MHz crystal halved by DSC), with a high-speed or a low-speed fault-tolerant transceiver
//   by variant (2i/H, 2i/F, 2i/M);
// - the dynamic object model: the first channel with an ID creates the object, later channels
//   with that ID attach to it and must bring the same CPS;
// - the buffer manager shared with the SL-CANi (buffer_manager.hpp): with at most 14 objects
//   each has a buffer of its own; beyond, objects with XCAN_EXCL_BUFFER (and the general-ID
//   channel) keep buffers 1..13, the rest of 1..14 are the temporary pool, requests wait in the
//   driver FIFO when no temporary buffer is free, and passive non-exclusive objects share the
//   receive-only buffer 15 behind the automatic acceptance filter, Data-only or Remote-only;
// - the acceptance-filter device, the general-ID send channel, active and passive send and
//   receive objects with every flag of §3.1, the bus-control device (bit timing, CMD_STOP /
//   CMD_START, INFO_DEVICE), the error callback at WARN ("heavily disturbed") and bus-off.
//
// The driver programs each 82527 through its registers and serves its interrupt at the instant
// the line goes active (a same-instant event after the chip's own). Callbacks and the results
// of blocking services go to an XcanSink with the simulated instant. Blocking services (a send
// with XCAN_NO_INT, an active receive read) answer Reply::pending and complete later through
// XcanSink::completed, so the daemon can block its client without a thread in the model.
//
// The MDD's version (MddVersion, 3.C unless set) gates what the manual marks «ab MDD Version
// 3.C»: INFO_XCAN_MSG_COUNT of send objects, XCAN_NEW_ONLY, the general-ID send channel.
//
// Every decision where the manual is silent is marked `Decision:` and listed in docs/sorcus.md.
// Loading an object into a buffer takes set_buffer_load_time() (0 unless set): its transmit
// request reaches the 82527 that much later; an object still cached in its buffer goes at once.
//
// Not modelled: the NI-Task's queue (the sink gets every callback at once, flagged sync or
// buffered), the 82527 bug that sends a remote frame with ID 0.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/firmware_model/adapters/sorcus/acceptance.hpp"
#include "canemu/firmware_model/adapters/sorcus/buffer_manager.hpp"
#include "canemu/firmware_model/adapters/sorcus/mdd_version.hpp"
#include "canemu/firmware_model/chips/i82527/i82527.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"
#include "sorcus/xcan_types.h"

namespace canemu::model::sorcus {

// Type 58 subtypes 1/2/3 (digest §2.6): /H two high-speed interfaces, /F two low-speed
// fault-tolerant ones, /M interface 0 ("Bus 1") high-speed and interface 1 low-speed.
enum class XcanVariant : uint8_t { h, f, m };

using ChannelHandle = uint32_t;  // 0 is never a handle
using RequestId = uint64_t;

// The callback's argument (digest §1.7 table).
enum class CallbackArg : uint8_t { none, data, status, message };

struct XcanCallback {
  SimTime at;
  ChannelHandle channel = 0;
  bool sync = false;  // the channel asked for _CP_SYNC_CALLBACK (else buffered, NI-Task)
  CallbackArg arg = CallbackArg::none;
  uint8_t size = 0;  // data: valid bytes
  std::array<uint8_t, 8> data{};
  ULONG status = 0;        // status: the bus state word (XCAN_STATUS)
  XCAN_MESSAGE message{};  // message
};

// The end of a blocking service.
struct XcanCompletion {
  SimTime at;
  RequestId request = 0;
  ChannelHandle channel = 0;
  uint32_t error = ERR_OK;    // ERR_OK or ERR_XCAN_TIMEOUT
  std::vector<uint8_t> data;  // an active receive read: the answer's data
};

class XcanSink {
 public:
  virtual void callback(const XcanCallback& callback) = 0;
  virtual void completed(const XcanCompletion& completion) = 0;

 protected:
  ~XcanSink() = default;
};

struct Reply {
  Reply() = default;
  Reply(uint32_t e) : error(e) {}  // NOLINT(google-explicit-constructor): a code is a reply
  Reply(uint32_t e, RequestId r) : error(e), pending(r) {}
  uint32_t error = ERR_OK;
  std::optional<RequestId> pending;  // the service goes on: XcanSink::completed ends it
  std::vector<uint8_t> data;         // read_block: the bytes read
};

class XcanModule {
 public:
  // The FIFO's depth. Decision: the manual gives none (digest §7.3); 64 requests.
  static constexpr std::size_t kFifoDepth = 64;
  // Decision: objects per interface, the limit behind ERR_XCAN_NO_MEMORY.
  static constexpr std::size_t kMaxObjects = 1024;

  // `scheduler` is the buses' (interrupt service and timeouts run on it); `sink` outlives the
  // module. The module's chips stay attached to their buses: it lives as long as they run.
  XcanModule(SimScheduler& scheduler, XcanVariant variant, XcanSink& sink);
  ~XcanModule();
  XcanModule(const XcanModule&) = delete;
  XcanModule& operator=(const XcanModule&) = delete;

  // Wires interface `i` (0 or 1) to `bus`; before any channel of it is opened.
  void connect(unsigned i, CanBus& bus);
  XcanVariant variant() const { return variant_; }
  // The MDD's version; before any channel is opened. Before 3.C: no INFO_XCAN_MSG_COUNT on
  // send objects (ERR_XCAN_WRONG_TYPE), no XCAN_NEW_ONLY and no general-ID channel
  // (ERR_XCAN_INVALID_CPS).
  void set_mdd_version(MddVersion v) { mdd_version_ = v; }
  MddVersion mdd_version() const { return mdd_version_; }
  // «Das Eintragen eines Message-Objekts in einen Message-Puffer nimmt eine gewisse Zeit (einige
  // µs) in Anspruch»: the time from loading a buffer (an object not cached there, or a general-ID
  // message) to its transmit request, in ns; 0 unless set.
  void set_buffer_load_time(int64_t ns);
  int64_t buffer_load_time() const { return ifaces_[0].mgr->load_time(); }
  bool low_speed(unsigned i) const;
  I82527& chip(unsigned i) { return ifaces_[i].chip; }
  // The low-speed transceiver reports a line fault (the daemon's line_error fault): it goes on
  // in single-wire mode; XCAN_LINE_ERROR in the state word, and the error callback at its
  // onset. False (and no effect) on a high-speed interface.
  bool set_line_error(unsigned i, bool error);

  // --- the generic channel services ---
  // `callback`: the client gave a callback function when it opened the channel.
  tl::expected<ChannelHandle, uint32_t> open_channel(const CPS_XCAN& cps, bool callback);
  uint32_t close_channel(ChannelHandle channel);
  Reply write_block(ChannelHandle channel, std::span<const uint8_t> data);
  Reply read_block(ChannelHandle channel);
  uint32_t write_ulong(ChannelHandle channel, ULONG value);
  tl::expected<ULONG, uint32_t> read_ulong(ChannelHandle channel);
  uint32_t control(ChannelHandle channel, USHORT command);
  tl::expected<ULONG, uint32_t> info(ChannelHandle channel, USHORT what);
  uint32_t clear_error(ChannelHandle channel);

  // --- views ---
  BufferView buffer(unsigned i, uint8_t n) const { return ifaces_[i].mgr->buffer(n); }
  // The automatic filter of the objects in buffer 15 ({0, 0} without any); a manual mask is
  // not in it.
  AcceptanceFilter buffer15_filter(unsigned i) const { return ifaces_[i].mgr->buffer15_filter(); }
  std::size_t fifo_size(unsigned i) const { return ifaces_[i].mgr->fifo_size(); }
  // Objects on the interface; the general-ID channel's buffer counts as one.
  std::size_t object_count(unsigned i) const { return ifaces_[i].objects.size(); }
  // Frames buffer 15 took that matched no object and went to no filter channel.
  uint64_t discarded(unsigned i) const { return ifaces_[i].discarded; }
  // The state word INFO_DEVICE gives (XCAN_STATUS: flags, last error code).
  ULONG bus_state(unsigned i) const;

 private:
  enum class Kind : uint8_t { bus_control, filter, object, general };
  enum class Role : uint8_t { active_send, passive_send, active_receive, passive_receive, general };

  // What X-CAN adds to the buffer manager's object of the same index.
  struct Object {
    Role role = Role::active_send;
    CPS_XCAN cps{};  // as configured
    bool no_int = false;
    uint32_t count = 0;  // INFO_XCAN_MSG_COUNT
  };
  struct Channel {
    Channel(unsigned i, Kind k, const CPS_XCAN& p, bool cb, int o = -1)
        : iface(i), kind(k), cps(p), callback(cb), object(o) {}
    unsigned iface = 0;
    Kind kind = Kind::object;
    CPS_XCAN cps{};
    bool callback = false;
    int object = -1;
    bool new_data = false;       // XCAN_NEW_ONLY: data came since the last read
    uint32_t sticky = ERR_OK;    // ERR_DATA_NOT_READY until clear_error
    bool start_pending = false;  // active receive: a CMD_START request awaits its answer
  };
  struct Waiter {
    RequestId id = 0;
    ChannelHandle channel = 0;
    int object = -1;
    bool read = false;
    EventId timeout = 0;
  };
  struct Events final : BufferEvents {
    XcanModule* module = nullptr;
    unsigned iface = 0;
    void status_changed() override { module->serve_status(iface); }
    void sent(const SendRequest& r, bool answered) override;
    void received(int object, const Frame& frame, bool lost) override;
    void unconfigured(const Frame& frame) override { module->unconfigured(iface, frame); }
  };
  struct Interface {
    I82527 chip;
    Events events;
    std::optional<BufferManager> mgr;
    CanBus* bus = nullptr;
    bool low_speed = false;
    bool line_error = false;
    XCAN_BITPARAMS params = XCAN_DEFAULT_BITPARAMS;
    std::vector<Object> objects;  // parallel to mgr->objects()
    ChannelHandle filter_channel = 0;
    ChannelHandle general_channel = 0;
    int general_object = -1;
    bool controlled = false;  // CMD_STOP or CMD_START came on the bus-control device
    bool stopped = false;     // CMD_STOP since the last CMD_START
    uint8_t error_bits = 0;   // WARN | BOFF as last served
    uint16_t last_lec = 0;
    bool isr_scheduled = false;
    uint64_t discarded = 0;
  };

  Channel* find(ChannelHandle h);
  void emit(ChannelHandle h, const Channel& c, XcanCallback cb);
  RequestId wait(ChannelHandle h, int object, bool read, USHORT timeout_us);
  void complete_waiters(unsigned i, int object, bool read, const std::vector<uint8_t>& data);
  void cancel_waiters(ChannelHandle h);

  // xcan_module.cpp: channels; xcan_services.cpp: services
  tl::expected<ChannelHandle, uint32_t> open_object(const CPS_XCAN& cps, bool callback);
  uint32_t validate_object_cps(const Interface& f, const CPS_XCAN& cps, Role& role,
                               bool& extended) const;
  uint32_t check_plan(const Interface& f, const ManagedObject* added,
                      const ManualFilter& manual) const;
  int add_object(unsigned i, const ManagedObject& m, const Object& o);
  ChannelHandle add_channel(Channel c);
  void reset_interface(unsigned i);
  uint32_t write_bitparams(unsigned i, std::span<const uint8_t> data);

  // xcan_driver.cpp: the chip and the requests; xcan_interrupt.cpp: the interrupt
  void init_chip(unsigned i);
  void program_timing(unsigned i);
  void bus_on(unsigned i);
  uint32_t request(unsigned i, const SendRequest& r);
  void serve_status(unsigned i);
  void finished(unsigned i, const SendRequest& r);
  void received(unsigned i, int object, const Frame& frame);
  void unconfigured(unsigned i, const Frame& frame);
  void error_callback(unsigned i);
  bool extended_format(const Interface& f, const CPS_XCAN& cps) const;

  SimScheduler& scheduler_;
  XcanVariant variant_;
  MddVersion mdd_version_ = kMdd3C;
  XcanSink& sink_;
  std::array<Interface, XCAN_INTERFACES> ifaces_;
  std::map<ChannelHandle, Channel> channels_;
  ChannelHandle next_handle_ = 1;
  std::vector<Waiter> waiters_;
  RequestId next_request_ = 1;
};

}  // namespace canemu::model::sorcus
