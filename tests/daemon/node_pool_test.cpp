// The pool of nodes for ephemeral devices: the controller the bus needs, reused once stopped,
// never taken from the bus.
#include "canemu/daemon/world/node_pool.hpp"

#include <gtest/gtest.h>

namespace canemu::daemon {
namespace {

using namespace canemu::model;

struct Buses {
  SimScheduler scheduler;
  CanBus classic{scheduler, "can0"};
  CanBus fd{scheduler, "canfd0"};
  NodePool pool{scheduler};
  Buses() {
    pool.add_bus(classic, false);
    pool.add_bus(fd, true);
  }
};

HostedNodeSettings at_500k() {
  HostedNodeSettings s;
  s.btr0 = 0x00;
  s.btr1 = 0x1C;
  return s;
}

TEST(NodePool, AClassicBusGetsAnSja1000AndACanFdBusTheCanFdController) {
  Buses b;
  EXPECT_EQ(b.pool.bus_count(), 2u);
  EXPECT_FALSE(b.pool.spare(0).fd_capable());
  EXPECT_TRUE(b.pool.spare(1).fd_capable());
  EXPECT_EQ(b.pool.node_count(0), 1u);
  EXPECT_EQ(b.pool.node_count(1), 1u);
}

TEST(NodePool, AStoppedNodeIsHandedOutAgainAndAStartedOneIsNot) {
  Buses b;
  HostedNode& first = b.pool.spare(0);
  EXPECT_EQ(&b.pool.spare(0), &first);  // not started: still spare
  first.start(at_500k(), nullptr, [] { return std::optional<TxFrame>{}; });
  HostedNode& second = b.pool.spare(0);
  EXPECT_NE(&second, &first);
  EXPECT_NE(second.node(), first.node());
  EXPECT_EQ(b.pool.node_count(0), 2u);
  first.stop();
  EXPECT_EQ(&b.pool.spare(0), &first);  // the first reusable node, in order of making
  EXPECT_EQ(b.pool.node_count(0), 2u);
}

TEST(NodePool, ANodeAFirmwareClaimsIsNotSpare) {
  Buses b;
  HostedNode& node = b.pool.spare(0);
  node.claim(true);
  EXPECT_NE(&b.pool.spare(0), &node);
  node.claim(false);
  EXPECT_EQ(&b.pool.spare(0), &node);
}

}  // namespace
}  // namespace canemu::daemon
