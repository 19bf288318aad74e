#include "canemu/ipc/shm_ring.hpp"

#include "canemu/ipc/clock.hpp"

#include <gtest/gtest.h>

#include <atomic>

#include <cstring>
#include <thread>

#include <csignal>

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

namespace canemu::ipc {
namespace {

struct Element {
  uint32_t seq;
  uint8_t payload[16];
};
static_assert(sizeof(Element) == 20);

struct Pair {
  RingMemory memory;
  UniqueFd reader_event;
  UniqueFd writer_event;
  RingWriter writer;
  RingReader reader;
  explicit Pair(RingMemory m, UniqueFd re, UniqueFd we)
      : memory(std::move(m)),
        reader_event(std::move(re)),
        writer_event(std::move(we)),
        writer(memory, reader_event.get(), writer_event.get()),
        reader(memory, writer_event.get(), reader_event.get()) {}
};

Pair make(uint32_t capacity) {
  auto m = RingMemory::create(capacity, sizeof(Element), "test-ring");
  EXPECT_TRUE(m) << m.error().message;
  return Pair(std::move(*m), std::move(*make_eventfd()), std::move(*make_eventfd()));
}

// A forked child killed and reaped when the test leaves early (a failing reader must not leave
// its writer behind); pid -1 once reaped.
struct Reap {
  pid_t pid;
  // Waits for the child's end; its wait status.
  int wait() {
    int status = 0;
    ::waitpid(pid, &status, 0);
    pid = -1;
    return status;
  }
  ~Reap() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
};

Element element(uint32_t seq) {
  Element e{};
  e.seq = seq;
  std::memset(e.payload, static_cast<int>(seq & 0xFF), sizeof e.payload);
  return e;
}

TEST(ShmRing, CapacityIsAtLeastTheRequestAndFillsWholePages) {
  // 32 x 20 bytes + 256 header bytes round up to one 4 KiB page: (4096 - 256) / 20 = 192.
  auto p = make(32);
  EXPECT_EQ(p.memory.capacity(), 192u);
  EXPECT_EQ(p.writer.free_count(), 192u);
  auto big = RingMemory::create(1000, 20, "big");
  ASSERT_TRUE(big);
  EXPECT_GE(big->capacity(), 1000u);
  EXPECT_FALSE(RingMemory::create(0, 20, "x"));
  EXPECT_FALSE(RingMemory::create(70000, 20, "x"));
}

// A reader that sleeps in its own poll loop: the eventfd is written only while it is armed, and
// arming with elements already in the ring says so instead of sleeping.
TEST(ShmRing, AReaderArmedForAPollLoopGetsItsEventfdWrittenOnce) {
  auto p = make(32);
  auto readable = [&] {
    pollfd q{p.reader_event.get(), POLLIN, 0};
    return ::poll(&q, 1, 0) == 1;
  };
  const Element e = element(1);
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
  EXPECT_FALSE(readable());                    // not armed: no system call on the writer's side
  EXPECT_FALSE(p.reader.arm_unless_filled());  // something to read already
  ASSERT_EQ(p.reader.get(nullptr), RingStatus::ok);
  EXPECT_TRUE(p.reader.arm_unless_filled());
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
  EXPECT_TRUE(readable());
  p.reader.disarm();
  EXPECT_FALSE(readable());  // drained
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
  EXPECT_FALSE(readable());  // disarmed again
  EXPECT_EQ(p.reader.fill_count(), 2u);
}

// A peer that keeps its waiting flag set (a hostile or broken client) still gets one eventfd
// write per arming, not one per element: the writer disarms it with the write.
TEST(ShmRing, AWaitingFlagKeptSetCostsOneEventfdWriteNotOnePerElement) {
  auto p = make(64);
  std::atomic<uint32_t>& waiting = p.memory.header()->reader_waiting;
  waiting.store(1);
  for (uint32_t i = 0; i < 50; ++i) {
    const Element e = element(i);
    ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
    if (i < 10) {
      waiting.store(1);  // the peer sets it again and again without sleeping
    }
  }
  uint64_t writes = 0;
  ASSERT_EQ(::read(p.reader_event.get(), &writes, sizeof writes),
            static_cast<ssize_t>(sizeof writes));
  EXPECT_EQ(writes, 11u);  // once per setting of the flag, none for the 39 puts after
  EXPECT_EQ(waiting.load(), 0u);
}

// The writer notes when it woke an armed reader (its CLOCK_MONOTONIC), and the reader takes it
// once; puts that wake nobody, and the reader waking itself, note nothing.
TEST(ShmRing, TheWriterNotesWhenItWokeTheReaderAndTheReaderTakesItOnce) {
  auto p = make(32);
  const Element e = element(1);
  EXPECT_EQ(p.reader.take_woken_ns(), 0);
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);  // the reader is not armed
  EXPECT_EQ(p.reader.take_woken_ns(), 0);
  ASSERT_EQ(p.reader.get(nullptr), RingStatus::ok);
  ASSERT_TRUE(p.reader.arm_unless_filled());
  const int64_t before = monotonic_ns();
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
  const int64_t after = monotonic_ns();
  const int64_t woken = p.reader.take_woken_ns();
  EXPECT_GE(woken, before);
  EXPECT_LE(woken, after);
  EXPECT_EQ(p.reader.take_woken_ns(), 0);       // taken
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);  // disarmed by the write: no wake-up, no note
  EXPECT_EQ(p.reader.take_woken_ns(), 0);
  p.reader.disarm();
  p.reader.wake_self();
  EXPECT_EQ(p.reader.take_woken_ns(), 0);
}

// wake_self(): the reader's own eventfd becomes readable, so a poll loop comes back to it.
TEST(ShmRing, AReaderWakesItselfForTheNextRoundOfItsPollLoop) {
  auto p = make(32);
  pollfd q{p.reader_event.get(), POLLIN, 0};
  EXPECT_EQ(::poll(&q, 1, 0), 0);
  p.reader.wake_self();
  EXPECT_EQ(::poll(&q, 1, 0), 1);
  p.reader.disarm();
  EXPECT_EQ(::poll(&q, 1, 0), 0);
}

TEST(ShmRing, ElementsComeOutInOrderAndCountsFollow) {
  auto p = make(32);
  for (uint32_t i = 0; i < 10; ++i) {
    const Element e = element(i);
    ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
  }
  EXPECT_EQ(p.reader.fill_count(), 10u);
  EXPECT_EQ(p.writer.free_count(), 182u);
  for (uint32_t i = 0; i < 10; ++i) {
    Element e;
    ASSERT_EQ(p.reader.get(&e), RingStatus::ok);
    EXPECT_EQ(e.seq, i);
    EXPECT_EQ(e.payload[15], i);
  }
  Element e;
  EXPECT_EQ(p.reader.get(&e), RingStatus::empty);
}

TEST(ShmRing, AFullRingRefusesAndNullGetDropsAnElement) {
  auto p = make(1);  // rounds up to 192
  const uint32_t cap = p.memory.capacity();
  for (uint32_t i = 0; i < cap; ++i) {
    const Element e = element(i);
    ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
  }
  const Element extra = element(999);
  EXPECT_EQ(p.writer.put(&extra), RingStatus::full);
  p.writer.count_overrun();
  EXPECT_EQ(p.reader.overruns(), 1u);
  EXPECT_EQ(p.reader.get(nullptr), RingStatus::ok);  // removed without copying
  Element e;
  ASSERT_EQ(p.reader.get(&e), RingStatus::ok);
  EXPECT_EQ(e.seq, 1u);
}

TEST(ShmRing, AcquireGivesContiguousRunsAndPartialReleases) {
  auto p = make(1);
  const uint32_t cap = p.memory.capacity();
  // Move the positions near the end so the next run wraps.
  for (uint32_t i = 0; i < cap - 3; ++i) {
    const Element e = element(i);
    ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
    ASSERT_EQ(p.reader.get(nullptr), RingStatus::ok);
  }
  void* w = nullptr;
  uint32_t n = 0;
  ASSERT_EQ(p.writer.acquire(&w, &n), RingStatus::ok);
  EXPECT_EQ(n, 3u);  // up to the end of the buffer, not the whole free count
  auto* slots = static_cast<Element*>(w);
  for (uint32_t i = 0; i < 3; ++i) {
    slots[i] = element(100 + i);
  }
  EXPECT_EQ(p.writer.release(4), RingStatus::invalid_argument);
  ASSERT_EQ(p.writer.release(3), RingStatus::ok);
  const Element e = element(103);
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);  // at the start of the buffer
  const void* r = nullptr;
  ASSERT_EQ(p.reader.acquire(&r, &n), RingStatus::ok);
  EXPECT_EQ(n, 3u);
  EXPECT_EQ(static_cast<const Element*>(r)[0].seq, 100u);
  ASSERT_EQ(p.reader.release(2), RingStatus::ok);  // partial: the third stays
  ASSERT_EQ(p.reader.acquire(&r, &n), RingStatus::ok);
  EXPECT_EQ(n, 1u);
  EXPECT_EQ(static_cast<const Element*>(r)[0].seq, 102u);
  ASSERT_EQ(p.reader.release(1), RingStatus::ok);
  ASSERT_EQ(p.reader.acquire(&r, &n), RingStatus::ok);
  EXPECT_EQ(static_cast<const Element*>(r)[0].seq, 103u);
  EXPECT_EQ(p.reader.release(0), RingStatus::ok);
  EXPECT_EQ(p.reader.fill_count(), 1u);
}

TEST(ShmRing, ReaderEventFiresOnWritesThatReachTheThresholdOnly) {
  auto p = make(32);
  p.reader.set_threshold(3);
  for (uint32_t i = 0; i < 2; ++i) {
    const Element e = element(i);
    p.writer.put(&e);
  }
  EXPECT_FALSE(p.reader.wait(0));
  const Element e = element(2);
  p.writer.put(&e);
  EXPECT_TRUE(p.reader.wait(0));
  EXPECT_FALSE(p.reader.wait(0));  // auto-reset
  // Reading does not signal the reader again, even with elements left.
  p.reader.get(nullptr);
  EXPECT_FALSE(p.reader.wait(0));
  // Setting the threshold does not signal either.
  p.reader.set_threshold(1);
  EXPECT_FALSE(p.reader.wait(0));
  p.reader.set_threshold(100000);
  EXPECT_EQ(p.reader.threshold(), p.memory.capacity());  // clamped
}

// Two threads of one program wait on the same event (a reader thread blocked in WaitRxEvent,
// another polling it with timeout 0): the poll ending must not take the sleeper's wake-up away.
TEST(ShmRing, AWaitWithTimeoutZeroLeavesAnotherThreadsWaitArmed) {
  auto p = make(32);
  std::atomic<int> sleeper_result{-1};
  std::thread sleeper([&] { sleeper_result = p.reader.wait(10'000) ? 1 : 0; });
  // Until the sleeper armed the event (its waiting flag is in the ring's header), at most 10 s.
  std::atomic<uint32_t>& waiting = p.memory.header()->reader_waiting;
  for (int i = 0; i < 10'000'000 && waiting.load() == 0; ++i) {
    std::this_thread::yield();
  }
  ASSERT_EQ(waiting.load(), 1u);
  EXPECT_FALSE(p.reader.wait(0));  // nothing yet
  EXPECT_EQ(waiting.load(), 1u);   // still armed for the sleeper
  const Element e = element(1);
  ASSERT_EQ(p.writer.put(&e), RingStatus::ok);
  sleeper.join();
  EXPECT_EQ(sleeper_result.load(), 1);  // woken by the put, not by its 10 s timeout
  EXPECT_EQ(waiting.load(), 0u);
}

TEST(ShmRing, WriterEventFiresWhenReadsFreeEnoughSpace) {
  auto p = make(1);
  const uint32_t cap = p.memory.capacity();
  for (uint32_t i = 0; i < cap; ++i) {
    const Element e = element(i);
    p.writer.put(&e);
  }
  p.writer.set_threshold(2);
  p.reader.get(nullptr);
  EXPECT_FALSE(p.writer.wait(0));  // 1 free
  p.reader.get(nullptr);
  EXPECT_TRUE(p.writer.wait(0));  // 2 free
}

TEST(ShmRing, CorruptedPositionsAreDetectedAndStick) {
  auto p = make(32);
  const Element e = element(1);
  p.writer.put(&e);
  // A misbehaving writer claims more than the capacity was written.
  p.memory.header()->write_pos.store(1000000);
  Element out;
  EXPECT_EQ(p.reader.get(&out), RingStatus::corrupted);
  EXPECT_TRUE(p.reader.corrupted());
  p.memory.header()->write_pos.store(1);
  EXPECT_EQ(p.reader.get(&out), RingStatus::corrupted);
  // A reader position moving backwards is caught by the writer.
  auto q = make(32);
  q.writer.put(&e);
  q.reader.get(nullptr);
  EXPECT_EQ(q.writer.fill_count(), 0u);  // the writer has seen the reader at 1
  q.memory.header()->read_pos.store(0);
  // The writer reads the reader's position when it needs it (here: for the free count), and
  // from then on refuses every access.
  EXPECT_EQ(q.writer.free_count(), 0u);
  EXPECT_TRUE(q.writer.corrupted());
  EXPECT_EQ(q.writer.put(&e), RingStatus::corrupted);
  // A writer that has filled the ring reads the reader's position before it writes again.
  auto f = make(32);
  const uint32_t capacity = f.memory.capacity();
  for (uint32_t i = 0; i < capacity; ++i) {
    ASSERT_EQ(f.writer.put(&e), RingStatus::ok);
  }
  EXPECT_EQ(f.writer.put(&e), RingStatus::full);
  f.memory.header()->read_pos.store(uint64_t{capacity} + 1);  // ahead of the writer
  EXPECT_EQ(f.writer.put(&e), RingStatus::corrupted);
}

TEST(ShmRing, MapChecksTheHeaderAndTheSeals) {
  auto p = make(32);
  const int dup = ::dup(p.memory.fd());
  auto mapped = RingMemory::map(UniqueFd(dup));
  ASSERT_TRUE(mapped) << mapped.error().message;
  EXPECT_EQ(mapped->capacity(), p.memory.capacity());
  p.memory.header()->magic = 0;
  auto bad = RingMemory::map(UniqueFd(::dup(p.memory.fd())));
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("header"), std::string::npos);
}

TEST(ShmRing, TwoProcessesExchangeAHundredThousandElementsInOrder) {
  auto p = make(64);
  p.writer.set_threshold(16);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Writer process: its own view of the same memory and events. It gives up after 20 s of
    // waiting in all, so a failing reader cannot leave it behind.
    RingWriter w(p.memory, p.reader_event.get(), p.writer_event.get());
    int waited = 0;
    for (uint32_t i = 0; i < 100000 && waited < 20;) {
      const Element e = element(i);
      if (w.put(&e) == RingStatus::ok) {
        ++i;
      } else if (!w.wait(1000)) {
        ++waited;  // full: wait for the reader to free space
      }
    }
    ::_exit(waited < 20 ? 0 : 1);
  }
  Reap reap{child};
  uint32_t expected = 0;
  bool in_order = true;
  while (expected < 100000) {
    Element e;
    const RingStatus s = p.reader.get(&e);
    if (s == RingStatus::ok) {
      in_order = in_order && e.seq == expected && e.payload[7] == (expected & 0xFF);
      ++expected;
    } else if (s == RingStatus::empty) {
      ASSERT_TRUE(p.reader.wait(5000)) << "no element for 5 s at " << expected;
    } else {
      FAIL() << to_string(s);
    }
  }
  const int status = reap.wait();
  EXPECT_TRUE(in_order);
  EXPECT_EQ(status, 0);
}

// The asymmetric barrier: a ring created by one process and mapped by another records whether
// each registered for membarrier; with both registered the signals skip their fences and the
// sleeping side's barrier orders them. Both sides block again and again (a ring of a few
// elements, woken at every access); a wait that times out while the ring holds what it waited
// for would be a lost wake-up.
TEST(ShmRing, SidesThatBlockInTwoProcessesNeverMissAWakeUp) {
  // Elements that fill the page after the header: a ring of exactly one element.
  struct Big {
    uint32_t seq;
    uint8_t rest[4096 - sizeof(RingHeader) - 4];
  };
  auto m = RingMemory::create(1, sizeof(Big), "test-ring-one");
  auto re = make_eventfd();
  auto we = make_eventfd();
  ASSERT_TRUE(m && re && we);
  ASSERT_EQ(m->capacity(), 1u);
  Pair p(std::move(*m), std::move(*re), std::move(*we));
  const uint32_t registered = ring_barrier_registered() ? 1 : 0;
  EXPECT_EQ(p.memory.header()->creator_barrier.load(), registered);
  EXPECT_EQ(p.memory.header()->mapper_barrier.load(), 0u);  // nobody mapped it yet
  constexpr uint32_t kCount = 20000;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    auto mapped = RingMemory::map(UniqueFd(::dup(p.memory.fd())));
    if (!mapped || mapped->header()->mapper_barrier.load() != registered) {
      ::_exit(3);
    }
    RingWriter w(*mapped, p.reader_event.get(), p.writer_event.get());
    for (uint32_t i = 0; i < kCount;) {
      Big e{};
      e.seq = i;
      if (w.put(&e) == RingStatus::ok) {
        ++i;
      } else if (!w.wait(2000)) {
        ::_exit(w.free_count() > 0 ? 2 : 1);  // 2: room, but no wake-up
      }
    }
    ::_exit(0);
  }
  Reap reap{child};
  uint32_t expected = 0;
  bool in_order = true;
  while (expected < kCount) {
    Big e;
    const RingStatus s = p.reader.get(&e);
    if (s == RingStatus::ok) {
      in_order = in_order && e.seq == expected;
      ++expected;
    } else if (s == RingStatus::empty) {
      if (!p.reader.wait(2000)) {
        ASSERT_EQ(p.reader.fill_count(), 0u) << "elements waited, no wake-up, at " << expected;
        FAIL() << "the writer stopped at " << expected;
      }
    } else {
      FAIL() << to_string(s);
    }
  }
  const int status = reap.wait();
  EXPECT_TRUE(in_order);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "writer status " << status;
}

// Every process that maps a ring must be registered for its signals to skip their fences: the
// first mapping records whether it is, and a "not" is for good.
TEST(ShmRing, TheMappersBarrierFlagOnlyEverGoesToNot) {
  auto p = make(32);
  std::atomic<uint32_t>& mapper = p.memory.header()->mapper_barrier;
  const uint32_t mine = ring_barrier_registered() ? 1 : 2;
  auto first = RingMemory::map(UniqueFd(::dup(p.memory.fd())));
  ASSERT_TRUE(first);
  EXPECT_EQ(mapper.load(), mine);
  mapper.store(2);  // as a mapper that is not registered leaves it
  auto second = RingMemory::map(UniqueFd(::dup(p.memory.fd())));
  ASSERT_TRUE(second);
  EXPECT_EQ(mapper.load(), 2u);
}

// A view made on a ring whose positions make no sense is corrupted from the start (its first
// access would otherwise trust them).
TEST(ShmRing, AViewOnCorruptPositionsIsCorruptedFromTheStart) {
  auto p = make(32);
  p.memory.header()->write_pos.store(uint64_t{p.memory.capacity()} + 5);
  RingReader reader(p.memory, p.writer_event.get(), p.reader_event.get());
  EXPECT_TRUE(reader.corrupted());
  Element out;
  EXPECT_EQ(reader.get(&out), RingStatus::corrupted);
  p.memory.header()->write_pos.store(3);
  p.memory.header()->read_pos.store(4);  // the reader ahead of the writer
  RingWriter writer(p.memory, p.reader_event.get(), p.writer_event.get());
  EXPECT_TRUE(writer.corrupted());
  const Element e = element(1);
  EXPECT_EQ(writer.put(&e), RingStatus::corrupted);
}

}  // namespace
}  // namespace canemu::ipc
