// The FIFO objects of the VCI C++ API (see fifo_objects.hpp): the reader and writer ends over
// a ring, and the information objects of the stand-alone FIFOs.
#include "fifo_objects.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <mutex>
#include <vector>

#include "com.hpp"
#include "events.hpp"

namespace canemu::client::vci::cpp {

using ipc::VciOp;

namespace {

// What a reader or writer works on: a ring and who keeps it alive.
struct FifoSide {
  std::shared_ptr<void> owner;  // keeps the ring's memory
  const canemu::ipc::RingMemory* memory = nullptr;
  std::function<void()> release;  // gives the side back (one reader, one writer at a time)
  // A channel's transmit FIFO: the size of its messages (CANMSG or CANMSG2), each checked by
  // check_tx_message() before it is handed over. 0: a FIFO of any data, not checked.
  std::size_t tx_message_size = 0;
  bool can_fd = false;  // ... on a CAN FD controller
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
  // A look's result: an empty (full) FIFO found again and again is a polling loop, which
  // gives canemud its turn (PollYield).
  HRESULT polled(HRESULT hr) {
    if (hr == VCI_E_RXQUEUE_EMPTY || hr == VCI_E_TXQUEUE_FULL) {
      looks_.missed();
    } else if (hr == VCI_OK) {
      looks_.hit();
    }
    return hr;
  }
  FifoSide side_;
  std::unique_ptr<Ring> own_;
  Ring& ring_;
  std::recursive_mutex mutex_;
  PollYield looks_;
};

class Reader final : public FifoEnd<IFifoReader, IID_IFifoReader, canemu::ipc::RingReader> {
 public:
  using FifoEnd::FifoEnd;
  HRESULT GetDataEntry(PVOID pvData) override {
    return polled(ring_result(ring_.get(pvData), VCI_E_RXQUEUE_EMPTY));
  }
  HRESULT AcquireRead(PVOID* ppvData, PUINT16 pwCount) override {
    const void* p = nullptr;
    uint32_t n = 0;
    const HRESULT hr = polled(
        ring_result(ring_.acquire(ppvData == nullptr ? nullptr : &p, &n), VCI_E_RXQUEUE_EMPTY));
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
    if (side_.tx_message_size != 0) {
      if (const HRESULT hr = check_tx_message(pvData, side_.tx_message_size, side_.can_fd);
          hr != VCI_OK) {
        return hr;
      }
    }
    return polled(ring_result(ring_.put(pvData), VCI_E_TXQUEUE_FULL));
  }
  HRESULT AcquireWrite(PVOID* ppvData, PUINT16 pwCount) override {
    void* p = nullptr;
    uint32_t n = 0;
    const HRESULT hr = polled(
        ring_result(ring_.acquire(ppvData == nullptr ? nullptr : &p, &n), VCI_E_TXQUEUE_FULL));
    if (hr == VCI_OK) {
      *ppvData = p;
      acquired_ = static_cast<uint8_t*>(p);
      acquired_count_ = n;
      if (pwCount != nullptr) {
        *pwCount = u16(n);
      } else {
        ring_.limit_acquired(1);
        acquired_count_ = std::min<uint32_t>(n, 1);
      }
    }
    return hr;
  }
  HRESULT ReleaseWrite(UINT16 wCount) override {
    // A channel's messages are checked before any is handed over: one that cannot be sent
    // refuses the release, and the program may correct it and release again.
    if (side_.tx_message_size != 0 && acquired_ != nullptr && wCount <= acquired_count_) {
      for (uint32_t i = 0; i < wCount; ++i) {
        const HRESULT hr = check_tx_message(acquired_ + std::size_t{i} * side_.tx_message_size,
                                            side_.tx_message_size, side_.can_fd);
        if (hr != VCI_OK) {
          return hr;
        }
      }
    }
    const HRESULT hr = ring_result(ring_.release(wCount), VCI_E_INVALIDARG);
    if (hr == VCI_OK) {
      acquired_ = nullptr;
      acquired_count_ = 0;
    }
    return hr;
  }

 private:
  uint8_t* acquired_ = nullptr;  // what the last AcquireWrite gave, until its release
  uint32_t acquired_count_ = 0;
};

}  // namespace

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
  FifoSide side{rings, &rings->pair.tx().memory(), [rings] { rings->writer_out = false; }};
  side.tx_message_size = rings->pair.element_size();
  side.can_fd = rings->can_fd;
  *pp = new Writer(std::move(side), rings->tx);
  return VCI_OK;
}

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

}  // namespace canemu::client::vci::cpp
