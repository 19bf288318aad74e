// [security]: root and the daemon's own user always, listed users by uid, listed groups by the
// peer's groups as the kernel reports them; names that do not exist are logged and left out.
#include "canemu/daemon/loop/access_policy.hpp"

#include <gtest/gtest.h>

#include <grp.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <memory>

#include "canemu/daemon/base/log.hpp"
#include "canemu/ipc/seqpacket.hpp"
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

// A uid nobody on the machine has, and so no group lists it either; a gid no group has.
constexpr uint32_t kStranger = 0x7FFF0001;
constexpr uint32_t kStrangerGid = 0x7FFF0002;

TEST(AccessPolicy, RootAndTheDaemonsOwnUserAreAlwaysAllowed) {
  AccessPolicy policy;
  Peer p;
  EXPECT_TRUE(policy.allowed(p.ours.get(), 0, kStrangerGid));
  EXPECT_TRUE(policy.allowed(p.ours.get(), static_cast<uint32_t>(::geteuid()), kStrangerGid));
  EXPECT_FALSE(policy.allowed(p.ours.get(), kStranger, kStrangerGid));
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
  EXPECT_EQ(
      capture.lines(),
      (std::vector<std::string>{
          "<4>canemud: [security] user \"no-such-user-canemu\" does not exist",
          "<4>canemud: [security] allowed_groups: group \"no-such-group-canemu\" does not exist"}));
  security.allowed_users.clear();
  policy.resolve(security);  // a reload replaces the lists
  EXPECT_TRUE(policy.uids().empty());
}

// A group of the machine other than this process's own and not among its supplementary ones.
const group* some_other_group() {
  std::vector<gid_t> mine(static_cast<std::size_t>(::getgroups(0, nullptr)));
  ::getgroups(static_cast<int>(mine.size()), mine.data());
  ::setgrent();
  const group* found = nullptr;
  while (const group* g = ::getgrent()) {
    if (g->gr_gid != ::getegid() && std::find(mine.begin(), mine.end(), g->gr_gid) == mine.end()) {
      found = g;
      break;
    }
  }
  ::endgrent();
  return found;
}

// A peer's primary group (SO_PEERCRED) counts like a supplementary one.
TEST(AccessPolicy, APeerWhosePrimaryGroupIsListedIsAllowed) {
  const group* g = some_other_group();
  ASSERT_NE(g, nullptr);
  const std::string name = g->gr_name;
  const uint32_t gid = g->gr_gid;
  AccessPolicy policy;
  SecurityConfig security;
  security.allowed_groups = {name};
  policy.resolve(security);
  Peer p;
  EXPECT_TRUE(policy.allowed(p.ours.get(), kStranger, gid));
  EXPECT_FALSE(policy.allowed(p.ours.get(), kStranger, kStrangerGid));
}

// By default the group the packages create may connect; where it does not exist, canemud says so
// without a warning, while a group the configuration names and the machine lacks is a warning.
TEST(AccessPolicy, TheServiceGroupIsAllowedByDefaultAndItsAbsenceIsNoWarning) {
  EXPECT_EQ(SecurityConfig{}.allowed_groups, std::vector<std::string>{"canemu"});
  log::Capture capture;
  AccessPolicy policy;
  policy.resolve(SecurityConfig{});
  for (const std::string& line : capture.lines()) {
    EXPECT_EQ(line.rfind("<4>", 0), std::string::npos) << line;
  }
  EXPECT_EQ(policy.gids().size(), ::getgrnam("canemu") != nullptr ? 1u : 0u);
}

// The socket file gets the configured mode and group.
TEST(AccessPolicy, TheSocketGetsTheConfiguredModeAndGroup) {
  char dir[] = "/tmp/canemu-perm-XXXXXX";
  const std::string file = std::string(::mkdtemp(dir)) + "/canemud.sock";
  auto listening = ipc::listen_seqpacket(file);
  ASSERT_TRUE(listening) << listening.error().message;
  auto bound = AccessPolicy::socket_file(file);
  ASSERT_TRUE(bound) << bound.error();
  const group* own = ::getgrgid(::getegid());
  ASSERT_NE(own, nullptr);
  SecurityConfig security;
  security.socket_mode = 0640;
  security.socket_group = own->gr_name;
  EXPECT_EQ(AccessPolicy::apply_socket_permissions(file, *bound, security), "");
  struct stat st {};
  ASSERT_EQ(::stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  EXPECT_EQ(st.st_gid, ::getegid());
  log::Capture capture;
  security.socket_mode = 0600;
  security.socket_group = "no-such-group-canemu";
  EXPECT_EQ(AccessPolicy::apply_socket_permissions(file, *bound, security), "");
  ASSERT_EQ(::stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  ASSERT_EQ(capture.lines().size(), 1u);
  EXPECT_NE(capture.lines()[0].find("socket_group \"no-such-group-canemu\" does not exist"),
            std::string::npos)
      << capture.lines()[0];
  EXPECT_NE(AccessPolicy::apply_socket_permissions(file + ".missing", *bound, security)
                .find("cannot open " + file + ".missing: No such file or directory"),
            std::string::npos);
  ::unlink(file.c_str());
  ::rmdir(dir);
}

// A reload applies the mode and group to the socket that was bound, never to what a link or
// another file at its path leads to (canemud runs as root there).
TEST(AccessPolicy, ALinkOrAnotherFileInTheSocketsPlaceIsLeftAlone) {
  char dir[] = "/tmp/canemu-perm-XXXXXX";
  const std::string folder = ::mkdtemp(dir);
  const std::string file = folder + "/canemud.sock";
  const std::string victim = folder + "/victim";
  auto listening = ipc::listen_seqpacket(file);
  ASSERT_TRUE(listening) << listening.error().message;
  auto bound = AccessPolicy::socket_file(file);
  ASSERT_TRUE(bound) << bound.error();
  FILE* f = std::fopen(victim.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  ASSERT_EQ(::chmod(victim.c_str(), 0600), 0);
  SecurityConfig security;
  security.socket_mode = 0666;
  const auto mode_of = [](const std::string& path) {
    struct stat st {};
    EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
    return st.st_mode & 07777;
  };
  // A symbolic link to another file in its place.
  ASSERT_EQ(::unlink(file.c_str()), 0);
  ASSERT_EQ(::symlink(victim.c_str(), file.c_str()), 0);
  EXPECT_NE(AccessPolicy::apply_socket_permissions(file, *bound, security)
                .find("is no longer the socket canemud bound (a symbolic link is there now)"),
            std::string::npos);
  EXPECT_EQ(mode_of(victim), 0600u);
  // A hard link to another file.
  ASSERT_EQ(::unlink(file.c_str()), 0);
  ASSERT_EQ(::link(victim.c_str(), file.c_str()), 0);
  EXPECT_NE(AccessPolicy::apply_socket_permissions(file, *bound, security).find("another file"),
            std::string::npos);
  EXPECT_EQ(mode_of(victim), 0600u);
  // Another socket bound at the path.
  ASSERT_EQ(::unlink(file.c_str()), 0);
  auto other = ipc::listen_seqpacket(file);
  ASSERT_TRUE(other) << other.error().message;
  ASSERT_EQ(::chmod(file.c_str(), 0600), 0);
  EXPECT_NE(AccessPolicy::apply_socket_permissions(file, *bound, security).find("another socket"),
            std::string::npos);
  EXPECT_EQ(mode_of(file), 0600u);
  ::unlink(file.c_str());
  ::unlink(victim.c_str());
  ::rmdir(dir);
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
  EXPECT_TRUE(policy.allowed(p->ours.get(), kStranger, kStrangerGid));
  policy.resolve(SecurityConfig{});
  EXPECT_FALSE(policy.allowed(p->ours.get(), kStranger, kStrangerGid));
}

}  // namespace
}  // namespace canemu::daemon
