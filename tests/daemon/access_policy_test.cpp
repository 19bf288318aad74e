// [security]: root and the daemon's own user always, listed users by uid, listed groups by the
// peer's groups as the kernel reports them; names that do not exist are logged and left out.
#include "canemu/daemon/access_policy.hpp"

#include <gtest/gtest.h>

#include <grp.h>
#include <sys/socket.h>
#include <unistd.h>
#include <memory>

#include "canemu/daemon/log.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::daemon {
namespace {

// A connected pair: the peer of one end is this process (its uid and groups).
struct Peer {
  ipc::UniqueFd ours;
  ipc::UniqueFd theirs;
  Peer() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0);
    ours.reset(fds[0]);
    theirs.reset(fds[1]);
  }
};

// A uid nobody on the machine has, and so no group lists it either.
constexpr uint32_t kStranger = 0x7FFF0001;

TEST(AccessPolicy, RootAndTheDaemonsOwnUserAreAlwaysAllowed) {
  AccessPolicy policy;
  Peer p;
  EXPECT_TRUE(policy.allowed(p.ours.get(), 0));
  EXPECT_TRUE(policy.allowed(p.ours.get(), static_cast<uint32_t>(::geteuid())));
  EXPECT_FALSE(policy.allowed(p.ours.get(), kStranger));
}

TEST(AccessPolicy, ListedUsersAreResolvedToUidsAndUnknownNamesAreLoggedAndLeftOut) {
  AccessPolicy policy;
  log::Capture capture;
  SecurityConfig security;
  security.allowed_users = {"root", "no-such-user-canemu"};
  security.allowed_groups = {"no-such-group-canemu"};
  policy.resolve(security);
  EXPECT_EQ(policy.uids(), std::vector<uint32_t>{0});
  EXPECT_TRUE(policy.gids().empty());
  EXPECT_EQ(capture.lines(),
            (std::vector<std::string>{
                "<4>canemud: [security] user \"no-such-user-canemu\" does not exist",
                "<4>canemud: [security] group \"no-such-group-canemu\" does not exist"}));
  security.allowed_users.clear();
  policy.resolve(security);  // a reload replaces the lists
  EXPECT_TRUE(policy.uids().empty());
}

// A group of the machine other than this process's own (whose gid the kernel does not report
// among the supplementary groups).
const group* some_other_group() {
  ::setgrent();
  const group* found = nullptr;
  while (const group* g = ::getgrent()) {
    if (g->gr_gid != ::getegid()) {
      found = g;
      break;
    }
  }
  ::endgrent();
  return found;
}

// The kernel reports a peer's supplementary groups. Root gives this process one for the time
// it makes the socket pair (whose credentials are taken then); others use one they are in.
TEST(AccessPolicy, APeerInAListedGroupIsAllowedWhateverItsUid) {
  std::vector<gid_t> saved(static_cast<std::size_t>(::getgroups(0, nullptr)));
  ASSERT_EQ(::getgroups(static_cast<int>(saved.size()), saved.data()),
            static_cast<int>(saved.size()));
  std::string name;
  std::unique_ptr<Peer> p;
  if (::geteuid() == 0) {
    const group* g = some_other_group();
    ASSERT_NE(g, nullptr);
    name = g->gr_name;
    const gid_t listed = g->gr_gid;
    ASSERT_EQ(::setgroups(1, &listed), 0);
    p = std::make_unique<Peer>();
    ASSERT_EQ(::setgroups(saved.size(), saved.data()), 0);
  } else if (const group* g = saved.empty() ? nullptr : ::getgrgid(saved.front())) {
    name = g->gr_name;
    p = std::make_unique<Peer>();
  } else {
    GTEST_SKIP() << "not root and in no named supplementary group";
  }
  AccessPolicy policy;
  SecurityConfig security;
  security.allowed_groups = {name};
  policy.resolve(security);
  EXPECT_TRUE(policy.allowed(p->ours.get(), kStranger));
  policy.resolve(SecurityConfig{});
  EXPECT_FALSE(policy.allowed(p->ours.get(), kStranger));
}

}  // namespace
}  // namespace canemu::daemon
