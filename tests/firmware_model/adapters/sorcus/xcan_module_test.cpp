// The X-CAN-2i MDD's objects seen through its channel services, with an SJA1000 node on the
// bus (digest §3.1, checklist §6 items 22, 23, 31, 42-57). Instants in ns at 500 kbit/s.
#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

#include <gtest/gtest.h>

#include "xcan_fixture.hpp"

namespace canemu::model::sorcus {
namespace {

using namespace testing;  // xcan_fixture.hpp

TEST(XcanObjects, ActiveSendWritesADataFrameAndCallsBackAfterTheAcknowledgedTransmission) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123));
  EXPECT_EQ(x.write(h, {0x11, 0x22}), uint32_t{ERR_OK});
  x.run_until(1'000'000);
  const Frame f = data_frame(0x123, {0x11, 0x22});
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, f);
  EXPECT_EQ(x.peer.log.received[0].at, frame_ns(f));
  ASSERT_EQ(x.sink.callbacks.size(), 1u);
  EXPECT_EQ(x.sink.callbacks[0].at.ns(), frame_ns(f));
  EXPECT_EQ(x.sink.callbacks[0].channel, h);
  EXPECT_EQ(x.sink.callbacks[0].arg, CallbackArg::none);
  EXPECT_FALSE(x.sink.callbacks[0].sync);
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 1u);
  EXPECT_EQ(x.read(h), (Bytes{0x11, 0x22}));  // a read gives the last data written
}

TEST(XcanObjects, ActiveSendRefusesMoreThanEightBytes) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123));
  EXPECT_EQ(x.write(h, Bytes(9, 0)), uint32_t{ERR_XCAN_DATA_SIZE});
  EXPECT_EQ(x.write(h, {}), uint32_t{ERR_OK});  // 0 bytes are a frame
  x.run_until(1'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, data_frame(0x123, {}));
}

TEST(XcanObjects, ActiveSendWithNoIntWaitsForItsFrameAndCallsNothing) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123, XCAN_NO_INT, 1000));
  const Reply r = x.m.write_block(h, Bytes{0x01});
  EXPECT_EQ(r.error, uint32_t{ERR_OK});
  ASSERT_TRUE(r.pending.has_value());
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.completions.size(), 1u);
  EXPECT_EQ(x.sink.completions[0].request, *r.pending);
  EXPECT_EQ(x.sink.completions[0].error, uint32_t{ERR_OK});
  EXPECT_EQ(x.sink.completions[0].at.ns(), frame_ns(data_frame(0x123, {0x01})));
  EXPECT_TRUE(x.sink.callbacks.empty());
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 1u);
}

TEST(XcanObjects, ActiveSendWithNoIntTimesOutAfterUsTimeoutWhenNobodyAcknowledges) {
  Xcan x;
  x.bus_control(1);  // interface 1: alone on its bus, no acknowledgement ever
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123, XCAN_NO_INT, 700, 1));
  const Reply r = x.m.write_block(h, Bytes{0x01});
  ASSERT_TRUE(r.pending.has_value());
  x.run_until(699'999);
  EXPECT_TRUE(x.sink.completions.empty());
  x.run_until(700'000);
  ASSERT_EQ(x.sink.completions.size(), 1u);
  EXPECT_EQ(x.sink.completions[0].error, uint32_t{ERR_XCAN_TIMEOUT});
  EXPECT_EQ(x.sink.completions[0].at.ns(), 700'000);
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 0u);
}

TEST(XcanObjects, ATimedOutSendIsNotWithdrawnAndGoesOnceSomebodyAcknowledges) {
  Xcan x;
  x.bus_control();
  x.peer.node.stop();  // nobody acknowledges
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123, XCAN_NO_INT, 700));
  ASSERT_TRUE(x.m.write_block(h, Bytes{0x01}).pending.has_value());
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.completions.size(), 1u);
  EXPECT_EQ(x.sink.completions[0].error, uint32_t{ERR_XCAN_TIMEOUT});
  x.peer.start();
  x.run_until(3'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, data_frame(0x123, {0x01}));
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 1u);
  EXPECT_EQ(x.sink.completions.size(), 1u);  // the request had ended already
}

TEST(XcanObjects, ActiveSendCmdStartSendsThePreviousDataAgain) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123));
  x.write(h, {0xAA});
  x.run_until(1'000'000);
  EXPECT_EQ(x.m.control(h, CMD_START), uint32_t{ERR_OK});
  x.run_until(2'000'000);
  const Frame f = data_frame(0x123, {0xAA});
  ASSERT_EQ(x.peer.log.received.size(), 2u);
  EXPECT_EQ(x.peer.log.received[1].frame, f);
  EXPECT_EQ(x.peer.log.received[1].at, 1'000'000 + frame_ns(f));
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 2u);
  EXPECT_EQ(x.sink.callbacks.size(), 2u);
}

TEST(XcanObjects, PassiveSendWriteOnlyUpdatesTheDataAndARemoteFrameGetsTheDataValidThen) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x200, XCAN_REMOTE));
  x.write(h, {0x01});
  x.run_until(500'000);
  EXPECT_TRUE(x.peer.log.received.empty());  // «ohne dass die Daten … versendet werden»
  x.write(h, {0x02, 0x03});                  // the data valid when the remote frame comes
  const Frame request = remote_frame(0x200, 2);
  x.peer.send(request);
  x.run_until(1'000'000);
  const Frame answer = data_frame(0x200, {0x02, 0x03});
  const int64_t answer_end = 500'000 + frame_ns(request) + kIntermission + frame_ns(answer);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, answer);
  EXPECT_EQ(x.peer.log.received[0].at, answer_end);
  // The callback comes after the answer went, not when the remote frame came.
  ASSERT_EQ(x.sink.callbacks.size(), 1u);
  EXPECT_EQ(x.sink.callbacks[0].at.ns(), answer_end);
  EXPECT_EQ(x.sink.callbacks[0].arg, CallbackArg::none);
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 1u);
  EXPECT_EQ(x.read(h), (Bytes{0x02, 0x03}));
}

TEST(XcanObjects, PassiveSendWithNoIntAnswersWithoutCallbackAndCmdStartSendsActively) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x200, XCAN_REMOTE | XCAN_NO_INT));
  x.write(h, {0x05});
  x.peer.send(remote_frame(0x200, 1));
  x.run_until(1'000'000);
  EXPECT_EQ(x.m.control(h, CMD_START), uint32_t{ERR_OK});
  x.run_until(2'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 2u);
  EXPECT_EQ(x.peer.log.received[0].frame, data_frame(0x200, {0x05}));
  EXPECT_EQ(x.peer.log.received[1].frame, data_frame(0x200, {0x05}));
  EXPECT_EQ(x.peer.log.received[1].at, 1'000'000 + frame_ns(data_frame(0x200, {0x05})));
  EXPECT_TRUE(x.sink.callbacks.empty());
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 2u);
}

TEST(XcanObjects, ActiveReceiveNeedsRemoteAndNoInt) {
  Xcan x;
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_IN, 0x300, XCAN_REMOTE, 100), true).error(),
            uint32_t{ERR_XCAN_INVALID_CPS});
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_IN, 0x300, XCAN_NO_INT, 100), true).error(),
            uint32_t{ERR_XCAN_INVALID_CPS});
}

// The bus running and an active-receive object for 0x300 (a remote frame asks for it, the
// answer awaited up to `timeout` ms) with a read pending on it.
ChannelHandle pending_active_read(Xcan& x, USHORT timeout) {
  x.bus_control();
  const ChannelHandle h =
      x.open(Xcan::cps(DEVICE_BUS_IN, 0x300, XCAN_REMOTE | XCAN_NO_INT, timeout));
  EXPECT_TRUE(x.m.read_block(h).pending.has_value());
  return h;
}

TEST(XcanObjects, ActiveReceiveReadSendsARemoteFrameAndCompletesWithTheAnswer) {
  Xcan x;
  const ChannelHandle h = pending_active_read(x, 5000);
  const Frame request = remote_frame(0x300, 0);
  x.run_until(frame_ns(request));
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, request);
  const Frame answer = data_frame(0x300, {0xDE, 0xAD});
  x.peer.send(answer);  // the SJA1000's driver answers at once
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.completions.size(), 1u);
  EXPECT_EQ(x.sink.completions[0].error, uint32_t{ERR_OK});
  EXPECT_EQ(x.sink.completions[0].data, (Bytes{0xDE, 0xAD}));
  EXPECT_EQ(x.sink.completions[0].at.ns(), frame_ns(request) + kIntermission + frame_ns(answer));
  EXPECT_TRUE(x.sink.callbacks.empty());  // a read calls no callback
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 1u);
}

TEST(XcanObjects, ActiveReceiveReadTimesOutWithoutAnAnswer) {
  Xcan x;
  pending_active_read(x, 300);
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.completions.size(), 1u);
  EXPECT_EQ(x.sink.completions[0].error, uint32_t{ERR_XCAN_TIMEOUT});
  EXPECT_EQ(x.sink.completions[0].at.ns(), 300'000);
}

TEST(XcanObjects, ActiveReceiveCmdStartGivesTheAnswerToTheCallback) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h =
      x.open(Xcan::cps(DEVICE_BUS_IN, 0x300, XCAN_REMOTE | XCAN_NO_INT | _CP_SYNC_CALLBACK, 300));
  EXPECT_EQ(x.m.control(h, CMD_START), uint32_t{ERR_OK});
  const Frame request = remote_frame(0x300, 0);
  x.run_until(frame_ns(request));
  const Frame answer = data_frame(0x300, {1, 2, 3, 4, 5, 6, 7, 8});
  x.peer.send(answer);
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.callbacks.size(), 1u);
  const XcanCallback& c = x.sink.callbacks[0];
  EXPECT_EQ(c.at.ns(), frame_ns(request) + kIntermission + frame_ns(answer));
  EXPECT_EQ(c.arg, CallbackArg::data);
  EXPECT_TRUE(c.sync);
  EXPECT_EQ(c.size, 8u);
  EXPECT_EQ(c.data, (std::array<uint8_t, 8>{1, 2, 3, 4, 5, 6, 7, 8}));
  // A second answer without a request calls nothing.
  x.peer.send(answer);
  x.run_until(2'000'000);
  EXPECT_EQ(x.sink.callbacks.size(), 1u);
}

TEST(XcanObjects, PassiveReceiveCallsBackOnEachFrameAndAReadGivesTheLatest) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_IN, 0x400));
  const Frame a = data_frame(0x400, {0x01});
  const Frame b = data_frame(0x400, {0x02, 0x03});
  x.peer.send(a);
  x.peer.send(b);
  x.peer.send(data_frame(0x401, {0x09}));  // its own buffer matches 400h exactly
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.callbacks.size(), 2u);
  EXPECT_EQ(x.sink.callbacks[0].at.ns(), frame_ns(a));
  EXPECT_EQ(x.sink.callbacks[0].size, 1u);
  EXPECT_EQ(x.sink.callbacks[0].data[0], 0x01);
  EXPECT_EQ(x.sink.callbacks[1].at.ns(), frame_ns(a) + kIntermission + frame_ns(b));
  EXPECT_EQ(x.sink.callbacks[1].size, 2u);
  EXPECT_EQ(x.read(h), (Bytes{0x02, 0x03}));  // last writer wins
  EXPECT_EQ(x.read(h), (Bytes{0x02, 0x03}));  // and stays readable
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 2u);
}

TEST(XcanObjects, NewOnlyReadWithoutNewDataGivesStickyDataNotReadyUntilClearError) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_IN, 0x400, XCAN_NEW_ONLY));
  x.peer.send(data_frame(0x400, {0x07}));
  x.run_until(1'000'000);
  EXPECT_EQ(x.read(h), (Bytes{0x07}));
  EXPECT_EQ(x.m.read_block(h).error, uint32_t{ERR_DATA_NOT_READY});
  x.peer.send(data_frame(0x400, {0x08}));
  x.run_until(2'000'000);
  EXPECT_EQ(x.m.read_block(h).error, uint32_t{ERR_DATA_NOT_READY});  // sticky
  EXPECT_EQ(x.m.clear_error(h), uint32_t{ERR_OK});
  EXPECT_EQ(x.read(h), (Bytes{0x08}));
}

// Checklist 106: what the manual marks «ab MDD Version 3.C» is missing from an MDD 3.B; the
// rest works as in 3.C.
TEST(XcanObjects, AnMddBefore3CHasNoSendCountNoNewOnlyAndNoGeneralIdChannel) {
  EXPECT_EQ(MddVersion::parse("3.B"), (MddVersion{3, 'B'}));
  EXPECT_EQ(MddVersion::parse("3.c"), std::nullopt);
  EXPECT_EQ(MddVersion::parse("10.A"), std::nullopt);
  EXPECT_LT(MddVersion::parse("2.Z"), kMdd3C);
  EXPECT_GT(MddVersion::parse("4.A"), kMdd3C);
  Xcan x;
  x.m.set_mdd_version(MddVersion{3, 'B'});
  x.bus_control();
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_IN, 0x400, XCAN_NEW_ONLY), true).error(),
            uint32_t{ERR_XCAN_INVALID_CPS});
  EXPECT_EQ(
      x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE), true).error(),
      uint32_t{ERR_XCAN_INVALID_CPS});
  const ChannelHandle send = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100));
  const ChannelHandle passive = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x101, XCAN_REMOTE));
  const ChannelHandle receive = x.open(Xcan::cps(DEVICE_BUS_IN, 0x200));
  EXPECT_EQ(x.write(send, {0x01}), uint32_t{ERR_OK});
  x.peer.send(data_frame(0x200, {0x02}));
  x.run_until(1'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.m.info(send, INFO_XCAN_MSG_COUNT).error(), uint32_t{ERR_XCAN_WRONG_TYPE});
  EXPECT_EQ(x.m.info(passive, INFO_XCAN_MSG_COUNT).error(), uint32_t{ERR_XCAN_WRONG_TYPE});
  EXPECT_EQ(x.m.info(receive, INFO_XCAN_MSG_COUNT).value(), 1u);  // receive objects count
  // From 3.C on (the default), all three are there.
  Xcan y;
  EXPECT_EQ(y.m.mdd_version(), kMdd3C);
  y.bus_control();
  EXPECT_TRUE(y.m.open_channel(Xcan::cps(DEVICE_BUS_IN, 0x400, XCAN_NEW_ONLY), true));
  EXPECT_TRUE(y.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE), true));
  const ChannelHandle counted = y.open(Xcan::cps(DEVICE_BUS_OUT, 0x100));
  EXPECT_EQ(y.m.info(counted, INFO_XCAN_MSG_COUNT).value(), 0u);
}

TEST(XcanObjects, PassiveReceiveCmdStartSendsARemoteFrameAndTheAnswerCallsBack) {
  Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_IN, 0x400));
  EXPECT_EQ(x.m.control(h, CMD_START), uint32_t{ERR_OK});
  const Frame request = remote_frame(0x400, 0);
  x.run_until(frame_ns(request));
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, request);
  x.peer.send(data_frame(0x400, {0x42}));
  x.run_until(1'000'000);
  EXPECT_EQ(x.callback_data(), (std::vector<Bytes>{{0x42}}));
}

TEST(XcanObjects, ASecondChannelAttachesToTheObjectWithTheSameCpsAndAnotherIsRefused) {
  Xcan x;
  x.bus_control();
  const ChannelHandle a = x.open(Xcan::cps(DEVICE_BUS_IN, 0x400));
  const ChannelHandle b = x.open(Xcan::cps(DEVICE_BUS_IN, 0x400, _CP_SYNC_CALLBACK));
  EXPECT_EQ(x.m.object_count(0), 1u);
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_IN, 0x400, XCAN_NEW_ONLY), true).error(),
            uint32_t{ERR_XCAN_CPS_MISMATCH});
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x400), true).error(),
            uint32_t{ERR_XCAN_CPS_MISMATCH});
  x.peer.send(data_frame(0x400, {0x01}));
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.callbacks.size(), 2u);
  EXPECT_EQ(x.sink.callbacks[0].channel, a);
  EXPECT_FALSE(x.sink.callbacks[0].sync);
  EXPECT_EQ(x.sink.callbacks[1].channel, b);
  EXPECT_TRUE(x.sink.callbacks[1].sync);
}

TEST(XcanObjects, IdentifiersOutOfRangeAndInvalidParametersAreRefused) {
  Xcan x;
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x7F0), true).error(),
            uint32_t{ERR_XCAN_ID_RANGE});
  EXPECT_TRUE(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x7EF), true).has_value());
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x100, 0, 0, 2), true).error(),
            uint32_t{ERR_XCAN_INVALID_CPS});
  EXPECT_EQ(x.m.open_channel(Xcan::cps(7, 0x100), true).error(), uint32_t{ERR_XCAN_INVALID_CPS});
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x100, XCAN_NEW_ONLY), true).error(),
            uint32_t{ERR_XCAN_INVALID_CPS});
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x100, XCAN_29BIT_ID), true).error(),
            uint32_t{ERR_XCAN_INVALID_CPS});  // 29 bits only in the mixed format
  EXPECT_EQ(x.m.write_block(99, Bytes{}).error, uint32_t{ERR_XCAN_INVALID_HANDLE});
}

TEST(XcanObjects, TwentyNineBitObjectsTakeIdsUpTo1FFFFFEF) {
  Xcan x;
  XCAN_BITPARAMS p = testing::params_500k();
  p.MsgFormat = 29;
  x.bus_control(0, p);
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x1FFFFFF0), true).error(),
            uint32_t{ERR_XCAN_ID_RANGE});
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x1FFFFFEF));
  x.write(h, {0x01});
  x.run_until(1'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, data_frame(0x1FFFFFEF, {0x01}, true));
}

TEST(XcanObjects, WrongServicesForAChannelAreRefused) {
  Xcan x;
  const ChannelHandle in = x.open(Xcan::cps(DEVICE_BUS_IN, 0x400));
  EXPECT_EQ(x.write(in, {0x01}), uint32_t{ERR_XCAN_WRONG_TYPE});
  EXPECT_EQ(x.m.write_ulong(in, 0), uint32_t{ERR_XCAN_WRONG_TYPE});
  EXPECT_EQ(x.m.control(in, CMD_STOP), uint32_t{ERR_XCAN_WRONG_TYPE});
  EXPECT_EQ(x.m.info(in, INFO_DEVICE).error(), uint32_t{ERR_XCAN_WRONG_TYPE});
}

TEST(XcanObjects, AZeroTimeoutWaitsForNothing) {
  testing::Xcan x;
  x.bus_control();
  const ChannelHandle out = x.open(testing::Xcan::cps(DEVICE_BUS_OUT, 0x123, XCAN_NO_INT, 0));
  const Reply w = x.m.write_block(out, std::vector<uint8_t>{0x01});
  EXPECT_EQ(w.error, uint32_t{ERR_OK});
  EXPECT_FALSE(w.pending.has_value());
  const ChannelHandle in =
      x.open(testing::Xcan::cps(DEVICE_BUS_IN, 0x300, XCAN_REMOTE | XCAN_NO_INT, 0));
  const Reply r = x.m.read_block(in);
  EXPECT_EQ(r.error, uint32_t{ERR_OK});
  EXPECT_FALSE(r.pending.has_value());
  EXPECT_TRUE(r.data.empty());  // nothing has come yet; the remote frame goes all the same
  x.run_until(1'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 2u);
  EXPECT_EQ(x.peer.log.received[1].frame, testing::remote_frame(0x300, 0));
  EXPECT_TRUE(x.sink.completions.empty());
}

TEST(XcanObjects, TwoWritesInARowSendTwoFramesEachWithItsData) {
  testing::Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(testing::Xcan::cps(DEVICE_BUS_OUT, 0x123));
  EXPECT_EQ(x.write(h, {0x01}), uint32_t{ERR_OK});
  EXPECT_EQ(x.write(h, {0x02}), uint32_t{ERR_OK});  // waits for the first to go
  EXPECT_EQ(x.write(h, {0x03}), uint32_t{ERR_OK});  // merges with the waiting one
  EXPECT_EQ(x.m.fifo_size(0), 1u);
  x.run_until(1'000'000);
  const Frame a = testing::data_frame(0x123, {0x01});
  const Frame b = testing::data_frame(0x123, {0x03});
  ASSERT_EQ(x.peer.log.received.size(), 2u);
  EXPECT_EQ(x.peer.log.received[0].frame, a);
  EXPECT_EQ(x.peer.log.received[1].frame, b);
  EXPECT_EQ(x.peer.log.received[1].at,
            testing::frame_ns(a) + testing::kIntermission + testing::frame_ns(b));
  EXPECT_EQ(x.sink.callbacks.size(), 2u);
  EXPECT_EQ(x.m.info(h, INFO_XCAN_MSG_COUNT).value(), 2u);
}

TEST(XcanObjects, APassiveSendObjectAnswersWithTheDataWrittenWhileTheRemoteFrameWasOnTheWire) {
  testing::Xcan x;
  x.bus_control();
  const ChannelHandle h = x.open(testing::Xcan::cps(DEVICE_BUS_OUT, 0x200, XCAN_REMOTE));
  x.write(h, {0x01});
  const Frame request = testing::remote_frame(0x200, 1);
  x.peer.send(request);
  x.run_until(testing::frame_ns(request) / 2);
  x.write(h, {0x09});  // mid-frame: valid when the remote frame has come
  x.run_until(1'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, testing::data_frame(0x200, {0x09}));
}

}  // namespace
}  // namespace canemu::model::sorcus
