// The X-CAN-2i MDD's buffer manager and buffer 15 (digest §1.4, §1.5, §3.1.6, §3.1.7; checklist
// §6 items 1-8, 11-20, 33-39, 55, 56): own buffers up to 14 objects, exclusive buffers, the
// temporary pool and the FIFO beyond, the automatic acceptance filter, the acceptance-filter
// device and the general-ID send channel, against an SJA1000 node at 500 kbit/s.
#include <gtest/gtest.h>

#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"
#include "xcan_fixture.hpp"

namespace canemu::model::sorcus {
namespace {

using namespace testing;  // xcan_fixture.hpp
using Use = BufferView::Use;

// Objects `first`, `first + 1`, ... of one kind.
std::vector<ChannelHandle> open_many(Xcan& x, USHORT device, ULONG first, int count,
                                     USHORT flags = 0) {
  std::vector<ChannelHandle> out;
  for (int k = 0; k < count; ++k) {
    out.push_back(x.open(Xcan::cps(device, first + static_cast<ULONG>(k), flags)));
  }
  return out;
}

// The peer sends one data frame with one byte (the ID's low byte) for every ID in [from, to].
void send_each(Xcan& x, uint32_t from, uint32_t to) {
  for (uint32_t id = from; id <= to; ++id) {
    x.peer.send(data_frame(id, {static_cast<uint8_t>(id)}));
  }
}

TEST(XcanBuffers, UpToFourteenObjectsEachHaveABufferOfTheirOwn) {
  Xcan x;
  open_many(x, DEVICE_BUS_OUT, 0x100, 7);
  open_many(x, DEVICE_BUS_IN, 0x200, 7);
  for (uint8_t n = 1; n <= 14; ++n) {
    const BufferView v = x.m.buffer(0, n);
    EXPECT_EQ(v.use, Use::own) << int{n};
    EXPECT_EQ(v.id, n <= 7 ? 0x100u + n - 1 : 0x200u + n - 8) << int{n};
  }
  EXPECT_EQ(x.m.buffer(0, 15).use, Use::unused);
}

TEST(XcanBuffers, TwentyObjectsUseExclusiveBuffersTheTemporaryPoolAndTheFifo) {
  Xcan x;
  x.bus_control();
  const auto excl = open_many(x, DEVICE_BUS_OUT, 0x010, 3, XCAN_EXCL_BUFFER);
  const auto sends = open_many(x, DEVICE_BUS_OUT, 0x100, 15);
  const auto receives = open_many(x, DEVICE_BUS_IN, 0x003, 1);
  x.open(Xcan::cps(DEVICE_BUS_IN, 0x007));
  ASSERT_EQ(x.m.object_count(0), 20u);
  // The plan: exclusive objects keep 1..3; the buffers the others had are the temporary pool
  // (still caching them); the passive receive objects share buffer 15.
  for (uint8_t n = 1; n <= 3; ++n) {
    EXPECT_EQ(x.m.buffer(0, n).use, Use::exclusive);
    EXPECT_EQ(x.m.buffer(0, n).id, 0x010u + n - 1);
  }
  for (uint8_t n = 4; n <= 14; ++n) {
    EXPECT_EQ(x.m.buffer(0, n).use, Use::temporary);
    EXPECT_EQ(x.m.buffer(0, n).id, 0x100u + n - 4);
  }
  EXPECT_EQ(x.m.buffer(0, 15).use, Use::receive_only);
  EXPECT_EQ(x.m.buffer15_filter(0), (AcceptanceFilter{0x7FB, 0x003}));

  // All at once: the exclusive object, then 15 active objects for 11 temporary buffers.
  EXPECT_EQ(x.write(excl[0], {0xE0}), uint32_t{ERR_OK});
  for (std::size_t k = 0; k < sends.size(); ++k) {
    EXPECT_EQ(x.write(sends[k], {static_cast<uint8_t>(k)}), uint32_t{ERR_OK});
  }
  EXPECT_EQ(x.m.fifo_size(0), 4u);
  // The FIFO holds the object: a write while it waits changes the data that will go.
  EXPECT_EQ(x.write(sends[14], {0xEE}), uint32_t{ERR_OK});
  EXPECT_EQ(x.m.fifo_size(0), 4u);
  EXPECT_TRUE(x.m.buffer(0, 4).busy);
  x.run_until(20'000'000);

  // Lowest buffer first: 1, then 4. When a temporary buffer's frame ends, the 82527 has chosen
  // the next lowest request at once; the driver's interrupt, at that same instant, then loads
  // the FIFO's head into the freed buffer, which goes after it. So 100h (buffer 4), 101h (5),
  // and the FIFO's four alternate in buffers 4 and 5 before 102h..10Ah (6..14).
  std::vector<Frame> expected{data_frame(0x010, {0xE0}), data_frame(0x100, {0}),
                              data_frame(0x101, {1})};
  for (uint8_t k = 11; k <= 13; ++k) {
    expected.push_back(data_frame(0x100 + k, {k}));
  }
  expected.push_back(data_frame(0x10E, {0xEE}));
  for (uint8_t k = 2; k <= 10; ++k) {
    expected.push_back(data_frame(0x100 + k, {k}));
  }
  ASSERT_EQ(x.peer.log.received.size(), expected.size());
  int64_t end = 0;
  for (std::size_t k = 0; k < expected.size(); ++k) {
    end += (k == 0 ? 0 : kIntermission) + frame_ns(expected[k]);
    EXPECT_EQ(x.peer.log.received[k].frame, expected[k]) << k;
    EXPECT_EQ(x.peer.log.received[k].at, end) << k;
  }
  EXPECT_EQ(x.m.fifo_size(0), 0u);
  // One callback per frame, at its end, in the same order.
  ASSERT_EQ(x.sink.callbacks.size(), expected.size());
  EXPECT_EQ(x.sink.callbacks[0].channel, excl[0]);
  EXPECT_EQ(x.sink.callbacks[3].channel, sends[11]);
  EXPECT_EQ(x.sink.callbacks[3].at.ns(), x.peer.log.received[3].at);
  // Buffers 4 and 5 cache the last objects they sent; buffers 6..14 still cache theirs.
  EXPECT_EQ(x.m.buffer(0, 4).id, 0x10Du);
  EXPECT_EQ(x.m.buffer(0, 5).id, 0x10Eu);
  EXPECT_EQ(x.m.buffer(0, 6).id, 0x102u);

  // The passive receive objects in buffer 15: 03h and 07h pass, 05h and 0Bh do not.
  x.sink.callbacks.clear();
  for (uint32_t id : {0x03u, 0x05u, 0x07u, 0x0Bu}) {
    x.peer.send(data_frame(id, {static_cast<uint8_t>(id)}));
  }
  x.run_until(30'000'000);
  ASSERT_EQ(x.sink.callbacks.size(), 2u);
  EXPECT_EQ(x.sink.callbacks[0].channel, receives[0]);
  EXPECT_EQ(x.sink.callbacks[0].data[0], 0x03);
  EXPECT_EQ(x.sink.callbacks[1].data[0], 0x07);
  EXPECT_EQ(x.m.discarded(0), 0u);
}

TEST(XcanBuffers, AFourteenthExclusiveObjectOrGeneralChannelIsRefused) {
  Xcan x;
  open_many(x, DEVICE_BUS_OUT, 0x100, 13, XCAN_EXCL_BUFFER);
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_IN, 0x200, XCAN_EXCL_BUFFER), true).error(),
            uint32_t{ERR_XCAN_EXCL_LIMIT});
  EXPECT_EQ(
      x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE), true).error(),
      uint32_t{ERR_XCAN_EXCL_LIMIT});
  // Without the flag there is room: buffer 14 for one more, the pool beyond.
  EXPECT_TRUE(x.m.open_channel(Xcan::cps(DEVICE_BUS_IN, 0x200), true).has_value());
  EXPECT_TRUE(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x201), true).has_value());
  EXPECT_EQ(x.m.buffer(0, 14).use, Use::temporary);
}

TEST(XcanBuffers, PassiveSendAndReceiveObjectsCannotShareBufferFifteen) {
  Xcan x;
  open_many(x, DEVICE_BUS_OUT, 0x100, 13);
  x.open(Xcan::cps(DEVICE_BUS_IN, 0x003));
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x005, XCAN_REMOTE), true).error(),
            uint32_t{ERR_XCAN_BUFFER15_MIXED});
  // With an exclusive buffer the passive send object is no concern of buffer 15.
  EXPECT_TRUE(
      x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, 0x005, XCAN_REMOTE | XCAN_EXCL_BUFFER), true)
          .has_value());
}

// 13 active send objects and the two passive receive objects of the manual's example: 15
// objects, so the two share buffer 15. Returns the two receive channels.
std::vector<ChannelHandle> example(Xcan& x, ULONG a, ULONG b) {
  x.bus_control();
  open_many(x, DEVICE_BUS_OUT, 0x100, 13);
  return {x.open(Xcan::cps(DEVICE_BUS_IN, a)), x.open(Xcan::cps(DEVICE_BUS_IN, b))};
}

TEST(XcanBuffers, FilterExample1PassesOnlyThreeAndSeven) {
  Xcan x;
  const auto rx = example(x, 0x03, 0x07);
  const ChannelHandle filter = x.filter();
  EXPECT_EQ(x.m.buffer15_filter(0), (AcceptanceFilter{0x7FB, 0x003}));
  EXPECT_EQ(x.m.read_ulong(filter).value(), 0x7FBu);
  send_each(x, 0x00, 0x2F);
  x.run_until(20'000'000);
  ASSERT_EQ(x.peer.log.sent.size(), 0x30u);
  ASSERT_EQ(x.sink.callbacks.size(), 2u);  // the two objects; no unconfigured message passed
  EXPECT_EQ(x.sink.callbacks[0].channel, rx[0]);
  EXPECT_EQ(x.sink.callbacks[0].at.ns(), x.peer.log.sent[0x03].at);
  EXPECT_EQ(x.sink.callbacks[1].channel, rx[1]);
  EXPECT_EQ(x.sink.callbacks[1].at.ns(), x.peer.log.sent[0x07].at);
}

TEST(XcanBuffers, FilterExample2PassesFourteenUnwantedIdsToTheFilterCallback) {
  Xcan x;
  const auto rx = example(x, 0x20, 0x07);
  const ChannelHandle filter = x.filter();
  EXPECT_EQ(x.m.buffer15_filter(0), (AcceptanceFilter{0x7D8, 0x000}));
  send_each(x, 0x00, 0x2F);
  x.run_until(20'000'000);
  std::vector<uint32_t> unwanted;
  for (const XcanCallback& c : x.sink.callbacks) {
    if (c.channel == filter) {
      ASSERT_EQ(c.arg, CallbackArg::message);
      EXPECT_EQ(c.message.usDataSize, 1u);
      EXPECT_EQ(c.message.usFlags, 0u);
      EXPECT_EQ(c.message.aucData[0], static_cast<uint8_t>(c.message.ulCanId));
      EXPECT_EQ(c.at.ns(), x.peer.log.sent[c.message.ulCanId].at);
      unwanted.push_back(c.message.ulCanId);
    } else {
      EXPECT_TRUE(c.channel == rx[0] || c.channel == rx[1]);
    }
  }
  EXPECT_EQ(unwanted, (std::vector<uint32_t>{0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x21, 0x22,
                                             0x23, 0x24, 0x25, 0x26, 0x27}));
  EXPECT_EQ(x.sink.callbacks.size(), 16u);
  EXPECT_EQ(x.m.discarded(0), 0u);
}

TEST(XcanBuffers, WithoutAFilterChannelTheDriverDiscardsUnwantedMessages) {
  Xcan x;
  example(x, 0x20, 0x07);
  send_each(x, 0x00, 0x2F);
  x.run_until(20'000'000);
  EXPECT_EQ(x.sink.callbacks.size(), 2u);
  EXPECT_EQ(x.m.discarded(0), 14u);
}

TEST(XcanBuffers, TheManualMaskMayOpenButNeverNarrowTheAutomaticOne) {
  Xcan x;
  example(x, 0x03, 0x07);
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_CTRL, 0x03), true).error(),
            uint32_t{ERR_XCAN_AUTO_ID_REQUIRED});
  const ChannelHandle filter = x.filter();
  EXPECT_EQ(x.m.write_ulong(filter, 0x7FF), uint32_t{ERR_XCAN_MASK_EXCLUDES});
  EXPECT_EQ(x.m.read_ulong(filter).value(), 0x7FBu);
  EXPECT_EQ(x.m.write_ulong(filter, 0x7F0), uint32_t{ERR_OK});
  EXPECT_EQ(x.m.read_ulong(filter).value(), 0x7F0u);
  send_each(x, 0x00, 0x2F);
  x.run_until(20'000'000);
  std::vector<uint32_t> unwanted;
  for (const XcanCallback& c : x.sink.callbacks) {
    if (c.channel == filter) {
      unwanted.push_back(c.message.ulCanId);
    }
  }
  // 00h..0Fh pass now; 03h and 07h go to their objects.
  EXPECT_EQ(unwanted, (std::vector<uint32_t>{0x00, 0x01, 0x02, 0x04, 0x05, 0x06, 0x08, 0x09, 0x0A,
                                             0x0B, 0x0C, 0x0D, 0x0E, 0x0F}));
}

TEST(XcanBuffers, TheFilterDeviceReadsAllOnesInitiallyAndTakesWholeMasksOnly) {
  Xcan x;
  CPS_XCAN c = Xcan::cps(DEVICE_CTRL, 0x123);
  c.usIndexFirst = 1;
  EXPECT_EQ(x.m.open_channel(c, true).error(), uint32_t{ERR_XCAN_INDEX});
  const ChannelHandle filter = x.filter(0x123);
  EXPECT_EQ(x.m.read_ulong(filter).value(), 0xFFFFFFFFu);
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_CTRL, 0x124), true).error(),
            uint32_t{ERR_XCAN_CHANNEL_BUSY});
  EXPECT_EQ(x.m.write_block(filter, std::vector<uint8_t>{}).error, uint32_t{ERR_XCAN_WRONG_TYPE});
}

TEST(XcanBuffers, ARemoteOnlyFilterWithMaskZeroReceivesEveryRemoteFrameWithoutData) {
  Xcan x;
  x.bus_control();
  const ChannelHandle filter = x.filter(0, XCAN_REMOTE);
  EXPECT_EQ(x.m.write_ulong(filter, 0), uint32_t{ERR_OK});
  x.open(Xcan::cps(DEVICE_BUS_IN, 0x400));  // puts the bus on
  const Frame r = remote_frame(0x555, 4);
  x.peer.send(data_frame(0x321, {1}));  // a data frame: not for a Remote-only buffer 15
  x.peer.send(r);
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.callbacks.size(), 1u);
  const XcanCallback& c = x.sink.callbacks[0];
  EXPECT_EQ(c.channel, filter);
  EXPECT_EQ(c.message.ulCanId, 0x555u);
  EXPECT_EQ(c.message.usDataSize, 0u);
  EXPECT_EQ(c.message.usFlags, XCAN_REMOTE);
  EXPECT_EQ(c.at.ns(), frame_ns(data_frame(0x321, {1})) + kIntermission + frame_ns(r));
}

TEST(XcanBuffers, APassiveSendObjectInBufferFifteenAnswersThroughATemporaryBuffer) {
  Xcan x;
  x.bus_control();
  open_many(x, DEVICE_BUS_OUT, 0x100, 14);
  const ChannelHandle h = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x200, XCAN_REMOTE));
  EXPECT_EQ(x.m.buffer(0, 15).use, Use::receive_only);
  EXPECT_EQ(x.m.buffer15_filter(0), (AcceptanceFilter{0x7FF, 0x200}));
  x.write(h, {0x12, 0x34});
  const Frame request = remote_frame(0x200, 2);
  x.peer.send(request);
  x.run_until(1'000'000);
  const Frame answer = data_frame(0x200, {0x12, 0x34});
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, answer);
  EXPECT_EQ(x.peer.log.received[0].at, frame_ns(request) + kIntermission + frame_ns(answer));
  EXPECT_EQ(x.m.buffer(0, 1).id, 0x200u);  // loaded into the lowest temporary buffer
  ASSERT_EQ(x.sink.callbacks.size(), 1u);
  EXPECT_EQ(x.sink.callbacks[0].channel, h);
  EXPECT_EQ(x.sink.callbacks[0].at.ns(), x.peer.log.received[0].at);
}

TEST(XcanBuffers, TheGeneralIdChannelIsExclusiveAndOnePerInterface) {
  Xcan x;
  EXPECT_EQ(x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID), true).error(),
            uint32_t{ERR_XCAN_INVALID_CPS});
  const ChannelHandle g = x.open(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE));
  EXPECT_EQ(
      x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE), true).error(),
      uint32_t{ERR_XCAN_CHANNEL_BUSY});
  EXPECT_EQ(x.m.buffer(0, 1).use, Use::general);
  EXPECT_EQ(x.m.close_channel(g), uint32_t{ERR_OK});
  // Interface 1 has its own.
  EXPECT_TRUE(
      x.m.open_channel(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE, 0, 1), true)
          .has_value());
}

TEST(XcanBuffers, TheGeneralIdChannelSendsAnyMessageAndTheRemoteAnswerReachesTheFilter) {
  Xcan x;
  XCAN_BITPARAMS p = testing::params_500k();
  p.MsgFormat = XCAN_MIXED_FORMAT;
  x.bus_control(0, p);
  const ChannelHandle g = x.open(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE));
  const ChannelHandle filter = x.filter(0x055);  // mask all ones: exactly 55h
  EXPECT_EQ(x.send_general(g, 0x0ABCDEF, {0x01, 0x02}, XCAN_29BIT_ID), uint32_t{ERR_OK});
  EXPECT_EQ(x.send_general(g, 0x055, {0, 0, 0}, XCAN_REMOTE), uint32_t{ERR_OK});
  EXPECT_EQ(x.send_general(g, 0x056, std::vector<uint8_t>(9, 0)), uint32_t{ERR_XCAN_DATA_SIZE});
  const Frame first = data_frame(0x0ABCDEF, {0x01, 0x02}, true);
  const Frame request = remote_frame(0x055, 3);
  x.run_until(frame_ns(first) + kIntermission + frame_ns(request));
  ASSERT_EQ(x.peer.log.received.size(), 2u);
  EXPECT_EQ(x.peer.log.received[0].frame, first);
  EXPECT_EQ(x.peer.log.received[1].frame, request);  // usDataSize is the remote frame's DLC
  x.peer.send(data_frame(0x055, {0xA1, 0xA2, 0xA3}));
  x.run_until(2'000'000);
  std::vector<XcanCallback> on_filter;
  std::vector<XcanCallback> on_general;
  for (const XcanCallback& c : x.sink.callbacks) {
    (c.channel == filter ? on_filter : on_general).push_back(c);
  }
  EXPECT_EQ(on_general.size(), 2u);  // one per message sent
  ASSERT_EQ(on_filter.size(), 1u);
  EXPECT_EQ(on_filter[0].message.ulCanId, 0x055u);
  EXPECT_EQ(on_filter[0].message.usDataSize, 3u);
  EXPECT_EQ(on_filter[0].message.aucData[2], 0xA3);
}

TEST(XcanBuffers, AnExclusiveObjectInBufferFourteenMovesBelowItAtTheFifteenthObject) {
  Xcan x;
  open_many(x, DEVICE_BUS_OUT, 0x100, 13);
  x.open(Xcan::cps(DEVICE_BUS_IN, 0x300, XCAN_EXCL_BUFFER));
  EXPECT_EQ(x.m.buffer(0, 14).id, 0x300u);
  x.open(Xcan::cps(DEVICE_BUS_OUT, 0x200));
  // Buffer 14 is never exclusive in the shared plan: the object takes the lowest buffer the
  // others left.
  EXPECT_EQ(x.m.buffer(0, 1).use, Use::exclusive);
  EXPECT_EQ(x.m.buffer(0, 1).id, 0x300u);
  EXPECT_EQ(x.m.buffer(0, 14).use, Use::temporary);
  x.bus_control();
  x.peer.send(data_frame(0x300, {0x33}));
  x.run_until(1'000'000);
  EXPECT_EQ(x.callback_data(), (std::vector<Bytes>{{0x33}}));
}

// Checklist 6: «Das Eintragen eines Message-Objekts in einen Message-Puffer nimmt eine gewisse
// Zeit (einige µs) in Anspruch. Wenn ein Message-Objekt … bereits in einem Message-Puffer
// eingetragen ist, entfällt diese Zeit». With a load time of 5 µs set: 15 objects, so buffers
// 1..14 are temporary and cache 100h..10Dh; 10Eh is cached nowhere.
TEST(XcanBuffers, LoadingABufferDelaysItsFrameAndACachedObjectGoesAtOnce) {
  Xcan x;
  EXPECT_EQ(x.m.buffer_load_time(), 0);  // unless set
  x.m.set_buffer_load_time(5'000);
  x.bus_control();
  const auto sends = open_many(x, DEVICE_BUS_OUT, 0x100, 15);
  EXPECT_EQ(x.write(sends[14], {0x0E}), uint32_t{ERR_OK});  // loaded into buffer 1
  EXPECT_TRUE(x.m.buffer(0, 1).busy);
  x.run_until(1'000'000);
  EXPECT_EQ(x.write(sends[1], {0x01}), uint32_t{ERR_OK});  // cached in buffer 2
  x.run_until(2'000'000);
  EXPECT_EQ(x.write(sends[0], {0x00}), uint32_t{ERR_OK});  // buffer 1 holds 10Eh: loaded again
  x.run_until(3'000'000);
  EXPECT_EQ(x.write(sends[0], {0x10}), uint32_t{ERR_OK});  // cached now
  x.run_until(4'000'000);
  const std::vector<std::pair<Frame, int64_t>> expected{{data_frame(0x10E, {0x0E}), 5'000},
                                                        {data_frame(0x101, {0x01}), 1'000'000},
                                                        {data_frame(0x100, {0x00}), 2'005'000},
                                                        {data_frame(0x100, {0x10}), 3'000'000}};
  ASSERT_EQ(x.peer.log.received.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(x.peer.log.received[k].frame, expected[k].first) << k;
    EXPECT_EQ(x.peer.log.received[k].at, expected[k].second + frame_ns(expected[k].first)) << k;
  }
  EXPECT_EQ(x.m.buffer(0, 1).id, 0x100u);
  EXPECT_EQ(x.m.buffer(0, 2).id, 0x101u);
}

TEST(XcanBuffers, AFullFifoRefusesFurtherRequests) {
  Xcan x;
  x.bus_control(1);  // interface 1 is alone: no transmission ever ends, the buffers stay busy
  std::vector<ChannelHandle> h;
  for (ULONG k = 0; k < 14 + XcanModule::kFifoDepth + 1; ++k) {
    h.push_back(x.open(Xcan::cps(DEVICE_BUS_OUT, 0x100 + k, 0, 0, 1)));
  }
  for (std::size_t k = 0; k < 14 + XcanModule::kFifoDepth; ++k) {
    EXPECT_EQ(x.write(h[k], {0x01}), uint32_t{ERR_OK}) << k;
  }
  EXPECT_EQ(x.m.fifo_size(1), XcanModule::kFifoDepth);
  EXPECT_EQ(x.write(h.back(), {0x01}), uint32_t{ERR_XCAN_FIFO_FULL});
}

TEST(XcanBuffers, MixedFormatObjectsOfBothWidthsShareAnInterface) {
  Xcan x;
  XCAN_BITPARAMS p = testing::params_500k();
  p.MsgFormat = XCAN_MIXED_FORMAT;
  x.bus_control(0, p);
  const ChannelHandle std_out = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123));
  const ChannelHandle ext_out = x.open(Xcan::cps(DEVICE_BUS_OUT, 0x123, XCAN_29BIT_ID));
  const ChannelHandle ext_in = x.open(Xcan::cps(DEVICE_BUS_IN, 0x1ABCDE, XCAN_29BIT_ID));
  EXPECT_EQ(x.m.object_count(0), 3u);  // 123h in 11 and in 29 bits are two objects
  x.write(std_out, {0x01});
  x.write(ext_out, {0x02});
  x.peer.send(data_frame(0x1ABCDE, {0x03}, true));
  // The 11-bit frame with the 29-bit identifier's base (1ABCDEh >> 18 = 6h): the object's XTD
  // tells the formats apart, so nobody takes it.
  x.peer.send(data_frame(0x006, {0x04}));
  x.run_until(2'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 2u);
  EXPECT_EQ(x.peer.log.received[0].frame, data_frame(0x123, {0x01}));  // lower buffer first
  EXPECT_EQ(x.peer.log.received[1].frame, data_frame(0x123, {0x02}, true));
  EXPECT_EQ(x.read(ext_in), (std::vector<uint8_t>{0x03}));
}

TEST(XcanBuffers, TheGeneralIdChannelWithNoIntWaitsForEachMessage) {
  Xcan x;
  x.bus_control();
  EXPECT_EQ(x.m.open_channel(
                   Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE | XCAN_NO_INT, 0), true)
                .error(),
            uint32_t{ERR_XCAN_INVALID_CPS});  // «1 ... 65535»
  const ChannelHandle g =
      x.open(Xcan::cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE | XCAN_NO_INT, 5000));
  XCAN_MESSAGE msg{};
  msg.ulCanId = 0x7AB;
  msg.usDataSize = 1;
  const Reply r = x.m.write_block(g, testing::bytes(msg));
  ASSERT_TRUE(r.pending.has_value());
  x.run_until(1'000'000);
  ASSERT_EQ(x.sink.completions.size(), 1u);
  EXPECT_EQ(x.sink.completions[0].error, uint32_t{ERR_OK});
  EXPECT_EQ(x.sink.completions[0].at.ns(), frame_ns(data_frame(0x7AB, {0})));
  EXPECT_TRUE(x.sink.callbacks.empty());
  EXPECT_EQ(x.m.info(g, INFO_XCAN_MSG_COUNT).value(), 1u);
}

}  // namespace
}  // namespace canemu::model::sorcus
