// Who may connect, with clients running as other users: canemud (as root, as CI runs it) serves
// peers whose uid or groups [security] allows, the socket file's mode and group keep out the rest
// before canemud sees them, and a reload that revokes a peer drops its connection.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <grp.h>
#include <libgen.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "canemu/client/channel.hpp"
#include "canemu/ipc/channel_message.hpp"
#include "canemu/ipc/seqpacket.hpp"
#include "daemon_process.hpp"
#include "pipe_support.hpp"

namespace canemu {
namespace {

using testing::Daemon;

constexpr uid_t kNobody = 65534;
constexpr gid_t kNogroup = 65534;

// What a client running as `uid`, primary group `gid` and supplementary `groups` got.
enum Outcome { kServed = 0, kRefusedByCanemud = 1, kRefusedByTheKernel = 2, kOther = 3 };

// Runs `body` in a child process with those credentials; its exit status is the outcome.
template <typename Body>
int as_user(uid_t uid, gid_t gid, const std::vector<gid_t>& groups, Body body) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::setgroups(groups.size(), groups.data()) != 0 || ::setgid(gid) != 0 ||
        ::setuid(uid) != 0) {
      ::_exit(kOther);
    }
    ::_exit(body());
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : kOther;
}

int connect_and_ask(const std::string& socket) {
  auto c = client::Connection::open(socket, "other user");
  if (!c) {
    if (c.error().message.find("not allowed by the [security] configuration") !=
        std::string::npos) {
      return kRefusedByCanemud;
    }
    return c.error().message.find("Permission denied") != std::string::npos ? kRefusedByTheKernel
                                                                            : kOther;
  }
  auto r = c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  return r ? kServed : kOther;
}

struct Rig {
  std::string dir;
  std::string file;
  gid_t users = 0;
  Rig() {
    char d[] = "/tmp/canemu-access-XXXXXX";
    dir = ::mkdtemp(d);
    ::chmod(dir.c_str(), 0755);
    file = dir + "/canemud.toml";
    const group* g = ::getgrnam("users");
    users = g != nullptr ? g->gr_gid : 0;
  }
  ~Rig() {
    ::unlink(file.c_str());
    ::rmdir(dir.c_str());
  }
  void write(const std::string& security) const {
    FILE* f = std::fopen(file.c_str(), "w");
    std::fputs(("[[bus]]\nname = \"can0\"\n\n[security]\n" + security).c_str(), f);
    std::fclose(f);
  }
};

// The daemon's socket lives in a private folder: let other users reach the socket itself.
void open_folder(const Daemon& d) {
  std::string path = d.socket();
  ::chmod(::dirname(path.data()), 0755);
}

// Clients run as other users: the tests need root (else they are skipped) and the machine's
// group "users"; `start` writes the [security] table `security` into `rig`'s configuration and
// starts canemud in stepped time on it, its socket's folder open to other users.
class AccessAsUsers : public ::testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) {
      GTEST_SKIP() << "needs root to run clients as other users";
    }
    ASSERT_NE(rig.users, 0u) << "the machine has no group \"users\"";
  }
  Daemon& start(const std::string& security) {
    rig.write(security);
    daemon_.emplace("stepped", std::vector<std::string>{"--config=" + rig.file});
    open_folder(*daemon_);
    return *daemon_;
  }
  Rig rig;

 private:
  std::optional<Daemon> daemon_;
};

TEST_F(AccessAsUsers, PeersAreServedByUidPrimaryGroupOrSupplementaryGroupAndNoOneElse) {
  Daemon& d = start("allowed_groups = [\"users\"]\nsocket_mode = 0o666\nsocket_group = \"\"\n");
  const auto ask = [&] { return connect_and_ask(d.socket()); };
  EXPECT_EQ(as_user(kNobody, kNogroup, {}, ask), kRefusedByCanemud);
  EXPECT_EQ(as_user(kNobody, kNogroup, {rig.users}, ask), kServed);
  EXPECT_EQ(as_user(kNobody, rig.users, {}, ask), kServed);
}

TEST_F(AccessAsUsers, TheSocketsModeAndGroupKeepOutWhoeverMayNotWriteToIt) {
  // canemud itself would let everyone in; the file lets in only group users.
  Daemon& d =
      start("allowed_users = [\"nobody\"]\nsocket_mode = 0o660\nsocket_group = \"users\"\n");
  struct stat st {};
  ASSERT_EQ(::stat(d.socket().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0660u);
  EXPECT_EQ(st.st_gid, rig.users);
  const auto ask = [&] { return connect_and_ask(d.socket()); };
  EXPECT_EQ(as_user(kNobody, kNogroup, {}, ask), kRefusedByTheKernel);
  EXPECT_EQ(as_user(kNobody, kNogroup, {rig.users}, ask), kServed);
  // The refused user is told that it may not use the socket (not how to start canemud, which
  // runs), with the socket's path.
  const std::string socket = d.socket();
  EXPECT_EQ(as_user(kNobody, kNogroup, {},
                    [&] {
                      auto c = client::Connection::open(socket, "outsider");
                      const std::string m = c ? std::string() : c.error().message;
                      std::fprintf(stderr, "refused with: %s\n", m.c_str());
                      return m.find("is not allowed to use canemud's socket " + socket) !=
                                         std::string::npos &&
                                     m.find("make run") == std::string::npos
                                 ? 0
                                 : 1;
                    }),
            0);
}

TEST_F(AccessAsUsers, AReloadThatRevokesAPeerDropsItsConnection) {
  Daemon& d = start("allowed_groups = [\"users\"]\nsocket_mode = 0o666\nsocket_group = \"\"\n");
  testing::Pipe connected;
  testing::Pipe go_on;
  ASSERT_TRUE(connected.ok() && go_on.ok());
  const std::string socket = d.socket();
  const pid_t child = ::fork();
  if (child == 0) {
    const int outcome = as_user(kNobody, kNogroup, {rig.users}, [&] {
      auto c = client::Connection::open(socket, "revoked");
      const char ok = c ? '1' : '0';
      [[maybe_unused]] ssize_t w = ::write(connected[1], &ok, 1);
      char byte = 0;
      [[maybe_unused]] ssize_t r = ::read(go_on[0], &byte, 1);
      if (!c) {
        return static_cast<int>(kOther);
      }
      auto s =
          c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
      return s ? static_cast<int>(kServed) : static_cast<int>(kRefusedByCanemud);
    });
    ::_exit(outcome);
  }
  char ok = 0;
  ASSERT_EQ(::read(connected[0], &ok, 1), 1);
  ASSERT_EQ(ok, '1');
  rig.write("allowed_groups = []\nsocket_mode = 0o666\nsocket_group = \"\"\n");
  d.signal(SIGHUP);
  EXPECT_TRUE(d.read_log_until("is no longer allowed; connection closed", 10'000)) << d.log();
  ASSERT_EQ(::write(go_on[1], "x", 1), 1);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), kRefusedByCanemud);
  // Root stays served.
  auto admin = testing::connect(d, "admin");
  EXPECT_EQ(testing::status(admin).bus_count, 1);
}

// Fault scenarios belong to the user who loaded them: another user's client cannot clear one by
// name (permission_denied with the reason) nor by "all" (it is left and counted); a member of
// [security] admin_groups and root clear every one.
TEST_F(AccessAsUsers, AUserClearsOnlyItsOwnScenariosAndAnAdminClearsAll) {
  const group* admins = ::getgrnam("adm");
  ASSERT_NE(admins, nullptr) << "the machine has no group \"adm\"";
  const gid_t adm = admins->gr_gid;
  Daemon& d = start(
      "allowed_groups = [\"users\"]\nadmin_groups = [\"adm\"]\nsocket_mode = 0o666\n"
      "socket_group = \"\"\n");
  const std::string socket = d.socket();
  const std::string text =
      "[scenario]\nname = \"mine\"\n\n[[fault]]\nat = \"1s\"\nbus = \"can0\"\n"
      "effect = \"crc_error\"\n";
  // Returns 0 when loaded, 1 when not.
  const auto load = [&] {
    auto c = client::Connection::open(socket, "loader");
    if (!c) {
      return 1;
    }
    auto m = std::make_unique<ipc::FaultLoadRequest>(ipc::make_message<ipc::FaultLoadRequest>());
    m->length = static_cast<uint32_t>(text.size());
    std::memcpy(m->text, text.data(), text.size());
    auto r = c->call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(*m);
    return r && r->applied == 1 ? 0 : 1;
  };
  // Returns 10 + cleared + 20 * refused, 1 when refused with the reason, 2 on other failures.
  const auto clear = [&](const std::string& name) {
    return [&socket, name] {
      auto c = client::Connection::open(socket, "clearer");
      if (!c) {
        return 2;
      }
      auto m = ipc::make_message<ipc::FaultClearRequest>();
      ipc::copy_name(m.scenario, name);
      auto r = c->call<ipc::FaultClearRequest, ipc::FaultClearReply>(m);
      if (!r) {
        return r.error().message.find("is not yours to clear") != std::string::npos ? 1 : 2;
      }
      return static_cast<int>(10 + r->cleared + 20 * r->refused);
    };
  };
  constexpr uid_t kOther = 65533;
  ASSERT_EQ(as_user(kNobody, rig.users, {}, load), 0);
  EXPECT_EQ(as_user(kOther, rig.users, {}, clear("mine")), 1);
  EXPECT_EQ(as_user(kOther, rig.users, {}, clear("")), 10 + 0 + 20 * 1);
  EXPECT_EQ(as_user(kNobody, rig.users, {}, clear("mine")), 10 + 1);  // its own
  ASSERT_EQ(as_user(kNobody, rig.users, {}, load), 0);
  EXPECT_EQ(as_user(kOther, rig.users, {adm}, clear("")), 10 + 1);  // an admin
}

// Refused peers that connect and never ask anything take no slot of an allowed peer and hold no
// more than 16 descriptors: canemud keeps at most 16 of them waiting for their answer, and
// closes the rest at once.
TEST_F(AccessAsUsers, RefusedPeersThatNeverAskTakeNoSlotOfAllowedOnes) {
  Daemon& d = start("allowed_groups = []\nsocket_mode = 0o666\nsocket_group = \"\"\n");
  const std::string socket = d.socket();
  const auto descriptors = [&d] {
    std::size_t n = 0;
    for ([[maybe_unused]] const auto& e :
         std::filesystem::directory_iterator("/proc/" + std::to_string(d.pid()) + "/fd")) {
      ++n;
    }
    return n;
  };
  const std::size_t before = descriptors();
  testing::Pipe held;
  testing::Pipe ready;
  ASSERT_TRUE(held.ok() && ready.ok());
  const pid_t child = ::fork();
  if (child == 0) {
    held.close(1);
    ready.close(0);
    const int rc = as_user(kNobody, kNogroup, {}, [&] {
      std::vector<ipc::UniqueFd> silent;
      for (int k = 0; k < 300; ++k) {  // more than the daemon's 256 client slots
        auto fd = ipc::connect_seqpacket(socket);
        if (fd) {
          silent.push_back(std::move(*fd));
        }
      }
      [[maybe_unused]] ssize_t w = ::write(ready[1], "r", 1);
      char byte = 0;
      [[maybe_unused]] ssize_t r = ::read(held[0], &byte, 1);  // held until the parent is done
      return static_cast<int>(silent.size() >= 300 ? kServed : kOther);
    });
    ::_exit(rc);
  }
  held.close(0);
  ready.close(1);
  // Every silent peer has connected (and queues before root's connection).
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ready.close(0);
  auto admin = client::Connection::open(socket, "admin");
  ASSERT_TRUE(admin) << admin.error().message;
  EXPECT_EQ(testing::status(*admin).client_count, 1);
  // The 16 waiting refused peers and root's connection.
  EXPECT_LE(descriptors(), before + 16 + 1);
  ASSERT_EQ(::write(held[1], "x", 1), 1);
  held.close(1);
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kServed);
}

// A refusal reaches the refused peer as its reason even when canemud closes the connection at
// once (16 refused peers wait for their answer already): the client reads the answer queued on
// the closed connection instead of reporting a broken pipe or a reset connection.
TEST_F(AccessAsUsers, APeerRefusedAtOnceIsToldWhy) {
  Daemon& d = start(
      "allowed_groups = [\"users\"]\nsocket_mode = 0o666\nsocket_group = \"\"\n"
      "max_clients_per_user = 1\n");
  const std::string socket = d.socket();
  const auto user = [&] {
    auto first = client::Connection::open(socket, "quota");
    if (!first) {
      return 10;
    }
    // Over the quota and silent: refused, each waits for its first request. Accepted before
    // the next connection, which queues behind them.
    std::vector<ipc::UniqueFd> silent;
    for (int k = 0; k < 16; ++k) {
      auto fd = ipc::connect_seqpacket(socket);
      if (!fd) {
        return 20;
      }
      silent.push_back(std::move(*fd));
    }
    auto refused = client::Connection::open(socket, "quota");
    if (refused) {
      return 30;
    }
    std::fprintf(stderr, "refused with: %s\n", refused.error().message.c_str());
    return refused.error().message.find(
               "uid 65534 has 1 connections to canemud; [security] max_clients_per_user "
               "allows 1") != std::string::npos
               ? 0
               : 40;
  };
  EXPECT_EQ(as_user(kNobody, rig.users, {}, user), 0);
}

// The client beyond canemud's 256 is told so, although canemud closes its connection at once.
TEST(Access, TheClientBeyondCanemudsLimitIsToldWhy) {
  Daemon d;
  std::vector<ipc::UniqueFd> held;
  for (int k = 0; k < 256; ++k) {
    auto fd = ipc::connect_seqpacket(d.socket());
    ASSERT_TRUE(fd) << fd.error().message;
    held.push_back(std::move(*fd));
  }
  auto refused = client::Connection::open(d.socket(), "the 257th");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("canemud serves at most 256 clients"), std::string::npos)
      << refused.error().message;
}

// Quotas per user ([security] max_clients_per_user, ring_mib_per_user): a user past its share
// is told which quota and by how much, other users and root keep theirs, and what a user gives
// back is free again.
TEST_F(AccessAsUsers, OneUserHoldsAtMostItsConnectionsAndRingMemory) {
  Daemon& d = start(
      "allowed_groups = [\"users\"]\nsocket_mode = 0o666\nsocket_group = \"\"\n"
      "max_clients_per_user = 3\nring_mib_per_user = 1\n");
  const std::string socket = d.socket();
  // About 700 KiB of rings: one fits in 1 MiB, two do not.
  client::ChannelOptions big;
  big.bus = "can0";
  big.rx_capacity = static_cast<uint32_t>((700u << 10) / sizeof(ipc::ChannelMessage));
  big.tx_capacity = 16;
  const auto user = [&] {
    std::vector<client::Connection> held;
    for (int k = 0; k < 3; ++k) {
      auto c = client::Connection::open(socket, "quota");
      if (!c) {
        return 10 + k;
      }
      held.push_back(std::move(*c));
    }
    auto fourth = client::Connection::open(socket, "quota");
    if (fourth || fourth.error().message.find(
                      "has 3 connections to canemud; [security] max_clients_per_user allows 3") ==
                      std::string::npos) {
      return 20;
    }
    {
      auto first = client::Channel::open(held[0], big);
      if (!first) {
        return 30;
      }
      // The quota is the user's, not the connection's.
      auto second = client::Channel::open(held[1], big);
      if (second || second.error().message.find("[security] ring_mib_per_user allows 1 MiB") ==
                        std::string::npos) {
        return 40;
      }
    }
    // Ring memory given back can be taken again (asked on the connection that closed it, so
    // that canemud has seen the close first), and so can a connection.
    if (!client::Channel::open(held[0], big)) {
      return 50;
    }
    held.pop_back();
    // Answered after canemud has seen the closed connection's hang-up (sent before it).
    (void)testing::status(held[0]);
    if (!client::Connection::open(socket, "quota")) {
      return 60;
    }
    return 0;
  };
  EXPECT_EQ(as_user(kNobody, rig.users, {}, user), 0);
  // Root has no quota: four connections, two big channels.
  std::vector<client::Connection> mine;
  for (int k = 0; k < 4; ++k) {
    auto c = client::Connection::open(socket, "root");
    ASSERT_TRUE(c) << c.error().message;
    mine.push_back(std::move(*c));
  }
  auto a = client::Channel::open(mine[0], big);
  auto b = client::Channel::open(mine[1], big);
  EXPECT_TRUE(a && b);
}

}  // namespace
}  // namespace canemu
