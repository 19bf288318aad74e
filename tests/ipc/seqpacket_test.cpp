#include "canemu/ipc/seqpacket.hpp"

#include <gtest/gtest.h>

#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

namespace canemu::ipc {
namespace {

struct SocketPair {
  UniqueFd a;
  UniqueFd b;
  SocketPair() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0);
    a.reset(fds[0]);
    b.reset(fds[1]);
  }
};

TEST(SeqPacket, DescriptorsTravelWithTheirPacket) {
  SocketPair s;
  UniqueFd e1(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  UniqueFd e2(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  const int fds[] = {e1.get(), e2.get()};
  const char text[] = "hello";
  ASSERT_TRUE(send_packet(s.a.get(), text, sizeof text, fds));
  std::vector<uint8_t> buffer;
  std::vector<UniqueFd> got;
  auto n = receive_packet(s.b.get(), buffer, 1000, &got);
  ASSERT_TRUE(n);
  EXPECT_EQ(*n, sizeof text);
  ASSERT_EQ(got.size(), 2u);
  // The received descriptors are the same eventfds: a write on one side is read on the other.
  const uint64_t seven = 7;
  ASSERT_EQ(::write(e2.get(), &seven, sizeof seven), 8);
  uint64_t value = 0;
  ASSERT_EQ(::read(got[1].get(), &value, sizeof value), 8);
  EXPECT_EQ(value, 7u);
  EXPECT_NE(got[0].get(), e1.get());
}

TEST(SeqPacket, DescriptorsNobodyAskedForAreClosed) {
  SocketPair s;
  UniqueFd e(::eventfd(0, EFD_CLOEXEC));
  const int fds[] = {e.get()};
  const char text[] = "x";
  ASSERT_TRUE(send_packet(s.a.get(), text, sizeof text, fds));
  std::vector<uint8_t> buffer;
  const int before = ::dup(0);
  ::close(before);
  ASSERT_TRUE(receive_packet(s.b.get(), buffer, 1000));
  // The lowest free descriptor is the same as before: nothing was left open.
  const int after = ::dup(0);
  ::close(after);
  EXPECT_EQ(before, after);
}

TEST(SeqPacket, TooManyDescriptorsAreRefused) {
  SocketPair s;
  std::vector<int> fds(kMaxPassedFds + 1, 0);
  const char text[] = "x";
  auto r = send_packet(s.a.get(), text, sizeof text, fds);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().error_number, EINVAL);
}

}  // namespace
}  // namespace canemu::ipc
