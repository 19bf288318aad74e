// One-way latency through a channel ring when the reader blocks (it sleeps on its eventfd, no
// spinning), beside baselines measured in the same run: a bare eventfd wake-up (the floor of any
// blocking hand-over) and a Unix socket, one-way and round trip over a SOCK_SEQPACKET pair. The
// writer waits between messages, so the reader is asleep each time. Targets: p50 <= 5 us, p99 <= 50
// us.
#include <benchmark/benchmark.h>

#include <cstring>

#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../support/latency.hpp"
#include "canemu/ipc/channel_message.hpp"
#include "canemu/ipc/shm_ring.hpp"

namespace {

using namespace canemu::ipc;
using canemu::bench::now_ns;
using canemu::bench::report;
using canemu::bench::SharedSamples;
using canemu::bench::sleep_ns;

constexpr std::size_t kSamples = 5000;
constexpr int64_t kGapNs = 200'000;  // between messages: the reader is asleep again by then

void BM_RingOneWayLatencyBlocking(benchmark::State& state) {
  auto memory = RingMemory::create(1024, sizeof(ChannelMessage), "bench-latency");
  auto reader_event = make_eventfd();
  auto writer_event = make_eventfd();
  SharedSamples samples(kSamples);
  if (!memory || !reader_event || !writer_event || !samples.valid()) {
    state.SkipWithError("setup failed");
    return;
  }
  for (auto _ : state) {
    const pid_t child = ::fork();
    if (child == 0) {
      RingReader r(*memory, writer_event->get(), reader_event->get());
      ChannelMessage m;
      for (std::size_t i = 0; i < kSamples;) {
        if (r.get(&m) == RingStatus::ok) {
          samples[i++] = now_ns() - m.timestamp_ns;
        } else {
          r.wait(-1);
        }
      }
      ::_exit(0);
    }
    RingWriter w(*memory, reader_event->get(), writer_event->get());
    ChannelMessage m;
    for (std::size_t i = 0; i < kSamples; ++i) {
      sleep_ns(kGapNs);
      m.timestamp_ns = now_ns();
      while (w.put(&m) != RingStatus::ok) {
      }
    }
    ::waitpid(child, nullptr, 0);
  }
  report(state, "ring_one_way", samples.vector());
}
BENCHMARK(BM_RingOneWayLatencyBlocking)->Iterations(1)->Unit(benchmark::kMillisecond);

// The floor under any blocking wake-up: a process blocked in read() on an eventfd, woken by a
// write from another process, with nothing else involved.
void BM_EventfdWakeBaseline(benchmark::State& state) {
  SharedSamples samples(kSamples + 1);  // the last slot counts the samples taken
  auto efd = make_eventfd();
  if (!samples.valid() || !efd) {
    state.SkipWithError("setup failed");
    return;
  }
  for (auto _ : state) {
    const pid_t child = ::fork();
    if (child == 0) {
      pollfd p{efd->get(), POLLIN, 0};
      for (std::size_t i = 0; i < kSamples; ++i) {
        uint64_t sent = 0;
        while (::read(efd->get(), &sent, sizeof sent) != sizeof sent) {
          ::poll(&p, 1, -1);
        }
        samples[i] = now_ns() - static_cast<int64_t>(sent);
        __atomic_store_n(&samples[kSamples], static_cast<int64_t>(i + 1), __ATOMIC_RELEASE);
      }
      ::_exit(0);
    }
    for (std::size_t i = 0; i < kSamples; ++i) {
      // One write per read: the next only after the child took this one (eventfd writes that
      // meet add up).
      while (__atomic_load_n(&samples[kSamples], __ATOMIC_ACQUIRE) != static_cast<int64_t>(i)) {
      }
      sleep_ns(kGapNs);
      const auto t = static_cast<uint64_t>(now_ns());
      (void)!::write(efd->get(), &t, sizeof t);
    }
    ::waitpid(child, nullptr, 0);
  }
  std::vector<int64_t> taken = samples.vector();
  taken.pop_back();
  report(state, "eventfd_wake", taken);
}
BENCHMARK(BM_EventfdWakeBaseline)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_UnixSocketLatencyBaseline(benchmark::State& state) {
  SharedSamples one_way(kSamples);
  std::vector<int64_t> round_trip(kSamples);
  int fds[2];
  if (!one_way.valid() || ::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fds) != 0) {
    state.SkipWithError("setup failed");
    return;
  }
  for (auto _ : state) {
    const pid_t child = ::fork();
    if (child == 0) {
      // Echoes every message; records how long each took to arrive.
      int64_t sent = 0;
      for (std::size_t i = 0; i < kSamples; ++i) {
        if (::recv(fds[1], &sent, sizeof sent, 0) != sizeof sent) {
          ::_exit(1);
        }
        one_way[i] = now_ns() - sent;
        (void)!::send(fds[1], &sent, sizeof sent, 0);
      }
      ::_exit(0);
    }
    for (std::size_t i = 0; i < kSamples; ++i) {
      sleep_ns(kGapNs);
      int64_t t = now_ns();
      (void)!::send(fds[0], &t, sizeof t, 0);
      (void)!::recv(fds[0], &t, sizeof t, 0);
      round_trip[i] = now_ns() - t;
    }
    ::waitpid(child, nullptr, 0);
  }
  ::close(fds[0]);
  ::close(fds[1]);
  report(state, "unix_socket_one_way", one_way.vector());
  report(state, "unix_socket_round_trip", round_trip);
}
BENCHMARK(BM_UnixSocketLatencyBaseline)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
