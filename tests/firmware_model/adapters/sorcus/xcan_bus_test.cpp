// The X-CAN-2i MDD's bus-control device and error handling (digest §3.1.1, §4; checklist §6
// items 74, 77, 81, 84, 90-99): bit timing, bus on by default, INFO_DEVICE, the error callback
// at WARN and bus-off under a bit-rate mismatch, recovery by CMD_STOP then CMD_START, the
// low-speed transceiver's line error, and an exchange with an SJA1000 node both ways.
#include <gtest/gtest.h>

#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"
#include "xcan_fixture.hpp"

namespace canemu::model::sorcus {
namespace {

using namespace testing;  // xcan_fixture.hpp

XCAN_BITPARAMS read_params(Xcan& x, ChannelHandle h) {
  const Reply r = x.m.read_block(h);
  EXPECT_EQ(r.data.size(), sizeof(XCAN_BITPARAMS));
  XCAN_BITPARAMS p{};
  std::memcpy(&p, r.data.data(), std::min(r.data.size(), sizeof p));
  return p;
}

bool same(const XCAN_BITPARAMS& a, const XCAN_BITPARAMS& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

TEST(XcanBus, BitParamsStartAtTheFactoryTwentyKbitAndReadBackAsWritten) {
  Xcan x;
  CPS_XCAN c = Xcan::cps(DEVICE_CTRL, 0);
  c.usIndexFirst = c.usIndexLast = XCAN_BUS_CTRL_INDEX;
  const ChannelHandle h = x.open(c);
  EXPECT_TRUE(same(read_params(x, h), XCAN_BITPARAMS XCAN_DEFAULT_BITPARAMS));
  EXPECT_EQ(x.m.chip(0).read(i82527::BIT_TIMING0), 0x53);  // 2500 ns, SJW 2
  EXPECT_EQ(x.m.chip(0).read(i82527::BIT_TIMING1), 0x2F);  // 16, 3
  XCAN_BITPARAMS p{1000, 16, 3, 2, 3, 1, 11};              // 50 kbit/s, 3 samples, 110 ohm
  EXPECT_EQ(x.m.write_block(h, bytes(p)).error, uint32_t{ERR_OK});
  EXPECT_TRUE(same(read_params(x, h), p));
  EXPECT_EQ(x.m.chip(0).read(i82527::BIT_TIMING0), 0x47);
  EXPECT_EQ(x.m.chip(0).read(i82527::BIT_TIMING1), 0xAF);
  EXPECT_EQ(x.m.write_block(h, bytes(params_500k())).error, uint32_t{ERR_OK});
  EXPECT_EQ(x.m.chip(0).read(i82527::BIT_TIMING0), 0x00);
  EXPECT_EQ(x.m.chip(0).read(i82527::BIT_TIMING1), 0x1C);
}

TEST(XcanBus, BitParamsOutOfRangeAreRefusedAndTheOldOnesKept) {
  Xcan x;
  const ChannelHandle h = x.bus_control();
  for (const XCAN_BITPARAMS& p : {XCAN_BITPARAMS{100, 13, 2, 1, 1, 0, 11},     // Tq < 125
                                  XCAN_BITPARAMS{130, 13, 2, 1, 1, 0, 11},     // not 125 x n
                                  XCAN_BITPARAMS{125, 4, 2, 1, 1, 0, 11},      // 4 + 2 < 7
                                  XCAN_BITPARAMS{125, 13, 2, 3, 1, 0, 11},     // Tseg2 < Tsjw
                                  XCAN_BITPARAMS{125, 13, 2, 1, 2, 0, 11},     // SpB 2
                                  XCAN_BITPARAMS{125, 13, 2, 1, 1, 2, 11},     // Rbus 2
                                  XCAN_BITPARAMS{125, 13, 2, 1, 1, 0, 12}}) {  // MsgFormat
    EXPECT_EQ(x.m.write_block(h, bytes(p)).error, uint32_t{ERR_XCAN_PARAM});
  }
  EXPECT_EQ(x.m.write_block(h, Bytes{1, 2}).error, uint32_t{ERR_XCAN_DATA_SIZE});
  EXPECT_TRUE(same(read_params(x, h), params_500k()));
  x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100));
  XCAN_BITPARAMS p = params_500k();
  p.MsgFormat = 29;  // not under existing 11-bit objects
  EXPECT_EQ(x.m.write_block(h, bytes(p)).error, uint32_t{ERR_XCAN_PARAM});
}

TEST(XcanBus, ALowSpeedInterfaceRefusesMoreThan125Kbit) {
  Xcan x(XcanVariant::m);
  EXPECT_FALSE(x.m.low_speed(0));
  EXPECT_TRUE(x.m.low_speed(1));
  CPS_XCAN c = Xcan::cps(DEVICE_CTRL, 0, 0, 0, 1);
  c.usIndexFirst = c.usIndexLast = XCAN_BUS_CTRL_INDEX;
  const ChannelHandle h = x.open(c);
  EXPECT_EQ(x.m.write_block(h, bytes(params_500k())).error, uint32_t{ERR_XCAN_PARAM});
  EXPECT_EQ(x.m.write_block(h, bytes(XCAN_BITPARAMS{500, 13, 2, 1, 1, 1, 11})).error,
            uint32_t{ERR_OK});
}

TEST(XcanBus, TheBusIsOnOnceTheFirstObjectChannelOpensUnlessStopped) {
  Xcan x;
  const ChannelHandle h = x.bus_control();
  EXPECT_EQ(x.m.info(h, INFO_DEVICE).value(), XCAN_STATUS(0, 0));
  x.filter();  // the filter channel is no object channel
  EXPECT_EQ(x.m.info(h, INFO_DEVICE).value(), XCAN_STATUS(0, 0));
  x.open(Xcan::cps(DEVICE_BUS_IN, 0x100));
  EXPECT_EQ(x.m.info(h, INFO_DEVICE).value(), XCAN_STATUS(XCAN_BUS_ON, 0));

  const ChannelHandle h1 = x.bus_control(1);
  EXPECT_EQ(x.m.control(h1, CMD_STOP), uint32_t{ERR_OK});
  const ChannelHandle out = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100, 0, 0, 1));
  EXPECT_EQ(x.m.info(h1, INFO_DEVICE).value(), XCAN_STATUS(0, 0));
  EXPECT_EQ(x.m.control(h1, CMD_START), uint32_t{ERR_OK});
  EXPECT_EQ(x.m.info(h1, INFO_DEVICE).value(), XCAN_STATUS(XCAN_BUS_ON, 0));
  EXPECT_EQ(x.m.info(out, INFO_XCAN_MSG_COUNT).value(), 0u);
}

TEST(XcanBus, ClosingTheLastChannelReturnsTheInterfaceToItsInitialState) {
  Xcan x;
  const ChannelHandle h = x.bus_control();
  const ChannelHandle o = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100));
  EXPECT_EQ(x.m.close_channel(o), uint32_t{ERR_OK});
  EXPECT_EQ(x.m.object_count(0), 1u);  // the bus-control channel is still open
  EXPECT_EQ(x.m.close_channel(h), uint32_t{ERR_OK});
  EXPECT_EQ(x.m.object_count(0), 0u);
  EXPECT_EQ(x.m.close_channel(h), uint32_t{ERR_XCAN_INVALID_HANDLE});
  const ChannelHandle again = x.bus_control();
  EXPECT_EQ(x.m.info(again, INFO_DEVICE).value(), XCAN_STATUS(0, 0));
}

TEST(XcanBus, ABitRateMismatchGivesTheErrorCallbackAtWarnAndBusOffThenStopStartRecovers) {
  Xcan x;
  model::testing::NodeLog chip_log;  // what the 82527 went through, to check the instants
  x.m.chip(0).set_listener(&chip_log);
  const ChannelHandle ctrl =
      x.bus_control(0, XCAN_BITPARAMS{250, 13, 2, 1, 1, 0, 11}, _CP_SYNC_CALLBACK);  // 250 kbit/s
  const ChannelHandle out = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100));
  EXPECT_EQ(x.write(out, {0x55}), uint32_t{ERR_OK});
  // The rest of the bus runs at 500 kbit/s: two SJA1000 nodes talking to each other keep their
  // receive counters low, so their error flags go on destroying the interface's frames.
  testing::Peer other(x.b);
  other.start();
  for (int k = 0; k < 100; ++k) {
    x.peer.send(data_frame(0x200, {1, 2, 3, 4}));
    other.send(data_frame(0x201, {1}));
  }
  x.run_until(60'000'000);
  ASSERT_TRUE(x.peer.queue.empty());
  ASSERT_TRUE(other.queue.empty());

  // The first error that took a counter to 96, and the bus-off instant.
  auto warn = std::find_if(chip_log.errors.begin(), chip_log.errors.end(),
                           [](const BusErrorEvent& e) { return e.tec >= 96 || e.rec >= 96; });
  ASSERT_NE(warn, chip_log.errors.end());
  auto off = std::find_if(chip_log.states.begin(), chip_log.states.end(),
                          [](const auto& s) { return s.second == ErrorState::bus_off; });
  ASSERT_NE(off, chip_log.states.end());
  const auto lec_of = [](const BusErrorEvent& e) -> uint16_t {
    switch (e.type) {
      case CanErrorType::stuff:
        return XCAN_LEC_STUFF;
      case CanErrorType::form:
        return XCAN_LEC_FORM;
      case CanErrorType::ack:
        return XCAN_LEC_ACK;
      case CanErrorType::crc:
        return XCAN_LEC_CRC;
      case CanErrorType::bit:
        return XCAN_LEC_BIT1;
    }
    return 0;
  };
  ASSERT_EQ(x.sink.callbacks.size(), 2u);
  const XcanCallback& heavy = x.sink.callbacks[0];
  EXPECT_EQ(heavy.channel, ctrl);
  EXPECT_TRUE(heavy.sync);
  EXPECT_EQ(heavy.arg, CallbackArg::status);
  EXPECT_EQ(heavy.at, warn->at);
  EXPECT_EQ(XCAN_STATUS_FLAGS(heavy.status), XCAN_BUS_ON | XCAN_BUS_HEAVY);
  EXPECT_EQ(XCAN_STATUS_LEC(heavy.status), lec_of(*warn));
  const XcanCallback& bus_off = x.sink.callbacks[1];
  EXPECT_EQ(bus_off.at.ns(), off->first);
  EXPECT_EQ(XCAN_STATUS_FLAGS(bus_off.status), XCAN_BUS_HEAVY | XCAN_BUS_OFF);
  EXPECT_EQ(XCAN_STATUS_LEC(bus_off.status), lec_of(chip_log.errors.back()));
  EXPECT_EQ(x.m.info(ctrl, INFO_DEVICE).value(), bus_off.status);
  EXPECT_EQ(x.peer.log.received.size(), other.log.sent.size());  // none of the interface's

  // Bus-off is left only by CMD_STOP, then CMD_START.
  EXPECT_EQ(x.write(out, {0x66}), uint32_t{ERR_XCAN_NOT_READY});
  EXPECT_EQ(x.m.control(ctrl, CMD_START), uint32_t{ERR_XCAN_NOT_READY});
  EXPECT_EQ(x.m.control(ctrl, CMD_STOP), uint32_t{ERR_OK});
  EXPECT_EQ(x.m.write_block(ctrl, bytes(params_500k())).error, uint32_t{ERR_OK});
  const int64_t start = x.now();
  EXPECT_EQ(x.m.control(ctrl, CMD_START), uint32_t{ERR_OK});
  // 128 x 11 recessive bits at 500 kbit/s on an idle bus, then both counters are 0.
  const int64_t recovered = start + 128 * 11 * model::testing::kBit;
  x.run_until(recovered - 1);
  EXPECT_TRUE(x.m.chip(0).confinement().bus_off());
  x.run_until(recovered);
  EXPECT_FALSE(x.m.chip(0).confinement().bus_off());
  EXPECT_EQ(x.m.chip(0).confinement().tec(), 0u);
  EXPECT_EQ(x.m.chip(0).confinement().rec(), 0u);
  x.run_until(70'000'000);
  // The request that waited in its buffer goes at the right rate now; no further callback on
  // the bus-control channel (none for leaving bus-off).
  const Frame f = data_frame(0x100, {0x55});
  ASSERT_FALSE(x.peer.log.received.empty());
  EXPECT_EQ(x.peer.log.received.back().frame, f);
  EXPECT_EQ(x.peer.log.received.back().at, recovered + frame_ns(f));
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.m.info(ctrl, INFO_DEVICE).value()), XCAN_BUS_ON);
  ASSERT_EQ(x.sink.callbacks.size(), 3u);
  EXPECT_EQ(x.sink.callbacks[2].channel, out);
}

TEST(XcanBus, ALoneInterfaceSeesAckErrorsInTheHighWord) {
  Xcan x;
  const ChannelHandle ctrl = x.bus_control(1);
  const ChannelHandle out = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100, 0, 0, 1));
  x.write(out, {0x01});
  x.run_until(3'000'000);
  const ULONG state = x.m.info(ctrl, INFO_DEVICE).value();
  EXPECT_EQ(XCAN_STATUS_LEC(state), XCAN_LEC_ACK);
  // A lone transmitter's counter stops at error-passive (ack errors then count no more), so it
  // never goes bus-off; on the way it passes 96 at the 12th ack error: one callback then.
  // Each try is 128 us: the 47 bits up to the ack slot's error, the flag, its delimiter and the
  // intermission.
  ASSERT_EQ(x.sink.callbacks.size(), 1u);
  EXPECT_EQ(x.sink.callbacks[0].at.ns(), 94'000 + 11 * 128'000);
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.sink.callbacks[0].status), XCAN_BUS_ON | XCAN_BUS_HEAVY);
  EXPECT_TRUE((XCAN_STATUS_FLAGS(state) & XCAN_BUS_OFF) == 0);
}

TEST(XcanBus, TheLowSpeedLineErrorIsReportedAndTheInterfaceGoesOnTalking) {
  Xcan x(XcanVariant::f);
  EXPECT_TRUE(x.m.low_speed(0));
  const ChannelHandle ctrl = x.bus_control(0, XCAN_BITPARAMS{500, 13, 2, 1, 1, 0, 11});
  x.peer.node.stop();
  x.peer.start(0x03, 0x1C);  // 125 kbit/s
  const ChannelHandle out = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100));
  x.run_until(1'000);
  EXPECT_TRUE(x.m.set_line_error(0, true));
  ASSERT_EQ(x.sink.callbacks.size(), 1u);
  EXPECT_EQ(x.sink.callbacks[0].at.ns(), 1'000);
  EXPECT_EQ(x.sink.callbacks[0].status, XCAN_STATUS(XCAN_BUS_ON | XCAN_LINE_ERROR, 0));
  EXPECT_EQ(x.m.info(ctrl, INFO_DEVICE).value(), XCAN_STATUS(XCAN_BUS_ON | XCAN_LINE_ERROR, 0));
  x.write(out, {0x01});  // single-wire mode: the frame still goes
  x.run_until(2'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_TRUE(x.m.set_line_error(0, false));
  EXPECT_EQ(x.m.info(ctrl, INFO_DEVICE).value(), XCAN_STATUS(XCAN_BUS_ON, 0));
  EXPECT_EQ(x.sink.callbacks.size(), 2u);  // the send's; none when the fault ends

  Xcan hs(XcanVariant::h);
  EXPECT_FALSE(hs.m.set_line_error(0, true));
}

TEST(XcanBus, AnInterfaceAndAnSja1000ExchangeDataAndRemoteFramesBothWays) {
  Xcan x;
  x.bus_control();
  const ChannelHandle active_send = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100));
  const ChannelHandle passive_receive = x.open(Xcan::cps(DEVICE_BUS_IN, 0x101));
  const ChannelHandle passive_send =
      x.open(Xcan::cps(DEVICE_BUS_OUT, 0x102, XCAN_REMOTE | XCAN_EXCL_BUFFER));
  const ChannelHandle active_receive =
      x.open(Xcan::cps(DEVICE_BUS_IN, 0x103, XCAN_REMOTE | XCAN_NO_INT, 10'000));
  x.write(passive_send, {0xC0, 0xC1});

  // X-CAN -> SJA1000: a data frame; SJA1000 -> X-CAN: a data frame.
  x.write(active_send, {0xA0});
  x.peer.send(data_frame(0x101, {0xB0}));
  // SJA1000 -> X-CAN: a remote frame the passive send object answers.
  x.peer.send(remote_frame(0x102, 2));
  x.run_until(2'000'000);
  // X-CAN -> SJA1000: a remote frame (an active receive read) the SJA1000 answers.
  const Reply r = x.m.read_block(active_receive);
  ASSERT_TRUE(r.pending.has_value());
  x.run_until(2'000'000 + frame_ns(remote_frame(0x103, 0)));
  x.peer.send(data_frame(0x103, {0xD0, 0xD1, 0xD2}));
  x.run_until(4'000'000);

  // The bus: 100h (lowest ID wins against 101h), 101h, the remote 102h, the answer 102h, the
  // remote 103h, the answer 103h.
  std::vector<Frame> on_bus;
  for (const auto& item : x.peer.log.received) {
    on_bus.push_back(item.frame);
  }
  EXPECT_EQ(on_bus, (std::vector<Frame>{data_frame(0x100, {0xA0}), data_frame(0x102, {0xC0, 0xC1}),
                                        remote_frame(0x103, 0)}));
  ASSERT_EQ(x.peer.log.sent.size(), 3u);
  // Both started together; 100h won the arbitration, 101h followed right after it.
  EXPECT_EQ(x.peer.log.received[0].at, frame_ns(data_frame(0x100, {0xA0})));
  EXPECT_EQ(x.peer.log.sent[0].frame, data_frame(0x101, {0xB0}));
  EXPECT_EQ(x.peer.log.sent[0].at,
            x.peer.log.received[0].at + kIntermission + frame_ns(data_frame(0x101, {0xB0})));
  EXPECT_EQ(x.read(passive_receive), (Bytes{0xB0}));
  ASSERT_EQ(x.sink.completions.size(), 1u);
  EXPECT_EQ(x.sink.completions[0].data, (Bytes{0xD0, 0xD1, 0xD2}));
  EXPECT_EQ(x.m.info(passive_send, INFO_XCAN_MSG_COUNT).value(), 1u);
  EXPECT_EQ(x.m.info(active_send, INFO_XCAN_MSG_COUNT).value(), 1u);
  EXPECT_EQ(x.m.info(passive_receive, INFO_XCAN_MSG_COUNT).value(), 1u);
  EXPECT_EQ(x.m.info(active_receive, INFO_XCAN_MSG_COUNT).value(), 1u);
}

}  // namespace
}  // namespace canemu::model::sorcus
