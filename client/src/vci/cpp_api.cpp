// The VCI C++ API (vcisdk.h) over the same core as the C libraries: reference-counted objects
// that hold the core's remote objects and rings.
#include <atomic>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "can_api.hpp"
#include "events.hpp"
#include "vcisdk.h"

using namespace canemu::client::vci;
using canemu::ipc::VciOp;

// ---------------------------------------------------------------- identifiers

namespace {
// canemu's interface and class identifiers: one family, the last byte numbering them.
constexpr GUID guid(uint8_t n) {
  return GUID{0x3b1f7c02U, 0x6a5e, 0x4d21, {0x8c, 0x3a, 0x27, 0x90, 0x5e, 0x11, 0xc4, n}};
}
bool same(const GUID& a, const GUID& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}
}  // namespace

extern "C" {
const IID IID_IUnknown = {0x00000000U, 0x0000, 0x0000, {0xc0, 0, 0, 0, 0, 0, 0, 0x46}};
const IID IID_IVciDeviceManager = guid(1);
const IID IID_IVciEnumDevice = guid(2);
const IID IID_IVciDevice = guid(3);
const IID IID_IBalObject = guid(4);
const IID IID_ICanSocket = guid(5);
const IID IID_ICanSocket2 = guid(6);
const IID IID_ICanControl = guid(7);
const IID IID_ICanControl2 = guid(8);
const IID IID_ICanChannel = guid(9);
const IID IID_ICanChannel2 = guid(10);
const IID IID_ICanScheduler = guid(11);
const IID IID_ICanScheduler2 = guid(12);
const IID IID_IFifoReader = guid(13);
const IID IID_IFifoWriter = guid(14);
const IID IID_IVciFifo = guid(15);
const IID IID_IVciFifo2 = guid(16);
const CLSID CLSID_VCIBAL = guid(0x80);
}

namespace {

// ---------------------------------------------------------------- reference counting

// The IUnknown part of every object: `Interface` is what it implements, `iid` its identifier
// (QueryInterface gives the object itself for it and for IID_IUnknown).
template <class Interface, const IID& iid>
class Com : public Interface {
 public:
  Com() = default;
  Com(const Com&) = delete;
  Com& operator=(const Com&) = delete;
  HRESULT QueryInterface(REFIID riid, PVOID* ppv) override {
    if (ppv == nullptr) {
      return VCI_E_INVALIDARG;
    }
    if (same(riid, iid) || same(riid, IID_IUnknown)) {
      this->AddRef();
      *ppv = static_cast<Interface*>(this);
      return VCI_OK;
    }
    *ppv = nullptr;
    return VCI_E_NOINTERFACE;
  }
  ULONG AddRef() override { return ++refs_; }
  ULONG Release() override {
    const ULONG n = --refs_;
    if (n == 0) {
      delete this;
    }
    return n;
  }

 protected:
  virtual ~Com() = default;

 private:
  std::atomic<ULONG> refs_{1};
};

template <class T>
HRESULT hand_out(T* object, PVOID* ppv) {
  *ppv = object;
  return VCI_OK;
}

template <class P>
bool null_out(P** pp) {
  if (pp == nullptr) {
    return false;
  }
  *pp = nullptr;
  return true;
}

// ---------------------------------------------------------------- FIFOs

// What a reader or writer works on: a ring and who keeps it alive.
struct FifoSide {
  std::shared_ptr<void> owner;  // keeps the ring's memory
  const canemu::ipc::RingMemory* memory = nullptr;
  std::function<void()> release;  // gives the side back (one reader, one writer at a time)
};

UINT16 u16(uint32_t v) {
  return static_cast<UINT16>(std::min<uint32_t>(v, 0xFFFF));
}

HRESULT ring_result(canemu::ipc::RingStatus s, HRESULT empty_or_full) {
  switch (s) {
    case canemu::ipc::RingStatus::ok:
      return VCI_OK;
    case canemu::ipc::RingStatus::empty:
    case canemu::ipc::RingStatus::full:
      return empty_or_full;
    case canemu::ipc::RingStatus::invalid_argument:
      return VCI_E_INVALIDARG;
    default:
      return VCI_E_UNEXPECTED;
  }
}

// What a FIFO's reader and writer have in common: the lock, the event, the threshold and the
// counts, on the ring `Ring` of their side.
template <class Interface, const IID& iid, class Ring>
class FifoEnd : public Com<Interface, iid> {
 public:
  // On a ring view that lives elsewhere (a channel's), or on one of its own.
  FifoEnd(FifoSide side, Ring& ring) : side_(std::move(side)), ring_(ring) {}
  FifoEnd(FifoSide side, std::unique_ptr<Ring> ring)
      : side_(std::move(side)), own_(std::move(ring)), ring_(*own_) {}
  ~FifoEnd() override {
    unwatch_ring_event(this);
    side_.release();
  }
  HRESULT Lock() override {
    mutex_.lock();
    return VCI_OK;
  }
  HRESULT Unlock() override {
    mutex_.unlock();
    return VCI_OK;
  }
  HRESULT AssignEvent(HANDLE hEvent) override {
    watch_ring_event(this, ring_.own_event(), hEvent);
    return VCI_OK;
  }
  HRESULT SetThreshold(UINT16 w) override {
    ring_.set_threshold(w);
    return VCI_OK;
  }
  HRESULT GetThreshold(PUINT16 p) override { return put(p, ring_.threshold()); }
  HRESULT GetCapacity(PUINT16 p) override { return put(p, side_.memory->capacity()); }
  HRESULT GetEntrySize(PUINT16 p) override { return put(p, side_.memory->element_size()); }
  HRESULT GetFillCount(PUINT16 p) override { return put(p, ring_.fill_count()); }
  HRESULT GetFreeCount(PUINT16 p) override { return put(p, ring_.free_count()); }

 protected:
  static HRESULT put(PUINT16 p, uint32_t v) {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = u16(v);
    return VCI_OK;
  }
  FifoSide side_;
  std::unique_ptr<Ring> own_;
  Ring& ring_;
  std::recursive_mutex mutex_;
};

class Reader final : public FifoEnd<IFifoReader, IID_IFifoReader, canemu::ipc::RingReader> {
 public:
  using FifoEnd::FifoEnd;
  HRESULT GetDataEntry(PVOID pvData) override {
    return ring_result(ring_.get(pvData), VCI_E_RXQUEUE_EMPTY);
  }
  HRESULT AcquireRead(PVOID* ppvData, PUINT16 pwCount) override {
    const void* p = nullptr;
    uint32_t n = 0;
    const HRESULT hr =
        ring_result(ring_.acquire(ppvData == nullptr ? nullptr : &p, &n), VCI_E_RXQUEUE_EMPTY);
    if (hr == VCI_OK) {
      *ppvData = const_cast<void*>(p);
      if (pwCount != nullptr) {
        *pwCount = u16(n);
      } else {
        ring_.limit_acquired(1);  // without a count, one element may be released
      }
    }
    return hr;
  }
  HRESULT ReleaseRead(UINT16 wCount) override {
    return ring_result(ring_.release(wCount), VCI_E_INVALIDARG);
  }
};

class Writer final : public FifoEnd<IFifoWriter, IID_IFifoWriter, canemu::ipc::RingWriter> {
 public:
  using FifoEnd::FifoEnd;
  HRESULT PutDataEntry(PVOID pvData) override {
    if (pvData == nullptr) {
      return VCI_E_INVALIDARG;
    }
    return ring_result(ring_.put(pvData), VCI_E_TXQUEUE_FULL);
  }
  HRESULT AcquireWrite(PVOID* ppvData, PUINT16 pwCount) override {
    void* p = nullptr;
    uint32_t n = 0;
    const HRESULT hr =
        ring_result(ring_.acquire(ppvData == nullptr ? nullptr : &p, &n), VCI_E_TXQUEUE_FULL);
    if (hr == VCI_OK) {
      *ppvData = p;
      if (pwCount != nullptr) {
        *pwCount = u16(n);
      } else {
        ring_.limit_acquired(1);
      }
    }
    return hr;
  }
  HRESULT ReleaseWrite(UINT16 wCount) override {
    return ring_result(ring_.release(wCount), VCI_E_INVALIDARG);
  }
};

HRESULT get_reader(const std::shared_ptr<Rings>& rings, IFifoReader** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  if (!rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  if (rings->reader_out.exchange(true)) {
    return VCI_E_ACCESSDENIED;
  }
  *pp = new Reader(
      FifoSide{rings, &rings->pair.rx().memory(), [rings] { rings->reader_out = false; }},
      rings->rx);
  return VCI_OK;
}

HRESULT get_writer(const std::shared_ptr<Rings>& rings, IFifoWriter** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  if (!rings || !rings->has_tx) {
    return rings ? VCI_E_ACCESSDENIED : VCI_E_NOT_INITIALIZED;
  }
  if (rings->writer_out.exchange(true)) {
    return VCI_E_ACCESSDENIED;
  }
  *pp = new Writer(
      FifoSide{rings, &rings->pair.tx().memory(), [rings] { rings->writer_out = false; }},
      rings->tx);
  return VCI_OK;
}

// A stand-alone FIFO (VciCreateFifo / VciAccessFifo): a ring canemud holds for the processes
// that use it; each side (reader, writer) is taken from canemud, so there is one of each in all
// processes together. A side's ring view is made when it is taken (the positions in shared
// memory are where the last holder left them).
struct SharedFifo {
  uint64_t id = 0;
  canemu::ipc::SharedRing ring;
  const canemu::ipc::RingMemory& memory() const { return ring.memory(); }
  uint32_t fill() const {
    const auto* h = ring.memory().header();
    return static_cast<uint32_t>(h->write_pos.load(std::memory_order_acquire) -
                                 h->read_pos.load(std::memory_order_acquire));
  }
};

std::mutex g_fifos_mutex;
std::map<uint64_t, std::weak_ptr<SharedFifo>> g_fifos;  // this process's views, by id

enum Side : uint32_t { kReaderSide = 0, kWriterSide = 1 };

HRESULT side_call(uint64_t id, Side side, bool take) {
  canemu::ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(VciOp::fifo_side);
  m.args[0] = static_cast<uint32_t>(id);
  m.args[1] = static_cast<uint32_t>(id >> 32);
  m.args[2] = side;
  m.args[3] = take ? 1 : 0;
  canemu::ipc::VciReply r{};
  return Library::get().call(m, r);
}

// Creates (`create`: capacity and size) or reaches (`id`) a FIFO through canemud.
HRESULT shared_fifo(VciOp op, uint32_t a0, uint32_t a1, std::shared_ptr<SharedFifo>& out) {
  canemu::ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(op);
  m.args[0] = a0;
  m.args[1] = a1;
  canemu::ipc::VciReply r{};
  std::vector<canemu::ipc::UniqueFd> fds;
  if (HRESULT hr = Library::get().call(m, r, &fds); hr != VCI_OK) {
    return hr;
  }
  if (fds.size() != canemu::ipc::kFifoFdCount) {
    return VCI_E_UNEXPECTED;
  }
  const uint64_t id = uint64_t{r.values[0]} | (uint64_t{r.values[1]} << 32);
  std::lock_guard lock(g_fifos_mutex);
  if (auto known = g_fifos[id].lock()) {
    out = known;  // this process has it mapped already
    return VCI_OK;
  }
  auto ring =
      canemu::ipc::SharedRing::map(std::move(fds[0]), std::move(fds[1]), std::move(fds[2]), 0);
  if (!ring) {
    return VCI_E_UNEXPECTED;
  }
  out = std::make_shared<SharedFifo>(SharedFifo{id, std::move(*ring)});
  g_fifos[id] = out;
  return VCI_OK;
}

template <class Interface, const IID& iid>
class FifoInfo : public Com<Interface, iid> {
 public:
  explicit FifoInfo(std::shared_ptr<SharedFifo> f) : f_(std::move(f)) {}
  HRESULT GetCapacity(PUINT16 p) override { return put(p, f_->memory().capacity()); }
  HRESULT GetEntrySize(PUINT16 p) override { return put(p, f_->memory().element_size()); }
  HRESULT GetFreeCount(PUINT16 p) override { return put(p, f_->memory().capacity() - f_->fill()); }
  HRESULT GetFillCount(PUINT16 p) override { return put(p, f_->fill()); }
  HRESULT GetFillLevel(PUINT16 p) override {
    return put(p, f_->fill() * 100 / f_->memory().capacity());
  }

 protected:
  static HRESULT put(PUINT16 p, uint32_t v) {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = u16(v);
    return VCI_OK;
  }
  std::shared_ptr<SharedFifo> f_;
};

class Fifo2 final : public FifoInfo<IVciFifo2, IID_IVciFifo2> {
 public:
  using FifoInfo::FifoInfo;
  HRESULT Reset() override {
    // Only while nobody anywhere has a reader or writer: both sides are taken for the time.
    if (HRESULT hr = side_call(f_->id, kReaderSide, true); hr != VCI_OK) {
      return hr;
    }
    if (HRESULT hr = side_call(f_->id, kWriterSide, true); hr != VCI_OK) {
      side_call(f_->id, kReaderSide, false);
      return hr;
    }
    canemu::ipc::RingReader reader = f_->ring.reader();
    while (reader.get(nullptr) == canemu::ipc::RingStatus::ok) {
    }
    side_call(f_->id, kWriterSide, false);
    side_call(f_->id, kReaderSide, false);
    return VCI_OK;
  }
};

HRESULT open_fifo(const std::shared_ptr<SharedFifo>& f, REFIID riid, PVOID* ppv) {
  const bool reader = same(riid, IID_IFifoReader);
  if (reader || same(riid, IID_IFifoWriter)) {
    const Side side = reader ? kReaderSide : kWriterSide;
    if (HRESULT hr = side_call(f->id, side, true); hr != VCI_OK) {
      return hr;
    }
    FifoSide fs{f, &f->memory(), [f, side] { side_call(f->id, side, false); }};
    if (reader) {
      return hand_out(
          static_cast<IFifoReader*>(new Reader(
              std::move(fs), std::make_unique<canemu::ipc::RingReader>(f->ring.reader()))),
          ppv);
    }
    return hand_out(
        static_cast<IFifoWriter*>(
            new Writer(std::move(fs), std::make_unique<canemu::ipc::RingWriter>(f->ring.writer()))),
        ppv);
  }
  if (same(riid, IID_IVciFifo)) {
    return hand_out(static_cast<IVciFifo*>(new FifoInfo<IVciFifo, IID_IVciFifo>(f)), ppv);
  }
  if (same(riid, IID_IVciFifo2)) {
    return hand_out(static_cast<IVciFifo2*>(new Fifo2(f)), ppv);
  }
  return VCI_E_NOINTERFACE;
}

// ---------------------------------------------------------------- CAN objects

// What the socket, control and channel objects have in common: the controller they are on.
struct Bus {
  DeviceDesc device;
  UINT32 no = 0;
};

template <class T>
HRESULT line_struct_of(const Bus& bus, const Remote* remote, std::size_t offset, T* out) {
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  canemu::ipc::VciReply reply{};
  HRESULT hr;
  if (remote != nullptr) {
    hr = Library::get().line_info(*remote, reply);
  } else {
    canemu::ipc::VciRequest m{};
    m.op = static_cast<uint16_t>(VciOp::line_info);
    canemu::ipc::copy_name(m.device, bus.device.name);
    m.controller = bus.no;
    hr = Library::get().call(m, reply);
  }
  if (hr == VCI_OK) {
    std::memcpy(out, reply.payload + offset, sizeof(T));
  }
  return hr;
}

HRESULT filter_of(const Remote& r, VciOp op, uint32_t kind, UINT8 select, UINT8 mode, UINT32 code,
                  UINT32 mask, PUINT8 mode_out) {
  if (select != CAN_FILTER_STD && select != CAN_FILTER_EXT) {
    return VCI_E_INVALIDARG;
  }
  return Library::get().filter(r, op, kind, select == CAN_FILTER_EXT, mode, code, mask, mode_out);
}

HRESULT init_line(const Remote& r, const void* init, std::size_t size, bool v2) {
  canemu::ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(VciOp::control_init);
  m.flags = v2 ? canemu::ipc::kVciV2 : 0;
  m.handle = r.handle;
  std::memcpy(m.payload, init, size);
  canemu::ipc::VciReply reply{};
  return Library::get().call(m, reply);
}

template <class Interface, const IID& iid, bool v2>
class Control final : public Com<Interface, iid> {
 public:
  Control(Bus bus, std::unique_ptr<Remote> remote) : bus_(std::move(bus)), r_(std::move(remote)) {
    register_alias(static_cast<Interface*>(this), r_.get());
  }
  ~Control() override { unregister_alias(static_cast<Interface*>(this)); }
  HRESULT ResetLine() override { return Library::get().simple(*r_, VciOp::control_reset); }
  HRESULT StartLine() override { return Library::get().simple(*r_, VciOp::control_start); }
  HRESULT StopLine() override { return Library::get().simple(*r_, VciOp::control_stop); }
  HRESULT SetAccFilter(UINT8 s, UINT32 code, UINT32 mask) override {
    return filter_of(*r_, VciOp::control_filter, kFilterAcceptance, s, 0, code, mask, nullptr);
  }
  HRESULT AddFilterIds(UINT8 s, UINT32 code, UINT32 mask) override {
    return filter_of(*r_, VciOp::control_filter, kFilterAddIds, s, 0, code, mask, nullptr);
  }
  HRESULT RemFilterIds(UINT8 s, UINT32 code, UINT32 mask) override {
    return filter_of(*r_, VciOp::control_filter, kFilterRemoveIds, s, 0, code, mask, nullptr);
  }

  // ICanControl
  HRESULT DetectBaud(UINT16 timeout_ms, PCANBTRTABLE table) {
    if (table == nullptr || table->bCount == 0 || table->bCount > 64) {
      return VCI_E_INVALIDARG;
    }
    // bIndex CAN_OPMODE_LOWSPEED asks for the low-speed coupling (only on a low-speed bus).
    const uint8_t op_mode = table->bIndex == CAN_OPMODE_LOWSPEED ? CAN_OPMODE_LOWSPEED : 0;
    uint32_t index = 0;
    const HRESULT hr =
        Library::get().detect(*r_, false, table, sizeof *table, timeout_ms, op_mode, 0, index);
    if (hr == VCI_OK) {
      table->bIndex = static_cast<UINT8>(index);
    }
    return hr;
  }
  HRESULT InitLine(PCANINITLINE p) {
    return p == nullptr ? VCI_E_INVALIDARG : init_line(*r_, p, sizeof *p, false);
  }
  HRESULT GetLineStatus(PCANLINESTATUS p) {
    return line_struct_of(bus_, r_.get(), canemu::ipc::kVciLineOffset, p);
  }
  // ICanControl2
  HRESULT DetectBaud(UINT8 op_mode, UINT8 ex_mode, UINT16 timeout_ms, PCANBTPTABLE table) {
    if (table == nullptr || table->bCount == 0 || table->bCount > 64) {
      return VCI_E_INVALIDARG;
    }
    uint32_t index = 0;
    const HRESULT hr =
        Library::get().detect(*r_, true, table, sizeof *table, timeout_ms, op_mode, ex_mode, index);
    if (hr == VCI_OK) {
      table->bIndex = static_cast<UINT8>(index);
    }
    return hr;
  }
  HRESULT InitLine(PCANINITLINE2 p) {
    return p == nullptr ? VCI_E_INVALIDARG : init_line(*r_, p, sizeof *p, true);
  }
  HRESULT GetLineStatus(PCANLINESTATUS2 p) {
    return line_struct_of(bus_, r_.get(), canemu::ipc::kVciLine2Offset, p);
  }
  HRESULT GetFilterMode(UINT8 s, PUINT8 mode) {
    if (mode == nullptr) {
      return VCI_E_INVALIDARG;
    }
    return filter_of(*r_, VciOp::control_filter, kFilterGetMode, s, 0, 0, 0, mode);
  }
  HRESULT SetFilterMode(UINT8 s, UINT8 mode, PUINT8 previous) {
    return filter_of(*r_, VciOp::control_filter, kFilterSetMode, s, mode, 0, 0, previous);
  }

 private:
  Bus bus_;
  std::unique_ptr<Remote> r_;
};
using CanControl1 = Control<ICanControl, IID_ICanControl, false>;
using CanControl2 = Control<ICanControl2, IID_ICanControl2, true>;

HRESULT open_remote(const Bus& bus, Object::Kind kind, bool v2, bool exclusive,
                    std::unique_ptr<Remote>& out) {
  VciOp op = VciOp::control_open;
  if (kind == Object::Kind::channel) {
    op = VciOp::channel_open;
  } else if (kind == Object::Kind::scheduler) {
    op = VciOp::scheduler_open;
  }
  uint32_t handle = 0;
  const uint16_t flags = static_cast<uint16_t>((v2 ? canemu::ipc::kVciV2 : 0) |
                                               (exclusive ? canemu::ipc::kVciExclusive : 0));
  if (HRESULT hr = Library::get().open_remote(op, flags, bus.device, bus.no, handle);
      hr != VCI_OK) {
    return hr;
  }
  if (kind == Object::Kind::channel) {
    out = std::make_unique<ChannelObj>(handle, bus.device, bus.no, v2);
  } else {
    out = std::make_unique<Remote>(kind, handle, bus.device, bus.no);
  }
  return VCI_OK;
}

template <class Interface, const IID& iid, bool v2>
class Channel final : public Com<Interface, iid> {
 public:
  Channel(Bus bus, std::unique_ptr<Remote> remote)
      : bus_(std::move(bus)), c_(static_cast<ChannelObj*>(remote.release())) {
    register_alias(static_cast<Interface*>(this), c_.get());
  }
  ~Channel() override { unregister_alias(static_cast<Interface*>(this)); }
  HRESULT GetReader(IFifoReader** pp) override { return get_reader(c_->rings, pp); }
  HRESULT GetWriter(IFifoWriter** pp) override { return get_writer(c_->rings, pp); }
  HRESULT Activate() override { return Library::get().simple(*c_, VciOp::channel_activate); }
  HRESULT Deactivate() override { return Library::get().simple(*c_, VciOp::channel_deactivate); }

  // ICanChannel
  HRESULT Initialize(UINT16 rx, UINT16 tx) {
    if (rx == 0) {
      return VCI_E_INVALIDARG;
    }
    return Library::get().init_channel(*c_, rx, 1, tx, 1, 0, CAN_FILTER_PASS);
  }
  HRESULT GetStatus(PCANCHANSTATUS p) {
    return channel_status_of(*c_, canemu::ipc::kVciLineOffset, p);
  }
  // ICanChannel2
  HRESULT Initialize(UINT32 rx, UINT32 tx, UINT32 filter_size, UINT8 mode) {
    if (rx == 0) {
      return VCI_E_INVALIDARG;
    }
    return Library::get().init_channel(*c_, rx, 1, tx, 1, filter_size, mode);
  }
  HRESULT GetStatus(PCANCHANSTATUS2 p) {
    return channel_status_of(*c_, canemu::ipc::kVciLine2Offset, p);
  }
  HRESULT GetControl(PCANCONTROL2* pp) {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    std::unique_ptr<Remote> r;
    if (HRESULT hr = open_remote(bus_, Object::Kind::control, true, false, r); hr != VCI_OK) {
      return hr;
    }
    *pp = new CanControl2(bus_, std::move(r));
    return VCI_OK;
  }
  HRESULT GetFilterMode(UINT8 s, PUINT8 mode) {
    if (mode == nullptr) {
      return VCI_E_INVALIDARG;
    }
    return filter_of(*c_, VciOp::channel_filter, kFilterGetMode, s, 0, 0, 0, mode);
  }
  HRESULT SetFilterMode(UINT8 s, UINT8 mode, PUINT8 previous) {
    return filter_of(*c_, VciOp::channel_filter, kFilterSetMode, s, mode, 0, 0, previous);
  }
  HRESULT SetAccFilter(UINT8 s, UINT32 code, UINT32 mask) {
    return filter_of(*c_, VciOp::channel_filter, kFilterAcceptance, s, 0, code, mask, nullptr);
  }
  HRESULT AddFilterIds(UINT8 s, UINT32 code, UINT32 mask) {
    return filter_of(*c_, VciOp::channel_filter, kFilterAddIds, s, 0, code, mask, nullptr);
  }
  HRESULT RemFilterIds(UINT8 s, UINT32 code, UINT32 mask) {
    return filter_of(*c_, VciOp::channel_filter, kFilterRemoveIds, s, 0, code, mask, nullptr);
  }

 private:
  Bus bus_;
  std::unique_ptr<ChannelObj> c_;
};
using CanChannel1 = Channel<ICanChannel, IID_ICanChannel, false>;
using CanChannel2 = Channel<ICanChannel2, IID_ICanChannel2, true>;

template <class Interface, const IID& iid, bool v2>
class Scheduler final : public Com<Interface, iid> {
 public:
  Scheduler(Bus bus, std::unique_ptr<Remote> remote) : bus_(std::move(bus)), r_(std::move(remote)) {
    register_alias(static_cast<Interface*>(this), r_.get());
  }
  ~Scheduler() override { unregister_alias(static_cast<Interface*>(this)); }
  HRESULT Resume() override { return Library::get().simple(*r_, VciOp::scheduler_resume); }
  HRESULT Suspend() override { return Library::get().simple(*r_, VciOp::scheduler_suspend); }
  HRESULT Reset() override { return Library::get().simple(*r_, VciOp::scheduler_reset); }
  HRESULT RemMessage(UINT32 i) override {
    return Library::get().simple(*r_, VciOp::scheduler_remove, {i});
  }
  HRESULT StartMessage(UINT32 i, UINT16 n) override {
    return Library::get().simple(*r_, VciOp::scheduler_start, {i, n});
  }
  HRESULT StopMessage(UINT32 i) override {
    return Library::get().simple(*r_, VciOp::scheduler_stop, {i});
  }
  // ICanScheduler
  HRESULT GetStatus(PCANSCHEDULERSTATUS p) {
    return p == nullptr ? VCI_E_INVALIDARG : scheduler_status_of(*r_, &p->bTaskStat, p->abMsgStat);
  }
  HRESULT AddMessage(PCANCYCLICTXMSG p, PUINT32 index) {
    if (p == nullptr) {
      return failed_add(index);
    }
    return scheduler_add_of(*r_, to_cyclic2(*p), index);
  }
  // ICanScheduler2
  HRESULT GetStatus(PCANSCHEDULERSTATUS2 p) {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    if (HRESULT hr = line_struct_of(bus_, r_.get(), canemu::ipc::kVciLine2Offset, &p->sLineStatus);
        hr != VCI_OK) {
      return hr;
    }
    return scheduler_status_of(*r_, &p->bTaskStat, p->abMsgStat);
  }
  HRESULT AddMessage(PCANCYCLICTXMSG2 p, PUINT32 index) {
    return p == nullptr ? failed_add(index) : scheduler_add_of(*r_, *p, index);
  }

 private:
  static HRESULT failed_add(PUINT32 index) {
    if (index != nullptr) {
      *index = 0xFFFFFFFFU;
    }
    return VCI_E_INVALIDARG;
  }
  Bus bus_;
  std::unique_ptr<Remote> r_;
};

template <class Interface, const IID& iid, bool v2>
class Socket final : public Com<Interface, iid> {
 public:
  explicit Socket(Bus bus) : bus_(std::move(bus)) {}
  HRESULT GetSocketInfo(PBALSOCKETINFO p) override {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    p->Obid.AsInt64 = static_cast<INT64>((bus_.device.vci_id << 8) | bus_.no);
    p->Type = bus_.device.caps().BusCtrlTypes[bus_.no];
    p->BusNo = static_cast<UINT16>(bus_.no);
    return VCI_OK;
  }
  // ICanSocket
  HRESULT GetCapabilities(PCANCAPABILITIES p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciCapsOffset, p);
  }
  HRESULT GetLineStatus(PCANLINESTATUS p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciLineOffset, p);
  }
  HRESULT CreateChannel(BOOL exclusive, PCANCHANNEL* pp) { return create(exclusive, pp); }
  // ICanSocket2
  HRESULT GetCapabilities(PCANCAPABILITIES2 p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciCaps2Offset, p);
  }
  HRESULT GetLineStatus(PCANLINESTATUS2 p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciLine2Offset, p);
  }
  HRESULT CreateChannel(BOOL exclusive, PCANCHANNEL2* pp) { return create(exclusive, pp); }

 private:
  template <class P>
  HRESULT create(BOOL exclusive, P** pp) {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    std::unique_ptr<Remote> r;
    if (HRESULT hr = open_remote(bus_, Object::Kind::channel, v2, exclusive != 0, r);
        hr != VCI_OK) {
      return hr;
    }
    if constexpr (v2) {
      *pp = new CanChannel2(bus_, std::move(r));
    } else {
      *pp = new CanChannel1(bus_, std::move(r));
    }
    return VCI_OK;
  }
  Bus bus_;
};

class Bal final : public Com<IBalObject, IID_IBalObject> {
 public:
  explicit Bal(DeviceDesc d) : d_(std::move(d)) {}
  HRESULT GetFeatures(PBALFEATURES p) override {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = BALFEATURES{};
    p->FwMajorVersion = 1;
    p->FwMinorVersion = 0;
    const VCIDEVICECAPS caps = d_.caps();
    p->BusSocketCount = caps.BusCtrlCount;
    std::memcpy(p->BusSocketType, caps.BusCtrlTypes, sizeof caps.BusCtrlTypes);
    return VCI_OK;
  }
  HRESULT OpenSocket(UINT32 bus_no, REFIID riid, PVOID* ppv) override {
    if (!null_out(ppv)) {
      return VCI_E_INVALIDARG;
    }
    if (bus_no >= d_.controller_fd.size()) {
      return VCI_E_INVALIDARG;
    }
    const Bus bus{d_, bus_no};
    std::unique_ptr<Remote> r;
    if (same(riid, IID_ICanSocket)) {
      return hand_out(static_cast<ICanSocket*>(new Socket<ICanSocket, IID_ICanSocket, false>(bus)),
                      ppv);
    }
    if (same(riid, IID_ICanSocket2)) {
      return hand_out(
          static_cast<ICanSocket2*>(new Socket<ICanSocket2, IID_ICanSocket2, true>(bus)), ppv);
    }
    const bool control1 = same(riid, IID_ICanControl);
    const bool control2 = same(riid, IID_ICanControl2);
    const bool list1 = same(riid, IID_ICanScheduler);
    const bool list2 = same(riid, IID_ICanScheduler2);
    if (!control1 && !control2 && !list1 && !list2) {
      return VCI_E_NOINTERFACE;
    }
    const Object::Kind kind =
        control1 || control2 ? Object::Kind::control : Object::Kind::scheduler;
    if (HRESULT hr = open_remote(bus, kind, control2 || list2, false, r); hr != VCI_OK) {
      return hr;
    }
    if (control1) {
      return hand_out(static_cast<ICanControl*>(new CanControl1(bus, std::move(r))), ppv);
    }
    if (control2) {
      return hand_out(static_cast<ICanControl2*>(new CanControl2(bus, std::move(r))), ppv);
    }
    if (list1) {
      return hand_out(
          static_cast<ICanScheduler*>(
              new Scheduler<ICanScheduler, IID_ICanScheduler, false>(bus, std::move(r))),
          ppv);
    }
    return hand_out(static_cast<ICanScheduler2*>(
                        new Scheduler<ICanScheduler2, IID_ICanScheduler2, true>(bus, std::move(r))),
                    ppv);
  }

 private:
  DeviceDesc d_;
};

class VciDevice final : public Com<IVciDevice, IID_IVciDevice> {
 public:
  explicit VciDevice(DeviceDesc d) : d_(std::move(d)) {}
  HRESULT GetDeviceInfo(PVCIDEVICEINFO p) override {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = d_.info();
    return VCI_OK;
  }
  HRESULT GetDeviceCaps(PVCIDEVICECAPS p) override {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = d_.caps();
    return VCI_OK;
  }
  HRESULT OpenComponent(REFCLSID rclsid, REFIID riid, PVOID* ppv) override {
    if (!null_out(ppv)) {
      return VCI_E_INVALIDARG;
    }
    if (!same(rclsid, CLSID_VCIBAL)) {
      return VCI_E_INVALIDARG;  // the BAL is the only component
    }
    if (!same(riid, IID_IBalObject) && !same(riid, IID_IUnknown)) {
      return VCI_E_NOINTERFACE;
    }
    return hand_out(static_cast<IBalObject*>(new Bal(d_)), ppv);
  }

 private:
  DeviceDesc d_;
};

class EnumDevice final : public Com<IVciEnumDevice, IID_IVciEnumDevice> {
 public:
  EnumDevice(std::vector<DeviceDesc> devices, uint32_t generation)
      : devices_(std::move(devices)), generation_(generation) {}
  ~EnumDevice() override { stop_watch(); }
  HRESULT Next(UINT32 n, PVCIDEVICEINFO out, PUINT32 fetched) override {
    if (out == nullptr || (fetched == nullptr && n != 1)) {
      return VCI_E_INVALIDARG;
    }
    UINT32 k = 0;
    for (; k < n && next_ < devices_.size(); ++k) {
      out[k] = devices_[next_++].info();
    }
    if (fetched != nullptr) {
      *fetched = k;
    }
    return k == 0 && n > 0 ? VCI_E_NO_MORE_ITEMS : VCI_OK;
  }
  HRESULT Skip(UINT32 n) override {
    next_ = std::min<std::size_t>(devices_.size(), next_ + n);
    return VCI_OK;
  }
  HRESULT Reset() override {
    std::vector<DeviceDesc> fresh;
    uint32_t generation = 0;
    if (HRESULT hr = Library::get().list_devices(fresh, &generation); hr != VCI_OK) {
      return hr;
    }
    devices_ = std::move(fresh);
    generation_ = generation;
    next_ = 0;
    return VCI_OK;
  }
  HRESULT AssignEvent(HANDLE event) override {
    stop_watch();
    if (event == nullptr) {
      return VCI_OK;
    }
    // A thread of its own waits for device changes and signals the event.
    stop_ = std::make_shared<std::atomic<bool>>(false);
    watcher_ = std::thread([stop = stop_, event, generation = generation_]() mutable {
      while (!*stop) {
        if (Library::get().wait_device_change(generation, 200) == VCI_OK && !*stop) {
          SetEvent(event);
          std::vector<DeviceDesc> ignored;
          Library::get().list_devices(ignored, &generation);
        }
      }
    });
    return VCI_OK;
  }

 private:
  void stop_watch() {
    if (watcher_.joinable()) {
      *stop_ = true;
      watcher_.join();
    }
  }
  std::vector<DeviceDesc> devices_;
  std::size_t next_ = 0;
  uint32_t generation_ = 0;
  std::shared_ptr<std::atomic<bool>> stop_;
  std::thread watcher_;
};

class DeviceManager final : public Com<IVciDeviceManager, IID_IVciDeviceManager> {
 public:
  HRESULT EnumDevices(IVciEnumDevice** pp) override {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    std::vector<DeviceDesc> devices;
    uint32_t generation = 0;
    if (HRESULT hr = Library::get().list_devices(devices, &generation); hr != VCI_OK) {
      return hr;
    }
    *pp = new EnumDevice(std::move(devices), generation);
    return VCI_OK;
  }
  HRESULT OpenDevice(REFVCIID id, IVciDevice** pp) override {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    HRESULT hr = VCI_OK;
    if (auto d = device_by_id(id.AsInt64, hr)) {
      *pp = new VciDevice(std::move(*d));
    }
    return hr;
  }
};

int hex(char c) {
  if (c >= '0' && c <= '9') {
    return c - '0';
  }
  if (c >= 'a' && c <= 'f') {
    return c - 'a' + 10;
  }
  if (c >= 'A' && c <= 'F') {
    return c - 'A' + 10;
  }
  return -1;
}

// Reads `digits` hex digits at `p` into `out`; false on anything else.
bool read_hex(const char*& p, int digits, uint64_t& out) {
  out = 0;
  for (int i = 0; i < digits; ++i) {
    const int v = hex(p[i]);
    if (v < 0) {
      return false;
    }
    out = (out << 4) | static_cast<uint64_t>(v);
  }
  p += digits;
  return true;
}

}  // namespace

// ---------------------------------------------------------------- functions

extern "C" {

HRESULT VCIAPI VciInitialize(void) {
  return VCI_OK;
}

HRESULT VCIAPI VciFormatError(HRESULT hrError, PTCHAR pszError, UINT32 dwLength) {
  if (pszError == nullptr || dwLength == 0) {
    return VCI_E_INVALIDARG;
  }
  std::snprintf(pszError, dwLength, "%s", format_error(hrError).c_str());
  return VCI_OK;
}

HRESULT VCIAPI VciGetVersion(PVCIVERSIONINFO p) {
  if (p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *p = VCIVERSIONINFO{4, 0, 0, 0, 0, 0, 0, 0};
  return VCI_OK;
}

HRESULT VCIAPI VciCreateLuid(PVCIID p) {
  if (p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  static std::atomic<int64_t> next{1};
  // Unique in this process: its pid above, a counter below.
  p->AsInt64 = (static_cast<int64_t>(::getpid()) << 32) | next++;
  return VCI_OK;
}

HRESULT VCIAPI VciLuidToChar(REFVCIID rVciid, PCHAR psz, LONG cbSize) {
  if (psz == nullptr || cbSize <= 0) {
    return VCI_E_INVALIDARG;
  }
  if (cbSize < 17) {
    return VCI_E_BUFFER_OVERFLOW;
  }
  std::snprintf(psz, static_cast<std::size_t>(cbSize), "%016" PRIX64,
                static_cast<uint64_t>(rVciid.AsInt64));
  return VCI_OK;
}

HRESULT VCIAPI VciCharToLuid(PCHAR psz, PVCIID p) {
  if (psz == nullptr || p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  const char* s = psz;
  uint64_t v = 0;
  if (std::strlen(psz) != 16 || !read_hex(s, 16, v)) {
    return VCI_E_FAIL;
  }
  p->AsInt64 = static_cast<INT64>(v);
  return VCI_OK;
}

HRESULT VCIAPI VciGuidToChar(REFGUID g, PCHAR psz, LONG cbSize) {
  if (psz == nullptr || cbSize <= 0) {
    return VCI_E_INVALIDARG;
  }
  if (cbSize < 39) {
    return VCI_E_BUFFER_OVERFLOW;
  }
  std::snprintf(psz, static_cast<std::size_t>(cbSize),
                "{%08X-%04X-%04X-%02X%02X-%02X%02X%02X%02X%02X%02X}", g.Data1, g.Data2, g.Data3,
                g.Data4[0], g.Data4[1], g.Data4[2], g.Data4[3], g.Data4[4], g.Data4[5], g.Data4[6],
                g.Data4[7]);
  return VCI_OK;
}

HRESULT VCIAPI VciCharToGuid(PCHAR psz, PGUID p) {
  if (psz == nullptr || p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  const char* s = psz;
  uint64_t a = 0;
  uint64_t b = 0;
  uint64_t c = 0;
  uint64_t d = 0;
  uint64_t e = 0;
  const bool ok = std::strlen(psz) == 38 && *s++ == '{' && read_hex(s, 8, a) && *s++ == '-' &&
                  read_hex(s, 4, b) && *s++ == '-' && read_hex(s, 4, c) && *s++ == '-' &&
                  read_hex(s, 4, d) && *s++ == '-' && read_hex(s, 12, e) && *s == '}';
  if (!ok) {
    return VCI_E_FAIL;
  }
  p->Data1 = static_cast<UINT32>(a);
  p->Data2 = static_cast<UINT16>(b);
  p->Data3 = static_cast<UINT16>(c);
  p->Data4[0] = static_cast<UINT8>(d >> 8);
  p->Data4[1] = static_cast<UINT8>(d);
  for (int i = 0; i < 6; ++i) {
    p->Data4[2 + i] = static_cast<UINT8>(e >> (40 - 8 * i));
  }
  return VCI_OK;
}

HRESULT VCIAPI VciGetDeviceManager(IVciDeviceManager** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  if (HRESULT hr = Library::get().connect(); hr != VCI_OK) {
    return hr;
  }
  *pp = new DeviceManager;
  return VCI_OK;
}

HRESULT VCIAPI VciQueryDeviceByHwid(REFGUID rHwid, IVciDevice** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  HRESULT hr = VCI_OK;
  if (auto d = device_by_hwid(rHwid, hr)) {
    *pp = new VciDevice(std::move(*d));
  }
  return hr;
}

HRESULT VCIAPI VciQueryDeviceByClass(REFGUID rClass, UINT32 dwInst, IVciDevice** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  HRESULT hr = VCI_OK;
  if (auto d = device_by_class(rClass, dwInst, hr)) {
    *pp = new VciDevice(std::move(*d));
  }
  return hr;
}

HRESULT VCIAPI VciCreateFifo(PVCIID pResid, UINT16 wCapacity, UINT16 wElementSize, REFIID riid,
                             PVOID* ppv) {
  if (!null_out(ppv) || pResid == nullptr || wCapacity == 0 || wElementSize == 0) {
    return VCI_E_INVALIDARG;
  }
  std::shared_ptr<SharedFifo> fifo;
  if (HRESULT hr = shared_fifo(VciOp::fifo_create, wCapacity, wElementSize, fifo); hr != VCI_OK) {
    return hr;
  }
  pResid->AsInt64 = static_cast<INT64>(fifo->id);
  return open_fifo(fifo, riid, ppv);
}

HRESULT VCIAPI VciAccessFifo(REFVCIID rResid, REFIID riid, PVOID* ppv) {
  if (!null_out(ppv)) {
    return VCI_E_INVALIDARG;
  }
  const auto id = static_cast<uint64_t>(rResid.AsInt64);
  std::shared_ptr<SharedFifo> fifo;
  if (HRESULT hr = shared_fifo(VciOp::fifo_access, static_cast<uint32_t>(id),
                               static_cast<uint32_t>(id >> 32), fifo);
      hr != VCI_OK) {
    return hr;
  }
  return open_fifo(fifo, riid, ppv);
}

}  // extern "C"
