// The channels of a VCI controller and the distributor between them (distributor.hpp): through
// the line as programs see them (opening, activation, reception, overruns, self reception),
// and the Distributor on its own.
#include <gtest/gtest.h>

#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include "adapters/ixxat/line_rig.hpp"
#include "canemu/firmware_model/adapters/ixxat/distributor.hpp"

namespace canemu::model {
namespace {

using namespace testing;  // line_rig.hpp, hosted_station.hpp

// ---------------------------------------------------------------- channels

TEST(VciCanLine, ExclusiveChannelsExcludeEveryOtherChannel) {
  Rig r;
  auto a = r.line.open_channel(false, false);
  auto b = r.line.open_channel(false, true);
  ASSERT_TRUE(a);
  ASSERT_TRUE(b);
  EXPECT_NE(*a, *b);
  auto denied = r.line.open_channel(true, false);
  ASSERT_FALSE(denied);
  EXPECT_EQ(denied.error(), VCI_E_ACCESSDENIED);
  r.line.close_channel(*a);
  r.line.close_channel(*b);
  auto x = r.line.open_channel(true, true);
  ASSERT_TRUE(x);
  EXPECT_EQ(r.line.open_channel(false, false).error(), VCI_E_ACCESSDENIED);
  EXPECT_EQ(r.line.open_channel(true, false).error(), VCI_E_ACCESSDENIED);
  r.line.close_channel(*x);
  EXPECT_TRUE(r.line.open_channel(false, false));
}

TEST(VciCanLine, ChannelCallsCheckHandleInitializationAndActivity) {
  Rig r;
  Port p, q;
  EXPECT_EQ(r.line.init_channel(99, {}, &p), VCI_E_INVALID_HANDLE);
  EXPECT_EQ(r.line.activate(99), VCI_E_INVALID_HANDLE);
  EXPECT_EQ(r.line.deactivate(99), VCI_E_INVALID_HANDLE);
  EXPECT_FALSE(r.line.channel_status(99));
  const ChannelId id = *r.line.open_channel(false, true);
  const auto fresh = r.line.channel_status(id);
  ASSERT_TRUE(fresh);
  EXPECT_FALSE(fresh->initialized);
  EXPECT_FALSE(fresh->activated);
  EXPECT_EQ(r.line.activate(id), VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(r.line.init_channel(id, {0, CAN_FILTER_VOID}, &p), VCI_E_INVALIDARG);
  EXPECT_EQ(r.line.init_channel(id, {0, CAN_FILTER_PASS | CAN_FILTER_SRRA}, &p), VCI_OK);
  ASSERT_EQ(r.line.activate(id), VCI_OK);
  EXPECT_TRUE(r.line.channel_status(id)->activated);
  EXPECT_EQ(r.line.init_channel(id, {}, &q), VCI_E_INVALID_STATE);
  ASSERT_EQ(r.line.deactivate(id), VCI_OK);
  EXPECT_EQ(r.line.init_channel(id, {}, &q), VCI_OK);
  EXPECT_FALSE(r.line.channel_status(id)->activated);
}

TEST(VciCanLine, AnActiveChannelReceivesNothingWhileTheLineIsNotOnline) {
  Rig r;
  Port p;
  r.init();
  r.channel(p);
  r.peer.start();
  r.peer.send(k123);
  r.b.run_until(1 * kMs);
  EXPECT_TRUE(p.rx.empty());
}

TEST(VciCanLine, ADeactivatedChannelNeitherReceivesNorTransmits) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.line.deactivate(ch), VCI_OK);
  r.send(p, msg(0x201));
  r.peer.send(k123);
  r.b.run_until(2 * kMs);
  EXPECT_EQ(p.rx.size(), 1u);  // the INFO START from before
  EXPECT_EQ(p.tx.size(), 1u);
  ASSERT_EQ(r.peer.log.sent.size(), 1u);
  EXPECT_TRUE(r.peer.log.received.empty());
  ASSERT_EQ(r.line.activate(ch), VCI_OK);  // the transmit FIFO is served again
  r.b.run_until(3 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].at, 2 * kMs + bits_of(classic(0x201)) * kBit);
}

TEST(VciCanLine, ADelayedFrameOfAChannelDeactivatedMeanwhileIsNotSent) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  CANMSG2 delayed = msg(0x124);
  delayed.dwTime = 5000;
  r.send(p, msg(0x123));
  r.send(p, delayed);
  r.b.run_until(1 * kMs);  // 0x124 waits in the firmware for its delay
  EXPECT_TRUE(p.tx.empty());
  ASSERT_EQ(r.line.deactivate(ch), VCI_OK);
  r.b.run_until(10 * kMs);
  ASSERT_EQ(r.line.activate(ch), VCI_OK);
  r.b.run_until(20 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_EQ(r.counters(ch).dropped, 1u);
}

TEST(VciCanLine, TwoChannelsBothReceiveEveryFrame) {
  Rig r;
  Port a, b;
  const std::vector<ChannelId> ch = r.online({{a}, {b, true}});
  r.peer.send(k123);
  r.peer.send(kZero);
  r.b.run_until(1 * kMs);
  for (Port* port : {&a, &b}) {
    ASSERT_EQ(port->data().size(), 2u);
    EXPECT_EQ(port->data()[0].dwTime, 124u);
    EXPECT_EQ(port->data()[1].dwTime, 230u);  // (62 + 3 + 50) bits at 2 us
  }
  EXPECT_EQ(r.counters(ch[0]).received, 3u);  // INFO START and two frames
  EXPECT_EQ(r.counters(ch[1]).received, 3u);
}

TEST(VciCanLine, AReceivedFrameCarriesItsEndOfFrameInTicksAndItsContent) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  r.peer.send(k123);
  r.b.run_until(10 * kMs);
  r.peer.send(classic(0x1ABCDEF, {1, 2, 3, 4, 5, 6, 7, 8}, true));
  r.peer.send(remote(0x7FF));
  r.b.run_until(20 * kMs);
  const auto d = p.data();
  ASSERT_EQ(d.size(), 3u);
  EXPECT_EQ(d[0].dwTime, 124u);  // 62 bits at 2 us, sent at once from t = 0
  EXPECT_EQ(d[0].dwMsgId, 0x123u);
  EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, 2, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d[0].abData[0], 0x11);
  EXPECT_EQ(d[0].abData[1], 0x22);
  const int64_t ext_bits = bits_of(classic(0x1ABCDEF, {1, 2, 3, 4, 5, 6, 7, 8}, true));
  EXPECT_EQ(d[1].dwTime, static_cast<uint32_t>((10 * kMs + ext_bits * kBit) / kUs));
  EXPECT_EQ(d[1].dwMsgId, 0x1ABCDEFu);
  EXPECT_EQ(info(d[1]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_EXT | 8, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(d[1].abData[7], 8);
  const int64_t rtr_end = 10 * kMs + (ext_bits + 3 + bits_of(remote(0x7FF))) * kBit;
  EXPECT_EQ(d[2].dwTime, static_cast<uint32_t>(rtr_end / kUs));
  EXPECT_EQ(d[2].dwMsgId, 0x7FFu);
  EXPECT_EQ(info(d[2]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_RTR, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(r.counters(ch).received, 4u);  // INFO START and the three frames
}

TEST(VciCanLine, TimeStampsCountFromTheEpochAtTheClockRate) {
  ixxat::Clocks clocks;
  clocks.clock_hz = 8'000'000;
  clocks.tsc_divisor = 4;  // 2 MHz: 0.5 us per tick
  testing::BusFixture b;
  Sja1000Node node(b.sched, b.bus);
  ixxat::CanLine line(b.sched, node, clocks, SimTime::from_ns(-3 * kMs));  // powered on at -3 ms
  Peer peer(b);
  Port p;
  ASSERT_EQ(line.open_control(), VCI_OK);
  ASSERT_EQ(line.init_line(v1_init()), VCI_OK);
  const ChannelId ch = *line.open_channel(false, false);
  ASSERT_EQ(line.init_channel(ch, {}, &p), VCI_OK);
  ASSERT_EQ(line.activate(ch), VCI_OK);
  ASSERT_EQ(line.start_line(), VCI_OK);
  peer.start();
  peer.send(k123);
  b.run_until(1 * kMs);
  ASSERT_EQ(p.rx.size(), 2u);
  EXPECT_EQ(p.rx[0].dwTime, 6000u);                                 // 3 ms at 2 MHz
  EXPECT_EQ(p.rx[1].dwTime, 6000u + 248u);                          // + 124 us
  EXPECT_EQ(line.ticks(SimTime::from_ns(1 * kMs + 1'499)), 8002u);  // whole ticks only
}

TEST(VciCanLine, ARxFifoOverflowDropsTheNewestAndMarksTheNextStoredMessage) {
  Rig r;
  Port p(2);
  const ChannelId ch = r.online(p);
  r.peer.send(classic(0x101));
  r.peer.send(classic(0x102));
  r.peer.send(classic(0x103));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(p.rx.size(), 2u);  // INFO START and 0x101
  EXPECT_EQ(p.rx[1].dwMsgId, 0x101u);
  EXPECT_EQ(p.rx[1].uMsgInfo.Bits.ovr, 0u);
  auto s = *r.line.channel_status(ch);
  EXPECT_TRUE(s.rx_overrun);
  EXPECT_EQ(s.counters.received, 2u);
  EXPECT_EQ(s.counters.lost, 2u);
  p.rx.clear();  // the application reads
  r.peer.send(classic(0x104));
  r.peer.send(classic(0x105));
  r.b.run_until(2 * kMs);
  ASSERT_EQ(p.rx.size(), 2u);
  EXPECT_EQ(p.rx[0].dwMsgId, 0x104u);
  EXPECT_EQ(info(p.rx[0]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_OVR | 2, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(p.rx[1].uMsgInfo.Bits.ovr, 0u);
  EXPECT_TRUE(r.line.channel_status(ch)->rx_overrun);  // sticky
  ASSERT_EQ(r.line.deactivate(ch), VCI_OK);
  ASSERT_EQ(r.line.init_channel(ch, {}, &p), VCI_OK);
  s = *r.line.channel_status(ch);
  EXPECT_FALSE(s.rx_overrun);
  EXPECT_EQ(s.counters.lost, 0u);
  EXPECT_EQ(s.counters.received, 0u);
}

TEST(VciCanLine, FramesOfAFormatTheLineWasNotInitializedForAreNeitherReceivedNorSent) {
  Rig r;
  Port p;
  r.init(CAN_OPMODE_STANDARD);
  const ChannelId ch = r.channel(p);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.peer.send(classic(0x100, {1}, true));
  r.peer.send(classic(0x101, {1}));
  r.send(p, msg(0x200, {1}, true));
  r.send(p, msg(0x201, {1}));
  r.b.run_until(1 * kMs);
  EXPECT_EQ(p.data_ids(), std::vector<uint32_t>{0x101});
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame.id(), 0x201u);
  EXPECT_FALSE(r.peer.log.received[0].frame.extended());
  EXPECT_EQ(r.counters(ch).rejected, 1u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
  EXPECT_TRUE(p.tx.empty());
}

TEST(VciCanLine, TransmitMessagesThatAreNotDataAreDroppedAndCounted) {
  Rig r;
  Port p;
  const ChannelId ch = r.online(p);
  CANMSG2 bad = msg(0x100);
  bad.uMsgInfo.Bits.type = CAN_MSGTYPE_INFO;
  CANMSG2 fd = msg(0x101);  // no CAN FD on an SJA1000
  fd.uMsgInfo.Bits.edl = 1;
  r.send(p, bad);
  r.send(p, fd);
  r.send(p, msg(0x123));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_EQ(r.peer.log.received[0].frame, k123);
  EXPECT_EQ(r.peer.log.received[0].at, 62 * kBit);
  EXPECT_EQ(r.counters(ch).rejected, 2u);
  EXPECT_EQ(r.counters(ch).sent, 1u);
}

// ---------------------------------------------------------------- self reception

TEST(VciCanLine, V1ChannelsReceiveEveryEchoWithSrrSet) {
  Rig r;
  Port a, b;
  r.online({{a}, {b}});
  r.send(a, with_srr(msg(0x123)));
  r.b.run_until(1 * kMs);
  for (Port* port : {&a, &b}) {
    const auto d = port->data();
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].dwTime, 124u);  // the end of the frame's transmission
    EXPECT_EQ(d[0].dwMsgId, 0x123u);
    EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_SRR | 2, CAN_ACCEPT_ALWAYS}));
    EXPECT_EQ(d[0].abData[1], 0x22);
  }
  EXPECT_EQ(r.peer.log.received.size(), 1u);
}

TEST(VciCanLine, AV2ChannelGetsItsOwnEchoEvenWithLockButNotOthersWithoutSrra) {
  Rig r;
  Port x, y;
  r.online({{x, true, {0, CAN_FILTER_LOCK}}, {y, true, {0, CAN_FILTER_PASS}}});
  r.send(x, with_srr(msg(0x123)));
  r.send(y, msg(0x124));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(x.data().size(), 1u);
  EXPECT_EQ(x.data()[0].dwTime, 124u);
  EXPECT_EQ(info(x.data()[0]),
            (Info{CAN_MSGTYPE_DATA, 0, CAN_MSGFLAGS_SRR | 2, CAN_ACCEPT_ALWAYS}));
  EXPECT_TRUE(y.data().empty());
  EXPECT_EQ(r.peer.log.received.size(), 2u);
}

TEST(VciCanLine, AV2ChannelWithSrraGetsOthersEchoesThroughItsFilterWithSrrCleared) {
  Rig r;
  Port x, y;
  r.init();
  r.channel(x);
  const ChannelId cy = r.channel(y, true, {0, CAN_FILTER_INCL | CAN_FILTER_SRRA});
  ASSERT_EQ(r.line.deactivate(cy), VCI_OK);
  ASSERT_EQ(
      r.line.filter(cy, acceptance(CAN_FILTER_STD, ixxat::filter_value(0x123, false), kStdMask)).hr,
      VCI_OK);
  ASSERT_EQ(r.line.activate(cy), VCI_OK);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.send(x, with_srr(msg(0x123)));
  r.send(x, with_srr(msg(0x124)));
  r.b.run_until(1 * kMs);
  const auto d = y.data();
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].dwMsgId, 0x123u);
  EXPECT_EQ(d[0].dwTime, 124u);
  EXPECT_EQ(info(d[0]), (Info{CAN_MSGTYPE_DATA, 0, 2, CAN_ACCEPT_FILTER_1}));
  EXPECT_EQ(x.data().size(), 2u);
}

TEST(VciCanLine, AFrameSentWithoutSrrIsInvisibleToEveryChannel) {
  Rig r;
  Port a, b, c;
  r.online({{a}, {b}, {c, true, {0, CAN_FILTER_PASS | CAN_FILTER_SRRA}}});
  r.send(a, msg(0x123));
  r.b.run_until(1 * kMs);
  ASSERT_EQ(r.peer.log.received.size(), 1u);
  EXPECT_TRUE(a.data().empty());
  EXPECT_TRUE(b.data().empty());
  EXPECT_TRUE(c.data().empty());
}

TEST(VciCanLine, EchoesBypassTheControlUnitFilter) {
  Rig r;
  Port a, b;
  r.init();
  ASSERT_EQ(
      r.line.filter(std::nullopt, acceptance(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE))
          .hr,
      VCI_OK);
  r.channel(a);
  r.channel(b);
  ASSERT_EQ(r.line.start_line(), VCI_OK);
  r.peer.start();
  r.send(a, with_srr(msg(0x123)));
  r.peer.send(classic(0x456));
  r.b.run_until(1 * kMs);
  EXPECT_EQ(a.data_ids(), std::vector<uint32_t>{0x123});
  EXPECT_EQ(b.data_ids(), std::vector<uint32_t>{0x123});
}

// ---------------------------------------------------------------- the distributor on its own

// A channel opened, initialized with `port` and activated.
ChannelId active_channel(ixxat::Distributor& d, Port& port, bool v2,
                         ixxat::ChannelSetup setup = {}) {
  const ChannelId id = *d.open(false, v2);
  EXPECT_EQ(d.init(id, setup, &port), VCI_OK);
  EXPECT_EQ(d.activate(id), VCI_OK);
  return id;
}

CANMSG2 hpm(CANMSG2 m) {
  m.uMsgInfo.Bits.hpm = 1;
  return m;
}

// The next message the line may send by `sendable`, with its channel: take_converted with a
// yes/no test.
template <class Sendable>
std::optional<std::pair<CANMSG2, ChannelId>> take(ixxat::Distributor& d, Sendable sendable) {
  auto m = d.take_converted([&](const CANMSG2& msg) -> std::optional<bool> {
    return sendable(msg) ? std::optional<bool>(true) : std::nullopt;
  });
  if (!m) {
    return std::nullopt;
  }
  return std::make_pair(m->msg, m->channel);
}

TEST(Distributor, AnExclusiveChannelIsAloneAndTheLastCloseEndsIt) {
  ixxat::Distributor d;
  const ChannelId a = *d.open(false, false);
  EXPECT_EQ(d.open(true, false).error(), VCI_E_ACCESSDENIED);
  d.close(a);
  EXPECT_TRUE(d.empty());
  const ChannelId x = *d.open(true, true);
  EXPECT_NE(x, a);  // identifiers are not reused
  EXPECT_EQ(d.open(false, false).error(), VCI_E_ACCESSDENIED);
  d.close(x);
  EXPECT_TRUE(d.open(false, false).has_value());
}

TEST(Distributor, FilterCallsNeedAnInitializedV2Channel) {
  ixxat::Distributor d;
  EXPECT_EQ(d.filters(99).error(), VCI_E_INVALID_HANDLE);
  const ChannelId v1 = *d.open(false, false);
  EXPECT_EQ(d.filters(v1).error(), VCI_E_NOT_IMPLEMENTED);
  const ChannelId v2 = *d.open(false, true);
  EXPECT_EQ(d.filters(v2).error(), VCI_E_NOT_INITIALIZED);
  Port port;
  ASSERT_EQ(d.init(v2, {0, CAN_FILTER_EXCL}, &port), VCI_OK);
  auto f = d.filters(v2);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->first->std.mode(), CAN_FILTER_EXCL);
  EXPECT_FALSE(f->second);  // not active
  ASSERT_EQ(d.activate(v2), VCI_OK);
  EXPECT_TRUE(d.filters(v2)->second);
  EXPECT_EQ(d.init(v2, {}, &port), VCI_E_INVALID_STATE);  // only while inactive
  EXPECT_EQ(d.activate(v1), VCI_E_NOT_INITIALIZED);
}

TEST(Distributor, AFullReceiveFifoLosesMessagesAndMarksTheNextStoredOne) {
  ixxat::Distributor d;
  Port small(1);
  const ChannelId id = active_channel(d, small, false);
  for (uint32_t k = 0; k < 3; ++k) {
    d.broadcast(msg(k));
  }
  small.rx.clear();
  d.broadcast(msg(7));
  ASSERT_EQ(small.rx.size(), 1u);
  EXPECT_EQ(small.rx[0].dwMsgId, 7u);
  EXPECT_EQ(small.rx[0].uMsgInfo.Bits.ovr, 1u);
  const ixxat::ChannelStatus st = *d.status(id);
  EXPECT_TRUE(st.rx_overrun);
  EXPECT_EQ(st.counters.received, 2u);
  EXPECT_EQ(st.counters.lost, 2u);
}

TEST(Distributor, AV2ChannelFilterSelectsReceivedFramesAndSetsAfc) {
  ixxat::Distributor d;
  Port v1, pass, incl;
  active_channel(d, v1, false);
  active_channel(d, pass, true, {0, CAN_FILTER_PASS});
  const ChannelId inc = *d.open(false, true);
  ASSERT_EQ(d.init(inc, {0, CAN_FILTER_INCL}, &incl), VCI_OK);
  auto f = d.filters(inc);
  f->first->std.set_acceptance(CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE);  // the ID list alone
  ASSERT_EQ(f->first->std.add_ids(ixxat::filter_value(0x100, false), 0xFFF), VCI_OK);
  ASSERT_EQ(d.activate(inc), VCI_OK);
  CANMSG2 m = msg(0x100);
  m.uMsgInfo.Bits.afc = CAN_ACCEPT_ALWAYS;
  d.distribute(testing::frame(0x100, {0x11, 0x22}), m);
  CANMSG2 other = msg(0x200);
  other.uMsgInfo.Bits.afc = CAN_ACCEPT_ALWAYS;
  d.distribute(testing::frame(0x200, {0x11, 0x22}), other);
  EXPECT_EQ(v1.data_ids(), (std::vector<uint32_t>{0x100, 0x200}));
  EXPECT_EQ(pass.data_ids(), (std::vector<uint32_t>{0x100, 0x200}));
  EXPECT_EQ(pass.rx[0].uMsgInfo.Bits.afc, CAN_ACCEPT_ALWAYS);  // PASS leaves it
  ASSERT_EQ(incl.data_ids(), (std::vector<uint32_t>{0x100}));
  EXPECT_EQ(incl.rx[0].uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_2);  // found in the ID list
}

TEST(Distributor, V1ChannelsGetCanFdFramesOnlyUpToEightBytes) {
  ixxat::Distributor d;
  Port v1, v2;
  const ChannelId a = active_channel(d, v1, false);
  active_channel(d, v2, true, {0, CAN_FILTER_PASS});
  const std::vector<uint8_t> data(12, 0xAB);
  const Frame f = *Frame::fd_frame(0x10, data);
  CANMSG2 m = msg(0x10);
  m.uMsgInfo.Bits.edl = 1;
  m.uMsgInfo.Bits.dlc = 9;  // 12 bytes
  d.distribute(f, m);
  EXPECT_TRUE(v1.rx.empty());
  EXPECT_EQ(d.status(a)->counters.not_shown, 1u);
  EXPECT_EQ(v2.rx.size(), 1u);
}

TEST(Distributor, EchoesFollowTheV1AndV2RulesAndTheListsFramesKeepSrr) {
  ixxat::Distributor d;
  Port v1, sender, other, srra;
  active_channel(d, v1, false);
  const ChannelId from = active_channel(d, sender, true, {0, CAN_FILTER_PASS});
  active_channel(d, other, true, {0, CAN_FILTER_PASS});
  active_channel(d, srra, true, {0, CAN_FILTER_PASS | CAN_FILTER_SRRA});
  const Frame f = testing::frame(0x123, {0x11, 0x22});
  const CANMSG2 echo = with_srr(msg(0x123));
  d.echo(f, echo, from);
  ASSERT_EQ(v1.rx.size(), 1u);
  EXPECT_EQ(v1.rx[0].uMsgInfo.Bits.srr, 1u);
  ASSERT_EQ(sender.rx.size(), 1u);
  EXPECT_EQ(sender.rx[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_TRUE(other.rx.empty());
  ASSERT_EQ(srra.rx.size(), 1u);
  EXPECT_EQ(srra.rx[0].uMsgInfo.Bits.srr, 0u);  // as if from another controller
  d.echo(f, echo, std::nullopt);                // the cyclic list's frame
  ASSERT_EQ(srra.rx.size(), 2u);
  EXPECT_EQ(srra.rx[1].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(sender.rx.size(), 1u);  // no channel's own
}

TEST(Distributor, TakeServesHighPriorityFirstThenTheChannelsInTurn) {
  ixxat::Distributor d;
  Port a, b;
  const ChannelId ca = active_channel(d, a, false);
  const ChannelId cb = active_channel(d, b, false);
  a.tx = {msg(0x1), msg(0x2)};
  b.tx = {hpm(msg(0x3)), msg(0x4)};
  const auto any = [](const CANMSG2&) { return true; };
  std::vector<std::pair<uint32_t, ChannelId>> order;
  while (auto m = take(d, any)) {
    order.emplace_back(m->first.dwMsgId, m->second);
  }
  // 0x3 first (high priority), then turns starting after b: a, b, a.
  EXPECT_EQ(order, (std::vector<std::pair<uint32_t, ChannelId>>{
                       {0x3, cb}, {0x1, ca}, {0x4, cb}, {0x2, ca}}));
}

TEST(Distributor, TakeDropsAndCountsWhatTheLineCannotSend) {
  ixxat::Distributor d;
  Port a;
  const ChannelId id = active_channel(d, a, false);
  a.tx = {msg(0x1), msg(0x2), msg(0x3)};
  const auto not_two = [](const CANMSG2& m) { return m.dwMsgId != 0x2; };
  EXPECT_EQ(take(d, not_two)->first.dwMsgId, 0x1u);
  EXPECT_EQ(take(d, not_two)->first.dwMsgId, 0x3u);
  EXPECT_FALSE(take(d, not_two).has_value());
  d.count_sent(id);
  d.count_dropped(id);
  d.count_sent(99);  // a closed channel: nothing to count
  const ixxat::ChannelCounters c = d.status(id)->counters;
  EXPECT_EQ(c.rejected, 1u);
  EXPECT_EQ(c.sent, 1u);
  EXPECT_EQ(c.dropped, 1u);
  ASSERT_EQ(d.deactivate(id), VCI_OK);
  a.tx = {msg(0x5)};
  EXPECT_FALSE(take(d, not_two).has_value());  // inactive channels send nothing
}

// A FIFO full of messages the line refuses does not hold the firmware: after kRejectBudget of
// them in one call the port is deferred and the other channels get their turn.
TEST(Distributor, AFloodOfRefusedMessagesIsTakenInSharesAndTheOthersGoOn) {
  ixxat::Distributor d;
  Port junk;
  Port good;
  active_channel(d, junk, false);
  active_channel(d, good, false);
  const uint32_t budget = ixxat::Distributor::kRejectBudget;
  for (uint32_t i = 0; i < 3 * budget; ++i) {
    junk.tx.push_back(msg(0x2));
  }
  junk.tx.push_back(msg(0x7));
  good.tx = {msg(0x5)};
  const auto not_two = [](const CANMSG2& m) { return m.dwMsgId != 0x2; };
  auto first = take(d, not_two);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->first.dwMsgId, 0x5u);  // the good channel's frame, not held up
  EXPECT_EQ(junk.deferred, 1);
  EXPECT_EQ(junk.tx.size(), 2 * budget + 1);
  // Each later call takes another share, until the junk is gone and its frame comes.
  EXPECT_FALSE(take(d, not_two).has_value());
  EXPECT_FALSE(take(d, not_two).has_value());
  EXPECT_EQ(junk.deferred, 3);
  auto last = take(d, not_two);
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->first.dwMsgId, 0x7u);
  EXPECT_EQ(junk.deferred, 3);
}

}  // namespace
}  // namespace canemu::model
