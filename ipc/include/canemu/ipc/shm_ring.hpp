// A single-producer single-consumer ring of fixed-size elements in shared memory, with the VCI
// FIFO semantics (VCI C++ guide 4 and 7.4.1): capacity at least the request,
// PutDataEntry/GetDataEntry, AcquireWrite/ReleaseWrite, AcquireRead/ReleaseRead, fill and free
// counts, and threshold events signalled only on the opposite side's access.
//
// Layout: RingHeader (the data part, trivially laid out, checked by magic, ABI version and
// sizes) followed by capacity x element_size bytes. RingWriter and RingReader are the two views;
// each process holds one. Positions are free-running 64-bit element counts; each side writes
// only its own position and reads the other's with acquire order, which is all an SPSC ring
// needs. Everything read from the other side is validated: a position that would put more than
// `capacity` elements in the ring, or move backwards, marks the ring corrupted and every
// further operation fails (the daemon then drops that client).
//
// Events: each side has an auto-reset event (a flag in the header plus an eventfd). Signalling
// sets the flag and writes the eventfd only if the other side is blocked in wait(), so a busy
// ring makes no system call per element. The "waiting" flags share a cache line that is only
// written around a sleep: a signal reads the other side's flag and changes it only when it was
// set, so a busy ring's signals move no cache line between the processes. Each side also reads
// the other's position only when its last reading leaves no room (no elements) for the access,
// and, for a threshold above 1, when it must know the exact fill (free) level.
// The signal's store-load order (position, then the other side's waiting flag) against the
// waiter's (waiting flag, then position) is kept asymmetrically when both processes could
// register for membarrier(2)'s global expedited barrier: the signal costs a compiler barrier,
// and the side about to sleep pays the barrier for both (an interrupt to the CPUs running the
// other processes), once per sleep instead of a fence per element. Otherwise both use fences.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "canemu/ipc/seqpacket.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::ipc {

inline constexpr uint32_t kRingMagic = 0x474E4952;  // "RING"
inline constexpr uint16_t kRingAbiVersion = 2;

struct alignas(64) RingHeader {
  uint32_t magic;
  uint16_t abi_version;
  uint16_t reserved;
  uint32_t element_size;
  uint32_t capacity;  // elements
  uint64_t total_bytes;
  // Whether the processes of the ring registered for membarrier's global expedited barrier.
  // creator_barrier: 1 when the creator did (written before anyone else sees the ring).
  // mapper_barrier: 0 before anyone mapped it, 1 while every process that mapped it did, 2
  // (for good) once one did not or its barrier failed.
  std::atomic<uint32_t> creator_barrier;
  std::atomic<uint32_t> mapper_barrier;
  // Written by the writer (the thresholds also by the reader, seldom).
  alignas(64) std::atomic<uint64_t> write_pos;
  std::atomic<uint32_t> reader_threshold;  // the reader's event fires at fill >= threshold
  std::atomic<uint32_t> reader_signalled;  // auto-reset event flag of the reader
  std::atomic<uint32_t> overruns;          // elements the writer could not put
  // Written by the reader.
  alignas(64) std::atomic<uint64_t> read_pos;
  std::atomic<uint32_t> writer_threshold;  // the writer's event fires at free >= threshold
  std::atomic<uint32_t> writer_signalled;
  // Set by a side while it blocks, cleared by the signal that wakes it.
  alignas(64) std::atomic<uint32_t> reader_waiting;
  std::atomic<uint32_t> writer_waiting;
  // The writer's CLOCK_MONOTONIC (ns) when it last woke the reader, written just before the
  // eventfd; taken (and zeroed) by the reader: canemud starts a frame a client queued at that
  // instant rather than at its own wake-up (take_woken_ns). 0: not known (an older peer, or no
  // wake-up since the last take). Nobody needs the instant a reader woke a writer: the field
  // after it is reserved (zero), which keeps the layout.
  std::atomic<int64_t> reader_woken_ns;
  std::atomic<int64_t> reserved_woken_ns;
};
static_assert(sizeof(RingHeader) == 256);
static_assert(std::atomic<uint64_t>::is_always_lock_free);
static_assert(std::atomic<uint32_t>::is_always_lock_free);

// The shared memory of one ring: a memfd, mapped. Move-only.
class RingMemory {
 public:
  // Capacity is rounded up so the element area fills whole 4 KiB pages (as VCI FIFOs do); at
  // least `capacity`, at most 65535 elements.
  static IpcResult<RingMemory> create(uint32_t capacity, uint32_t element_size,
                                      const std::string& name);
  // Maps a ring received from the other side; checks magic, version and sizes against the fd's
  // size before anything else is used.
  static IpcResult<RingMemory> map(UniqueFd fd);

  RingMemory(RingMemory&& other) noexcept;
  RingMemory& operator=(RingMemory&& other) noexcept;
  RingMemory(const RingMemory&) = delete;
  RingMemory& operator=(const RingMemory&) = delete;
  ~RingMemory();

  RingHeader* header() const { return static_cast<RingHeader*>(base_); }
  uint8_t* elements() const { return static_cast<uint8_t*>(base_) + sizeof(RingHeader); }
  int fd() const { return fd_.get(); }
  uint32_t capacity() const { return capacity_; }
  uint32_t element_size() const { return element_size_; }

 private:
  RingMemory() = default;
  UniqueFd fd_;
  void* base_ = nullptr;
  std::size_t bytes_ = 0;
  uint32_t capacity_ = 0;
  uint32_t element_size_ = 0;
};

enum class RingStatus { ok, empty, full, invalid_argument, corrupted };
std::string_view to_string(RingStatus s);

// An auto-reset event between the two sides: a flag in shared memory and an eventfd.
struct RingEvent {
  std::atomic<uint32_t>* flag = nullptr;
  std::atomic<uint32_t>* waiting = nullptr;
  int eventfd = -1;
  RingHeader* header = nullptr;              // whether both processes take part in the barrier
  std::atomic<int64_t>* woken_ns = nullptr;  // where signal() notes when it woke the other side
  // Threads of this process inside wait() on this event (shared by copies of it): while one
  // sleeps, the shared waiting flag stays set, so another thread's wait() ending (a poll with
  // timeout 0, or the signal it took) never leaves a sleeper without its wake-up.
  std::shared_ptr<std::atomic<uint32_t>> sleepers = std::make_shared<std::atomic<uint32_t>>(0);

  // Sets the flag and, if the other side armed (waiting), writes the eventfd once and
  // disarms it.
  void signal() const;
  // Returns true if signalled within `timeout_ms` (-1: forever); resets the event.
  bool wait(int timeout_ms) const;
  // For a side that sleeps in its own poll loop (canemud's epoll) rather than in wait():
  // arm() makes the next signal write the eventfd; disarm() stops that, resets the event and
  // drains the eventfd.
  void arm() const;

 private:
  void sleeper_barrier() const;

 public:
  void disarm() const;
};

class RingWriter {
 public:
  // `reader_event` is the eventfd the reader blocks on; `own_event` the one this side blocks on.
  RingWriter(const RingMemory& memory, int reader_eventfd, int own_eventfd);

  RingStatus put(const void* element);                   // PutDataEntry
  RingStatus acquire(void** elements, uint32_t* count);  // AcquireWrite: contiguous free
  RingStatus release(uint32_t count);                    // ReleaseWrite
  // The last acquire() counts as `n` elements at most (VCI: acquired without a count pointer,
  // one element may be released).
  void limit_acquired(uint32_t n) { acquired_ = acquired_ < n ? acquired_ : n; }
  uint32_t free_count() const;
  uint32_t fill_count() const;
  void set_threshold(uint32_t free_threshold);  // clamped to the capacity
  uint32_t threshold() const;
  bool wait(int timeout_ms) const { return own_.wait(timeout_ms); }
  void count_overrun() { hdr_->overruns.fetch_add(1, std::memory_order_relaxed); }
  bool corrupted() const { return corrupted_; }
  // Whether the ring is corrupted, having read and checked the reader's position if this side
  // wrote since the last look (a writer that finds room reads it only now and then): the
  // daemon's check once per loop pass, one read per ring that was written.
  bool corrupted_after_writes() const {
    if (wrote_) {
      wrote_ = false;
      uint64_t read;
      load_read(read);
    }
    return corrupted_;
  }
  // This side's event, for a thread that watches it on the side's behalf (VCI AssignEvent).
  const RingEvent& own_event() const { return own_; }

 private:
  bool load_read(uint64_t& read) const;
  void published(uint64_t new_write);

  RingHeader* hdr_;
  uint8_t* data_;
  uint32_t capacity_;
  uint32_t size_;
  uint32_t acquired_ = 0;
  uint64_t write_ = 0;          // own position, never read back from shared memory
  uint32_t slot_ = 0;           // write_ % capacity_
  mutable bool wrote_ = false;  // since corrupted_after_writes() last looked
  mutable bool corrupted_ = false;
  mutable uint64_t last_read_ = 0;
  RingEvent reader_;
  RingEvent own_;
};

class RingReader {
 public:
  RingReader(const RingMemory& memory, int writer_eventfd, int own_eventfd);

  RingStatus get(void* element);                               // GetDataEntry (nullptr: drop)
  RingStatus acquire(const void** elements, uint32_t* count);  // AcquireRead: contiguous filled
  RingStatus release(uint32_t count);                          // ReleaseRead
  void limit_acquired(uint32_t n) { acquired_ = acquired_ < n ? acquired_ : n; }
  uint32_t fill_count() const;
  uint32_t free_count() const;
  void set_threshold(uint32_t fill_threshold);  // clamped to the capacity
  uint32_t threshold() const;
  bool wait(int timeout_ms) const { return own_.wait(timeout_ms); }
  // Sleeping in a poll loop on the own eventfd: arms it unless elements are waiting already.
  // Returns false (and stays disarmed) when there is something to read.
  bool arm_unless_filled();
  void disarm() { own_.disarm(); }
  // Makes the own eventfd readable (armed and signalled): a poll loop comes back to this ring
  // in its next round, after the other descriptors it serves. (One thread arms and signals:
  // no barrier between processes is needed.)
  void wake_self() const {
    own_.waiting->store(1, std::memory_order_seq_cst);
    own_.signal();
  }
  uint32_t overruns() const { return hdr_->overruns.load(std::memory_order_relaxed); }
  bool corrupted() const { return corrupted_; }
  const RingEvent& own_event() const { return own_; }
  // When the writer last woke this side (its CLOCK_MONOTONIC, ns), once: 0 if it did not since
  // the last call. What the writer says: the caller bounds it.
  int64_t take_woken_ns() { return hdr_->reader_woken_ns.exchange(0, std::memory_order_acquire); }

 private:
  bool load_write(uint64_t& write) const;
  void consumed(uint64_t new_read);

  RingHeader* hdr_;
  const uint8_t* data_;
  uint32_t capacity_;
  uint32_t size_;
  uint32_t acquired_ = 0;
  uint64_t read_ = 0;  // own position, never read back from shared memory
  uint32_t slot_ = 0;  // read_ % capacity_
  mutable bool corrupted_ = false;
  mutable uint64_t last_write_ = 0;
  RingEvent writer_;
  RingEvent own_;
};

// Whether this process is registered for membarrier(2)'s global expedited barrier (it tries
// once, and again in a forked child, whose registration is not inherited).
bool ring_barrier_registered();

// An eventfd for a ring side (non-blocking, close-on-exec).
IpcResult<UniqueFd> make_eventfd();

}  // namespace canemu::ipc
