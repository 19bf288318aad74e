// The CAN FD controller with its host driver: FD frames with the rate switch between nodes,
// bus-off left by the driver's restart, reuse with cleared counters.
#include "canemu/firmware_model/chips/can_fd/can_fd_node.hpp"

#include <gtest/gtest.h>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "hosted_station.hpp"

namespace canemu::model {
namespace {

using Bus = testing::BusFixture;

// Ten quanta per bit, sample point at 80 %: 500 kbit/s nominal, 2 Mbit/s data.
const BitTiming kNominal{5'000'000, 1, 7, 2, 1, 1};
const BitTiming kData{20'000'000, 1, 7, 2, 1, 1};
constexpr int64_t kBit = 2000;

// A CAN FD node with its own queue and log.
struct Station : testing::Station<CanFdNode> {
  using testing::Station<CanFdNode>::Station;
  void start(int64_t restart_ns = 0) {
    HostedNodeSettings s;
    s.nominal = kNominal;
    s.data = kData;
    s.restart_delay = SimDuration(restart_ns);
    testing::Station<CanFdNode>::start(s);
  }
};

Frame fd_frame(uint32_t id, std::size_t length, bool brs) {
  std::vector<uint8_t> data(length);
  for (std::size_t k = 0; k < length; ++k) {
    data[k] = static_cast<uint8_t>(k * 7);
  }
  return *Frame::fd_frame(id, data, false, brs);
}

TEST(CanFdNode, SendsFdFramesWithTheRateSwitchOneAfterTheOther) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  const Frame big = fd_frame(0x100, 64, true);
  const Frame small = fd_frame(0x101, 12, false);
  a.queue = {TxFrame{big, false, false}, TxFrame{small, false, false}};
  a.node.kick();
  EXPECT_TRUE(a.node.transmitting());
  EXPECT_EQ(a.node.chip().tx_queued(), 1u);  // one at a time: the rest waits in the owner's queue
  b.run_until(10'000'000);
  const int64_t first = frame_duration(encode(big), kNominal, kData).ns();
  const int64_t gap = 3 * kBit;  // intermission
  const int64_t second = first + gap + frame_duration(encode(small), kNominal, kData).ns();
  ASSERT_EQ(r.log.received.size(), 2u);
  EXPECT_EQ(r.log.received[0].at, first);
  EXPECT_EQ(r.log.received[0].frame, big);
  EXPECT_EQ(r.log.received[1].at, second);
  EXPECT_EQ(r.log.received[1].frame, small);
  ASSERT_EQ(a.log.sent.size(), 2u);
  EXPECT_EQ(a.log.sent[0].at, first);
  EXPECT_EQ(a.log.sent[1].at, second);
  EXPECT_EQ(r.node.chip().rx_queued(), 0u);  // taken out at once
}

TEST(CanFdNode, LeavesBusOffOnlyWhenTheDriverRestartsIt) {
  Bus b;
  Station a(b), r(b);
  a.start(1'000'000);  // restart 1 ms after bus-off
  r.start();
  b.run_until(100 * kBit);
  a.node.controller().confinement().set_counters(256, 0);
  b.bus.counters_changed(a.node.node());
  ASSERT_NO_FATAL_FAILURE(testing::expect_bus_off_until_recovery(b, a.log, 100 * kBit, 1'000'000));
}

TEST(CanFdNode, AReusedNodeStartsWithClearedCounters) {
  Bus b;
  Station a(b), r(b);
  a.start();
  r.start();
  a.node.controller().confinement().set_counters(200, 17);
  b.bus.counters_changed(a.node.node());
  a.node.stop();
  EXPECT_TRUE(a.node.reusable());
  a.start();
  EXPECT_EQ(a.node.controller().confinement().tec(), 0);
  EXPECT_EQ(a.node.controller().confinement().rec(), 0);
  EXPECT_EQ(a.node.controller().confinement().state(), ErrorState::active);
  a.queue.push_back(TxFrame{fd_frame(0x5, 8, true), false, false});
  a.node.kick();
  b.run_until(1'000'000);
  EXPECT_EQ(r.log.received.size(), 1u);
}

// The FD controller withdraws a babbled copy without telling its driver: the node notices by
// itself and lets its own traffic go.
TEST(CanFdNode, ALoneBabblersLastCopyIsWithdrawnAndItsOwnFrameFollows) {
  Bus b;
  Station a(b);
  a.start();
  ASSERT_TRUE(a.node.babble(fd_frame(0x10, 8, true), SimTime::from_ns(3'000'000)));
  a.send(fd_frame(0x20, 4, false));
  b.run_until(2'900'000);
  EXPECT_EQ(a.node.controller().confinement().tec(), 128);
  b.run_until(3'100'000);
  // The copy on the wire at 3 ms (if any) completes; then the node's own frame is loaded.
  b.run_until(4'000'000);
  EXPECT_TRUE(a.node.transmitting());
  EXPECT_FALSE(a.node.babbling());
  EXPECT_TRUE(a.log.dropped.empty());
  EXPECT_TRUE(a.queue.empty());  // its frame left the queue for the controller
}

}  // namespace
}  // namespace canemu::model
