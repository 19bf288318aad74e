#include "canemu/ipc/shm_ring.hpp"

#include "canemu/ipc/clock.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>

#include <fcntl.h>
#include <linux/membarrier.h>
#include <poll.h>
#include <pthread.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

namespace canemu::ipc {

namespace {

constexpr std::size_t kPage = 4096;
constexpr uint32_t kMaxCapacity = 65535;  // VCI FIFO counts are 16-bit

IpcError sys(const std::string& what) {
  const int e = errno;
  return IpcError{e, what + ": " + std::strerror(e)};
}

// Whether the other side's position, just loaded, is consistent: it never moves back, and the
// reader is never ahead of the writer nor more than a capacity behind it.
bool positions_consistent(uint64_t peer, uint64_t last_peer, uint64_t read, uint64_t write,
                          uint32_t capacity) {
  return peer >= last_peer && read <= write && write - read <= capacity;
}

// Grants the contiguous run of `available` (> 0) elements from position `pos` for an Acquire
// call: returns the slot index of its first element and sets how many the caller may release
// (the whole run when it asked for the count, else one).
uint32_t grant_run(uint64_t pos, uint32_t available, uint32_t capacity, uint32_t* count,
                   uint32_t& acquired) {
  const uint32_t at = static_cast<uint32_t>(pos % capacity);
  acquired = std::min(available, capacity - at);
  if (count != nullptr) {
    *count = acquired;
  } else {
    acquired = 1;
  }
  return at;
}

// One element's copy, inlined for the sizes the rings carry (LINMSG 16, CANMSG 20, CANMSG2 80,
// ipc::ChannelMessage 96 bytes): a copy of a size known only at run time is a call and a few
// branches, as much as the rest of a put.
inline void copy_element(void* to, const void* from, uint32_t size) {
  switch (size) {
    case 16:
      std::memcpy(to, from, 16);
      return;
    case 20:
      std::memcpy(to, from, 20);
      return;
    case 80:
      std::memcpy(to, from, 80);
      return;
    case 96:
      std::memcpy(to, from, 96);
      return;
    default:
      std::memcpy(to, from, size);
  }
}

// -1 unknown, 0 not registered, 1 registered for MEMBARRIER_CMD_GLOBAL_EXPEDITED.
std::atomic<int> barrier_state{-1};

int membarrier(int cmd) {
  return static_cast<int>(::syscall(__NR_membarrier, cmd, 0, 0));
}

int register_barrier() {
  const int supported = membarrier(MEMBARRIER_CMD_QUERY);
  const bool ok = supported > 0 && (supported & MEMBARRIER_CMD_GLOBAL_EXPEDITED) != 0 &&
                  membarrier(MEMBARRIER_CMD_REGISTER_GLOBAL_EXPEDITED) == 0;
  return ok ? 1 : 0;
}

// Whether a signal on the ring may skip its fence (this process's own registration aside).
bool both_registered(const RingHeader& h) {
  return h.creator_barrier.load(std::memory_order_relaxed) == 1 &&
         h.mapper_barrier.load(std::memory_order_relaxed) == 1;
}

}  // namespace

// The sleeping side's half of the asymmetric barrier: every thread of every registered process
// runs a full barrier before this returns. A waiter that is not registered (a forked child
// whose registration failed) or whose barrier failed, on a ring whose signals skip their fence:
// it makes them fence from now on and, for the signals already under way, issues the slow
// system-wide barrier that needs no registration.
void RingEvent::sleeper_barrier() const {
  if (ring_barrier_registered() && membarrier(MEMBARRIER_CMD_GLOBAL_EXPEDITED) == 0) {
    return;
  }
  if (header != nullptr && both_registered(*header)) {
    header->mapper_barrier.store(2, std::memory_order_seq_cst);
    membarrier(MEMBARRIER_CMD_GLOBAL);
  }
}

bool ring_barrier_registered() {
  int state = barrier_state.load(std::memory_order_acquire);
  if (state < 0) {
    static const bool at_fork = [] {
      // A forked child has a memory map of its own, not registered: it registers again.
      return ::pthread_atfork(nullptr, nullptr, [] { barrier_state.store(register_barrier()); }) ==
             0;
    }();
    state = at_fork ? register_barrier() : 0;
    barrier_state.store(state, std::memory_order_release);
  }
  return state == 1;
}

std::string_view to_string(RingStatus s) {
  switch (s) {
    case RingStatus::ok:
      return "ok";
    case RingStatus::empty:
      return "empty";
    case RingStatus::full:
      return "full";
    case RingStatus::invalid_argument:
      return "invalid_argument";
    case RingStatus::corrupted:
      return "corrupted";
  }
  return "?";
}

IpcResult<UniqueFd> make_eventfd() {
  UniqueFd fd(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC));
  if (!fd.valid()) {
    return tl::unexpected(sys("eventfd"));
  }
  return fd;
}

IpcResult<RingMemory> RingMemory::create(uint32_t capacity, uint32_t element_size,
                                         const std::string& name) {
  if (capacity == 0 || capacity > kMaxCapacity || element_size == 0 || element_size > 4096) {
    return tl::unexpected(IpcError{EINVAL, "ring of " + std::to_string(capacity) + " x " +
                                               std::to_string(element_size) +
                                               " bytes: capacity must be 1..65535, elements "
                                               "1..4096 bytes"});
  }
  // Whole pages; the rest of the last page becomes extra elements.
  std::size_t bytes = sizeof(RingHeader) + std::size_t{capacity} * element_size;
  bytes = (bytes + kPage - 1) / kPage * kPage;
  const uint32_t rounded = static_cast<uint32_t>(
      std::min<std::size_t>((bytes - sizeof(RingHeader)) / element_size, kMaxCapacity));

  RingMemory m;
  m.fd_.reset(::memfd_create(name.c_str(), MFD_CLOEXEC | MFD_ALLOW_SEALING));
  if (!m.fd_.valid()) {
    return tl::unexpected(sys("memfd_create"));
  }
  if (::ftruncate(m.fd_.get(), static_cast<off_t>(bytes)) != 0) {
    return tl::unexpected(sys("ftruncate"));
  }
  // The other side must not resize it under us (a shrink would fault our accesses).
  if (::fcntl(m.fd_.get(), F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL) != 0) {
    return tl::unexpected(sys("fcntl F_ADD_SEALS"));
  }
  m.base_ = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, m.fd_.get(), 0);
  if (m.base_ == MAP_FAILED) {
    m.base_ = nullptr;
    return tl::unexpected(sys("mmap"));
  }
  m.bytes_ = bytes;
  m.capacity_ = rounded;
  m.element_size_ = element_size;
  RingHeader* h = new (m.base_) RingHeader{};
  h->magic = kRingMagic;
  h->abi_version = kRingAbiVersion;
  h->element_size = element_size;
  h->capacity = rounded;
  h->total_bytes = bytes;
  h->reader_threshold.store(1);
  h->writer_threshold.store(1);
  h->creator_barrier.store(ring_barrier_registered() ? 1 : 0);
  return m;
}

IpcResult<RingMemory> RingMemory::map(UniqueFd fd) {
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) {
    return tl::unexpected(sys("fstat"));
  }
  const int seals = ::fcntl(fd.get(), F_GET_SEALS);
  if (seals < 0 || !(seals & F_SEAL_SHRINK)) {
    return tl::unexpected(IpcError{EINVAL, "ring memory is not sealed against shrinking"});
  }
  const auto bytes = static_cast<std::size_t>(st.st_size);
  if (bytes < sizeof(RingHeader)) {
    return tl::unexpected(IpcError{EINVAL, "ring memory smaller than its header"});
  }
  RingMemory m;
  m.base_ = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd.get(), 0);
  if (m.base_ == MAP_FAILED) {
    m.base_ = nullptr;
    return tl::unexpected(sys("mmap"));
  }
  m.bytes_ = bytes;
  m.fd_ = std::move(fd);
  // Read the other side's header once, into locals, and use only what was checked.
  const RingHeader* h = m.header();
  const uint32_t magic = h->magic;
  const uint16_t version = h->abi_version;
  const uint32_t element_size = h->element_size;
  const uint32_t capacity = h->capacity;
  if (magic != kRingMagic || version != kRingAbiVersion || element_size == 0 ||
      element_size > 4096 || capacity == 0 || capacity > kMaxCapacity ||
      sizeof(RingHeader) + std::size_t{capacity} * element_size > bytes) {
    return tl::unexpected(IpcError{EINVAL, "ring header is not valid (magic, ABI version " +
                                               std::to_string(version) + " where this side has " +
                                               std::to_string(kRingAbiVersion) + ", or sizes)"});
  }
  m.capacity_ = capacity;
  m.element_size_ = element_size;
  // Every process that maps the ring must be registered for the signals to skip their fences.
  std::atomic<uint32_t>& mapper = m.header()->mapper_barrier;
  if (ring_barrier_registered()) {
    uint32_t none = 0;
    mapper.compare_exchange_strong(none, 1, std::memory_order_seq_cst);
  } else {
    mapper.store(2, std::memory_order_seq_cst);
  }
  return m;
}

RingMemory::RingMemory(RingMemory&& o) noexcept
    : fd_(std::move(o.fd_)),
      base_(std::exchange(o.base_, nullptr)),
      bytes_(std::exchange(o.bytes_, 0)),
      capacity_(o.capacity_),
      element_size_(o.element_size_) {}

RingMemory& RingMemory::operator=(RingMemory&& o) noexcept {
  if (this != &o) {
    if (base_ != nullptr) {
      ::munmap(base_, bytes_);
    }
    fd_ = std::move(o.fd_);
    base_ = std::exchange(o.base_, nullptr);
    bytes_ = std::exchange(o.bytes_, 0);
    capacity_ = o.capacity_;
    element_size_ = o.element_size_;
  }
  return *this;
}

RingMemory::~RingMemory() {
  if (base_ != nullptr) {
    ::munmap(base_, bytes_);
  }
}

void RingEvent::signal() const {
  // Release: the flag is never seen before the position this signal announces.
  flag->store(1, std::memory_order_release);
  // The position and the flag stored before the waiting flag is read (the waiter stores its
  // waiting flag before it reads ours): a store-load pair. When both processes are registered
  // the waiter's membarrier orders it; otherwise (the mapper not yet known to be registered,
  // or this process not) this side fences.
  if (header != nullptr && both_registered(*header) &&
      barrier_state.load(std::memory_order_relaxed) == 1) {
    std::atomic_signal_fence(std::memory_order_seq_cst);
  } else {
    std::atomic_thread_fence(std::memory_order_seq_cst);
  }
  // One write per arming: the waiter arms again before it sleeps again, so a peer that keeps
  // its waiting flag set cannot make this side write the eventfd for every element. The flag
  // is only read while it is clear, so a busy ring's signal writes nothing of the other side's.
  if (waiting->load(std::memory_order_relaxed) != 0 &&
      waiting->exchange(0, std::memory_order_seq_cst) != 0 && eventfd >= 0) {
    if (woken_ns != nullptr) {
      woken_ns->store(monotonic_ns(), std::memory_order_release);
    }
    const uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(eventfd, &one, sizeof one);
  }
}

bool RingEvent::wait(int timeout_ms) const {
  if (flag->exchange(0, std::memory_order_acq_rel) != 0) {
    return true;
  }
  sleepers->fetch_add(1, std::memory_order_seq_cst);
  // Leaving: the waiting flag stays set while other threads of this process sleep on it.
  const auto leave = [this](bool signalled) {
    const bool others = sleepers->fetch_sub(1, std::memory_order_seq_cst) > 1;
    waiting->store(others ? 1 : 0, std::memory_order_seq_cst);
    return signalled;
  };
  const int64_t start_ms = monotonic_ns() / 1'000'000;
  while (true) {
    waiting->store(1, std::memory_order_seq_cst);
    sleeper_barrier();
    if (flag->exchange(0, std::memory_order_seq_cst) != 0) {
      return leave(true);
    }
    int left = -1;
    if (timeout_ms >= 0) {
      const int64_t elapsed = monotonic_ns() / 1'000'000 - start_ms;
      left = static_cast<int>(std::max<int64_t>(0, timeout_ms - elapsed));
    }
    pollfd p{eventfd, POLLIN, 0};
    const int r = ::poll(&p, 1, left);
    uint64_t count;
    [[maybe_unused]] const ssize_t n = ::read(eventfd, &count, sizeof count);
    if (flag->exchange(0, std::memory_order_acq_rel) != 0) {
      return leave(true);
    }
    // A wake-up left over from a signal already consumed (here, or by another thread of this
    // process): wait on, unless time is up.
    if ((r == 0 && left >= 0) || (r < 0 && errno != EINTR) || left == 0) {
      return leave(false);
    }
  }
}

void RingEvent::arm() const {
  waiting->store(1, std::memory_order_seq_cst);
  sleeper_barrier();
}

void RingEvent::disarm() const {
  waiting->store(0, std::memory_order_seq_cst);
  flag->store(0, std::memory_order_relaxed);
  uint64_t count;
  if (eventfd >= 0) {
    [[maybe_unused]] const ssize_t n = ::read(eventfd, &count, sizeof count);
  }
}

// ---- writer ----

RingWriter::RingWriter(const RingMemory& m, int reader_eventfd, int own_eventfd)
    : hdr_(m.header()),
      data_(m.elements()),
      capacity_(m.capacity()),
      size_(m.element_size()),
      reader_{&hdr_->reader_signalled, &hdr_->reader_waiting, reader_eventfd, hdr_,
              &hdr_->reader_woken_ns},
      own_{&hdr_->writer_signalled, &hdr_->writer_waiting, own_eventfd, hdr_} {
  write_ = hdr_->write_pos.load(std::memory_order_relaxed);
  slot_ = static_cast<uint32_t>(write_ % capacity_);
  last_read_ = hdr_->read_pos.load(std::memory_order_acquire);
  // The positions found are checked like any other: they bound every access.
  corrupted_ = !positions_consistent(last_read_, 0, last_read_, write_, capacity_);
}

bool RingWriter::load_read(uint64_t& read) const {
  if (corrupted_) {
    return false;
  }
  read = hdr_->read_pos.load(std::memory_order_acquire);
  if (!positions_consistent(read, last_read_, read, write_, capacity_)) {
    corrupted_ = true;
    return false;
  }
  last_read_ = read;
  return true;
}

void RingWriter::published(uint64_t new_write) {
  hdr_->write_pos.store(new_write, std::memory_order_release);
  wrote_ = true;
  // A write access that leaves the fill level at or above the threshold signals. Any access
  // leaves at least one element; beyond that the reader's position is read afresh (an older
  // one would make the fill look higher than it is).
  const uint32_t threshold = hdr_->reader_threshold.load(std::memory_order_relaxed);
  if (threshold <= 1) {
    reader_.signal();
    return;
  }
  uint64_t read = last_read_;
  if (load_read(read) && new_write - read >= std::min(threshold, capacity_)) {
    reader_.signal();
  }
}

RingStatus RingWriter::put(const void* element) {
  if (corrupted_) {
    return RingStatus::corrupted;
  }
  if (write_ - last_read_ == capacity_) {  // full when last looked: look again
    uint64_t read;
    if (!load_read(read)) {
      return RingStatus::corrupted;
    }
    if (write_ - read == capacity_) {
      return RingStatus::full;
    }
  }
  copy_element(data_ + std::size_t{slot_} * size_, element, size_);
  ++write_;
  slot_ = slot_ + 1 == capacity_ ? 0 : slot_ + 1;
  // The next slot's ends fetched ahead: cached no more (bench/README.md, "The rings' memory").
  __builtin_prefetch(data_ + std::size_t{slot_} * size_, 0, 3);
  __builtin_prefetch(data_ + std::size_t{slot_ + 1} * size_ - 1, 0, 3);
  published(write_);
  return RingStatus::ok;
}

RingStatus RingWriter::acquire(void** elements, uint32_t* count) {
  if (elements == nullptr) {
    return RingStatus::invalid_argument;
  }
  uint64_t read;
  if (!load_read(read)) {
    return RingStatus::corrupted;
  }
  const uint32_t free = static_cast<uint32_t>(capacity_ - (write_ - read));
  if (free == 0) {
    return RingStatus::full;
  }
  const uint32_t at = grant_run(write_, free, capacity_, count, acquired_);
  *elements = data_ + std::size_t{at} * size_;
  return RingStatus::ok;
}

RingStatus RingWriter::release(uint32_t count) {
  if (count > acquired_) {
    return RingStatus::invalid_argument;
  }
  uint64_t read;
  if (!load_read(read)) {
    return RingStatus::corrupted;
  }
  acquired_ = 0;
  if (count == 0) {
    return RingStatus::ok;
  }
  write_ += count;
  slot_ = static_cast<uint32_t>(write_ % capacity_);
  published(write_);
  return RingStatus::ok;
}

uint32_t RingWriter::fill_count() const {
  uint64_t read;
  return load_read(read) ? static_cast<uint32_t>(write_ - read) : 0;
}

uint32_t RingWriter::free_count() const {
  uint64_t read;
  return load_read(read) ? static_cast<uint32_t>(capacity_ - (write_ - read)) : 0;
}

void RingWriter::set_threshold(uint32_t t) {
  hdr_->writer_threshold.store(std::min(t, capacity_), std::memory_order_relaxed);
}

uint32_t RingWriter::threshold() const {
  return hdr_->writer_threshold.load(std::memory_order_relaxed);
}

// ---- reader ----

bool RingReader::arm_unless_filled() {
  own_.arm();
  // The store above must be visible before the position is read below (a store-load pair).
  std::atomic_thread_fence(std::memory_order_seq_cst);
  // A put between the last read and arm() did not write the eventfd: look once more.
  if (fill_count() > 0 || corrupted_) {
    own_.disarm();
    return false;
  }
  return true;
}

RingReader::RingReader(const RingMemory& m, int writer_eventfd, int own_eventfd)
    : hdr_(m.header()),
      data_(m.elements()),
      capacity_(m.capacity()),
      size_(m.element_size()),
      writer_{&hdr_->writer_signalled, &hdr_->writer_waiting, writer_eventfd, hdr_},
      own_{&hdr_->reader_signalled, &hdr_->reader_waiting, own_eventfd, hdr_} {
  read_ = hdr_->read_pos.load(std::memory_order_relaxed);
  slot_ = static_cast<uint32_t>(read_ % capacity_);
  last_write_ = hdr_->write_pos.load(std::memory_order_acquire);
  corrupted_ = !positions_consistent(last_write_, 0, read_, last_write_, capacity_);
}

bool RingReader::load_write(uint64_t& write) const {
  if (corrupted_) {
    return false;
  }
  write = hdr_->write_pos.load(std::memory_order_acquire);
  if (!positions_consistent(write, last_write_, read_, write, capacity_)) {
    corrupted_ = true;
    return false;
  }
  last_write_ = write;
  return true;
}

void RingReader::consumed(uint64_t new_read) {
  hdr_->read_pos.store(new_read, std::memory_order_release);
  // A read access that leaves at least `threshold` elements free signals: any access leaves
  // one; beyond that the writer's position is read afresh (an older one would make the free
  // room look larger than it is).
  const uint32_t threshold = hdr_->writer_threshold.load(std::memory_order_relaxed);
  if (threshold <= 1) {
    writer_.signal();
    return;
  }
  uint64_t write = last_write_;
  if (load_write(write) && capacity_ - (write - new_read) >= std::min(threshold, capacity_)) {
    writer_.signal();
  }
}

RingStatus RingReader::get(void* element) {
  if (corrupted_) {
    return RingStatus::corrupted;
  }
  if (last_write_ == read_) {  // empty when last looked: look again
    uint64_t write;
    if (!load_write(write)) {
      return RingStatus::corrupted;
    }
    if (write == read_) {
      return RingStatus::empty;
    }
  }
  if (element != nullptr) {
    copy_element(element, data_ + std::size_t{slot_} * size_, size_);
  }
  ++read_;
  slot_ = slot_ + 1 == capacity_ ? 0 : slot_ + 1;
  consumed(read_);
  return RingStatus::ok;
}

RingStatus RingReader::acquire(const void** elements, uint32_t* count) {
  if (elements == nullptr) {
    return RingStatus::invalid_argument;
  }
  uint64_t write;
  if (!load_write(write)) {
    return RingStatus::corrupted;
  }
  const uint32_t fill = static_cast<uint32_t>(write - read_);
  if (fill == 0) {
    return RingStatus::empty;
  }
  const uint32_t at = grant_run(read_, fill, capacity_, count, acquired_);
  *elements = data_ + std::size_t{at} * size_;
  return RingStatus::ok;
}

RingStatus RingReader::release(uint32_t count) {
  if (count > acquired_) {
    return RingStatus::invalid_argument;
  }
  uint64_t write;
  if (!load_write(write)) {
    return RingStatus::corrupted;
  }
  acquired_ = 0;
  if (count == 0) {
    return RingStatus::ok;
  }
  read_ += count;
  slot_ = static_cast<uint32_t>(read_ % capacity_);
  consumed(read_);
  return RingStatus::ok;
}

uint32_t RingReader::fill_count() const {
  uint64_t write;
  return load_write(write) ? static_cast<uint32_t>(write - read_) : 0;
}

uint32_t RingReader::free_count() const {
  uint64_t write;
  return load_write(write) ? static_cast<uint32_t>(capacity_ - (write - read_)) : 0;
}

void RingReader::set_threshold(uint32_t t) {
  hdr_->reader_threshold.store(std::min(t, capacity_), std::memory_order_relaxed);
}

uint32_t RingReader::threshold() const {
  return hdr_->reader_threshold.load(std::memory_order_relaxed);
}

}  // namespace canemu::ipc
