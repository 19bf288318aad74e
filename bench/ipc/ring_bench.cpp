// Throughput of the shared-memory ring between two processes, busy-polling, with 80-byte
// elements (the size of a VCI CANMSG2), beside a baseline measured in the same run: a bare SPSC
// ring in shared memory with no validation and no events. Target: >= 10 million elements/s.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <optional>

#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include "canemu/ipc/shm_ring.hpp"

namespace {

using namespace canemu::ipc;

constexpr uint32_t kElement = 80;
constexpr uint64_t kCount = 2'000'000;

struct Message {
  uint8_t bytes[kElement];
};

struct Ring {
  RingMemory memory;
  UniqueFd reader_event;
  UniqueFd writer_event;
};

std::optional<Ring> make_ring(const char* name) {
  auto memory = RingMemory::create(1024, kElement, name);
  auto reader_event = make_eventfd();
  auto writer_event = make_eventfd();
  if (!memory || !reader_event || !writer_event) {
    return std::nullopt;
  }
  return Ring{std::move(*memory), std::move(*reader_event), std::move(*writer_event)};
}

// Runs `produce` in a forked child and `consume` (which takes kCount elements and returns a
// checksum of them) in this process, once per benchmark iteration.
template <typename Produce, typename Consume>
void run_between_processes(benchmark::State& state, Produce produce, Consume consume) {
  uint64_t total = 0;
  for (auto _ : state) {
    const pid_t child = ::fork();
    if (child == 0) {
      produce();
      ::_exit(0);
    }
    const uint64_t check = consume();
    ::waitpid(child, nullptr, 0);
    benchmark::DoNotOptimize(check);
    total += kCount;
  }
  state.counters["elements_per_second"] =
      benchmark::Counter(static_cast<double>(total), benchmark::Counter::kIsRate);
}

void BM_RingTwoProcessesBusyPoll(benchmark::State& state) {
  auto ring = make_ring("bench-ring");
  if (!ring) {
    state.SkipWithError("ring setup failed");
    return;
  }
  run_between_processes(
      state,
      [&] {
        // The writer maps the ring as the other process does (the daemon creates, a client
        // maps).
        auto mapped = RingMemory::map(UniqueFd(::dup(ring->memory.fd())));
        if (!mapped) {
          ::_exit(1);
        }
        RingWriter w(*mapped, ring->reader_event.get(), ring->writer_event.get());
        Message m{};
        for (uint64_t i = 0; i < kCount;) {
          std::memcpy(m.bytes, &i, sizeof i);
          if (w.put(&m) == RingStatus::ok) {
            ++i;
          }
        }
      },
      [&] {
        RingReader r(ring->memory, ring->writer_event.get(), ring->reader_event.get());
        Message m{};
        uint64_t check = 0;
        for (uint64_t got = 0; got < kCount;) {
          if (r.get(&m) == RingStatus::ok) {
            uint64_t v;
            std::memcpy(&v, m.bytes, sizeof v);
            check += v;
            ++got;
          }
        }
        return check;
      });
}

// The same ring used the way the daemon and the client libraries move frames: whole runs with
// AcquireWrite/ReleaseWrite and AcquireRead/ReleaseRead, so the event bookkeeping (one fence per
// access) is paid per run, not per element.
void BM_RingTwoProcessesBusyPollRuns(benchmark::State& state) {
  auto ring = make_ring("bench-ring-runs");
  if (!ring) {
    state.SkipWithError("ring setup failed");
    return;
  }
  run_between_processes(
      state,
      [&] {
        // The writer maps the ring as the other process does (the daemon creates, a client
        // maps).
        auto mapped = RingMemory::map(UniqueFd(::dup(ring->memory.fd())));
        if (!mapped) {
          ::_exit(1);
        }
        RingWriter w(*mapped, ring->reader_event.get(), ring->writer_event.get());
        for (uint64_t i = 0; i < kCount;) {
          void* slots = nullptr;
          uint32_t n = 0;
          if (w.acquire(&slots, &n) != RingStatus::ok) {
            continue;
          }
          n = static_cast<uint32_t>(std::min<uint64_t>({n, 64, kCount - i}));
          auto* m = static_cast<Message*>(slots);
          for (uint32_t k = 0; k < n; ++k, ++i) {
            std::memcpy(m[k].bytes, &i, sizeof i);
          }
          w.release(n);
        }
      },
      [&] {
        RingReader r(ring->memory, ring->writer_event.get(), ring->reader_event.get());
        uint64_t check = 0;
        for (uint64_t got = 0; got < kCount;) {
          const void* slots = nullptr;
          uint32_t n = 0;
          if (r.acquire(&slots, &n) != RingStatus::ok) {
            continue;
          }
          const auto* m = static_cast<const Message*>(slots);
          for (uint32_t k = 0; k < n; ++k) {
            uint64_t v;
            std::memcpy(&v, m[k].bytes, sizeof v);
            check += v;
          }
          r.release(n);
          got += n;
        }
        return check;
      });
}

// The baseline: the simplest correct SPSC ring in shared memory. Its positions only grow, so
// one ring serves every iteration.
struct alignas(64) Bare {
  alignas(64) std::atomic<uint64_t> head{0};
  alignas(64) std::atomic<uint64_t> tail{0};
  alignas(64) Message slots[1024];
};

void BM_BareSpscRingTwoProcessesBaseline(benchmark::State& state) {
  void* mem =
      ::mmap(nullptr, sizeof(Bare), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (mem == MAP_FAILED) {
    state.SkipWithError("mmap failed");
    return;
  }
  Bare* ring = new (mem) Bare{};
  run_between_processes(
      state,
      [&] {
        Message m{};
        for (uint64_t i = 0; i < kCount;) {
          const uint64_t head = ring->head.load(std::memory_order_relaxed);
          if (head - ring->tail.load(std::memory_order_acquire) < 1024) {
            std::memcpy(m.bytes, &i, sizeof i);
            ring->slots[head % 1024] = m;
            ring->head.store(head + 1, std::memory_order_release);
            ++i;
          }
        }
      },
      [&] {
        uint64_t check = 0;
        for (uint64_t got = 0; got < kCount;) {
          const uint64_t tail = ring->tail.load(std::memory_order_relaxed);
          if (ring->head.load(std::memory_order_acquire) != tail) {
            uint64_t v;
            std::memcpy(&v, ring->slots[tail % 1024].bytes, sizeof v);
            check += v;
            ring->tail.store(tail + 1, std::memory_order_release);
            ++got;
          }
        }
        return check;
      });
  ::munmap(mem, sizeof(Bare));
}

BENCHMARK(BM_RingTwoProcessesBusyPoll)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RingTwoProcessesBusyPollRuns)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BareSpscRingTwoProcessesBaseline)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
