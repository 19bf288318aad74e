// A channel's ring pair and a FIFO's ring as the two processes hold them: canemud creates, the
// client maps the descriptors it received (here: duplicates, as SCM_RIGHTS would give), and the
// views of both sides talk through the one memory, each waking the other on its eventfd.
#include "canemu/ipc/ring_pair.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

namespace canemu::ipc {
namespace {

struct Element {
  uint32_t seq;
  uint8_t payload[12];
};
static_assert(sizeof(Element) == 16);

// What the other process would receive for `fds`: its own descriptors of the same files.
template <std::size_t N>
std::vector<UniqueFd> received(const std::array<int, N>& fds) {
  std::vector<UniqueFd> out;
  for (int fd : fds) {
    out.emplace_back(fd < 0 ? -1 : ::fcntl(fd, F_DUPFD_CLOEXEC, 0));
  }
  return out;
}

bool readable(int fd) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, 0) == 1;
}

RingPair made(uint32_t rx_capacity = 32, uint32_t tx_capacity = 8) {
  auto pair = RingPair::create(rx_capacity, tx_capacity, sizeof(Element), "test", "dev1");
  EXPECT_TRUE(pair) << pair.error().message;
  return std::move(*pair);
}

TEST(RingPair, CanemudCreatesBothRingsAndTheThreeEventfdsOfTheProtocol) {
  const RingPair pair = made();
  // (4096 - 256) / 16 = 240 elements fill each ring's one page.
  EXPECT_EQ(pair.rx().memory().capacity(), 240u);
  EXPECT_EQ(pair.tx().memory().capacity(), 240u);
  EXPECT_EQ(pair.element_size(), sizeof(Element));
  EXPECT_EQ(pair.element_bytes(), 480u * sizeof(Element));
  // canemud never waits for room in the receive ring: no eventfd for that side.
  EXPECT_EQ(pair.rx().writer_event(), -1);
  const auto fds = pair.fds();
  EXPECT_EQ(fds[0], pair.rx().memory().fd());
  EXPECT_EQ(fds[1], pair.tx().memory().fd());
  EXPECT_EQ(fds[2], pair.rx().reader_event());
  EXPECT_EQ(fds[3], pair.tx().writer_event());
  EXPECT_EQ(fds[4], pair.tx().reader_event());
  for (int fd : fds) {
    EXPECT_GE(fd, 0);
    EXPECT_EQ(::fcntl(fd, F_GETFD) & FD_CLOEXEC, FD_CLOEXEC);
  }
}

TEST(RingPair, TheMemfdsAreNamedAfterTheDevice) {
  const RingPair pair = made();
  char link[256] = {};
  const std::string path = "/proc/self/fd/" + std::to_string(pair.rx().memory().fd());
  ASSERT_GT(::readlink(path.c_str(), link, sizeof link - 1), 0);
  EXPECT_EQ(std::string(link).rfind("/memfd:test-rx-dev1", 0), 0u) << link;
}

TEST(RingPair, AMappedPairCarriesElementsBothWays) {
  const RingPair daemon = made();
  auto client = RingPair::map(received(daemon.fds()), sizeof(Element));
  ASSERT_TRUE(client) << client.error().message;
  RingWriter daemon_rx = daemon.rx().writer();
  RingReader daemon_tx = daemon.tx().reader();
  RingReader client_rx = client->rx().reader();
  RingWriter client_tx = client->tx().writer();

  const Element down{7, {1, 2, 3}};
  ASSERT_EQ(daemon_rx.put(&down), RingStatus::ok);
  Element got{};
  ASSERT_EQ(client_rx.get(&got), RingStatus::ok);
  EXPECT_EQ(got.seq, 7u);
  EXPECT_EQ(got.payload[2], 3);

  const Element up{9, {4}};
  ASSERT_EQ(client_tx.put(&up), RingStatus::ok);
  ASSERT_EQ(daemon_tx.get(&got), RingStatus::ok);
  EXPECT_EQ(got.seq, 9u);
  EXPECT_EQ(daemon_tx.get(&got), RingStatus::empty);
}

TEST(RingPair, TheClientsPutRingsTheDoorbellOfASleepingDaemon) {
  const RingPair daemon = made();
  auto client = RingPair::map(received(daemon.fds()), sizeof(Element));
  ASSERT_TRUE(client);
  RingReader daemon_tx = daemon.tx().reader();
  RingWriter client_tx = client->tx().writer();
  ASSERT_TRUE(daemon_tx.arm_unless_filled());  // the daemon sleeps on its doorbell
  EXPECT_FALSE(readable(daemon.tx().reader_event()));
  const Element e{1, {}};
  ASSERT_EQ(client_tx.put(&e), RingStatus::ok);
  EXPECT_TRUE(readable(daemon.tx().reader_event()));
  // And the daemon's put wakes the client blocked on the receive ring's eventfd.
  RingWriter daemon_rx = daemon.rx().writer();
  RingReader client_rx = client->rx().reader();
  ASSERT_TRUE(client_rx.arm_unless_filled());
  ASSERT_EQ(daemon_rx.put(&e), RingStatus::ok);
  EXPECT_TRUE(readable(client->rx().reader_event()));
}

TEST(RingPair, MappingChecksTheDescriptorCountAndTheElementSize) {
  const RingPair daemon = made();
  auto fds = received(daemon.fds());
  fds.pop_back();
  auto short_of_one = RingPair::map(std::move(fds), sizeof(Element));
  ASSERT_FALSE(short_of_one);
  EXPECT_EQ(short_of_one.error().error_number, EPROTO);
  EXPECT_EQ(short_of_one.error().message, "a ring pair comes with 5 descriptors, not 4");

  auto other_size = RingPair::map(received(daemon.fds()), 20);
  ASSERT_FALSE(other_size);
  EXPECT_EQ(other_size.error().error_number, EPROTO);
  EXPECT_EQ(other_size.error().message, "ring of 16-byte elements where 20 were expected");
}

TEST(RingPair, MappingRefusesMemoryThatIsNotARing) {
  const RingPair daemon = made();
  auto fds = received(daemon.fds());
  fds[1] = UniqueFd(::fcntl(daemon.rx().reader_event(), F_DUPFD_CLOEXEC, 0));  // an eventfd
  auto mapped = RingPair::map(std::move(fds), sizeof(Element));
  ASSERT_FALSE(mapped);
  EXPECT_EQ(mapped.error().error_number, EINVAL);
}

TEST(RingPair, ACapacityOutOfRangeIsRefused) {
  EXPECT_FALSE(RingPair::create(0, 8, sizeof(Element), "test", "x"));
  EXPECT_FALSE(RingPair::create(8, 70000, sizeof(Element), "test", "x"));
}

TEST(SharedRing, AStandAloneFifoPassesMemoryReaderAndWriterEventfdsInThatOrder) {
  auto fifo = SharedRing::create(16, sizeof(Element), "test-fifo");
  ASSERT_TRUE(fifo) << fifo.error().message;
  EXPECT_EQ(fifo->fds(), (std::array<int, kFifoFdCount>{fifo->memory().fd(), fifo->reader_event(),
                                                        fifo->writer_event()}));
  EXPECT_GE(fifo->writer_event(), 0);
  auto fds = received(fifo->fds());
  auto other = SharedRing::map(std::move(fds[0]), std::move(fds[1]), std::move(fds[2]), 0);
  ASSERT_TRUE(other) << other.error().message;
  // A writer here, a reader there: the reader waiting for a put is woken on its eventfd, the
  // writer waiting for room on its own.
  RingWriter writer = fifo->writer();
  RingReader reader = other->reader();
  ASSERT_TRUE(reader.arm_unless_filled());
  const Element e{3, {}};
  ASSERT_EQ(writer.put(&e), RingStatus::ok);
  EXPECT_TRUE(readable(other->reader_event()));
  writer.set_threshold(writer.free_count() + 1);  // room for one more is what it waits for
  writer.own_event().arm();
  EXPECT_FALSE(readable(fifo->writer_event()));
  ASSERT_EQ(reader.get(nullptr), RingStatus::ok);
  EXPECT_TRUE(readable(fifo->writer_event()));
}

}  // namespace
}  // namespace canemu::ipc
