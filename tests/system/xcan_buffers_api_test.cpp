// The X-CAN-2i MDD's buffer manager through libxcan.so against a real canemud, in stepped time:
// twenty objects on one interface (exclusive buffers, the temporary pool, the driver FIFO) and
// the acceptance filter of buffer 15 with the manual's examples 1 and 2 (digest §1.5), every
// 11-bit identifier sent by the IXXAT adapter "alpha" through the VCI C API.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <vector>

#include "vcinpl.h"
#include "xcan.h"
#include "xcan_test_support.hpp"

namespace canemu::testing {
namespace {

// Channels `first`, `first + 1`, ... of one kind on interface 0, with direct callbacks (they
// have run by the time a later service of this program returns).
std::vector<MAX_HANDLE> open_many(const XcanDaemon& x, USHORT device, ULONG first, int count,
                                  USHORT flags = 0) {
  std::vector<MAX_HANDLE> out;
  for (int k = 0; k < count; ++k) {
    out.push_back(
        x.open(cps(device, first + static_cast<ULONG>(k), flags | _CP_SYNC_CALLBACK), record));
  }
  return out;
}

// The callbacks so far, once a service of the bus-control channel `bus` has answered (so every
// direct callback of what happened before has run), and forgets them.
std::vector<Seen> take_seen(MAX_HANDLE bus) {
  ULONG state = 0;
  EXPECT_EQ(max_channel_info(bus, INFO_DEVICE, &state), ERR_OK);
  std::lock_guard lock(g_mutex);
  std::vector<Seen> out;
  out.swap(g_seen);
  return out;
}

ULONG msg_count(MAX_HANDLE channel) {
  ULONG count = 0;
  EXPECT_EQ(max_channel_info(channel, INFO_XCAN_MSG_COUNT, &count), ERR_OK);
  return count;
}

// 3 objects with exclusive buffers (010h..012h), 15 active send objects (100h..10Eh) and the
// passive receive objects 03h and 07h: 20 objects. The exclusive ones keep buffers 1..3, the
// other 11 of 1..14 are the temporary pool, the two passive receive objects share buffer 15.
TEST(XcanBuffersApi, TwentyObjectsUseTheTemporaryBuffersAndTheDriverFifo) {
  XcanDaemon x;
  Adapter alpha("alpha");
  const auto excl = open_many(x, DEVICE_BUS_OUT, 0x010, 3, XCAN_EXCL_BUFFER);
  const auto sends = open_many(x, DEVICE_BUS_OUT, 0x100, 15);
  auto receives = open_many(x, DEVICE_BUS_IN, 0x003, 1);
  receives.push_back(open_many(x, DEVICE_BUS_IN, 0x007, 1)[0]);
  step_ns(1'000'000);

  // All at once at 1 ms: the exclusive object, then 15 requests for 11 temporary buffers; the
  // last four wait in the driver FIFO, which holds the object: 10Eh's second write changes the
  // data it will send, and it sends once.
  ULONG size = 1;
  const uint8_t e0 = 0xE0;
  ASSERT_EQ(max_write_channel_block(excl[0], &size, &e0), ERR_OK);
  for (std::size_t k = 0; k < sends.size(); ++k) {
    const auto b = static_cast<uint8_t>(k);
    ASSERT_EQ(max_write_channel_block(sends[k], &size, &b), ERR_OK);
  }
  const uint8_t ee = 0xEE;
  ASSERT_EQ(max_write_channel_block(sends[14], &size, &ee), ERR_OK);
  step_ns(20'000'000);

  // Lowest buffer first: 1, then 4. When a temporary buffer's frame ends, the 82527 has already
  // chosen the next lowest buffer's request; the FIFO's head, loaded into the freed buffer at
  // that instant, goes after it: 100h (buffer 4), 101h (5), then the FIFO's four alternate in
  // buffers 4 and 5 before 102h..10Ah (buffers 6..14).
  struct Expected {
    uint32_t id;
    uint8_t byte;
  };
  std::vector<Expected> expected{{0x010, 0xE0}, {0x100, 0}, {0x101, 1}};
  for (uint8_t k = 11; k <= 13; ++k) {
    expected.push_back({0x100u + k, k});
  }
  expected.push_back({0x10E, 0xEE});
  for (uint8_t k = 2; k <= 10; ++k) {
    expected.push_back({0x100u + k, k});
  }
  const auto got = alpha.frames();
  ASSERT_EQ(got.size(), expected.size());
  int64_t end_us = 1000;
  for (std::size_t k = 0; k < expected.size(); ++k) {
    end_us += ((k == 0 ? 0 : 3) + bits_of(expected[k].id, {expected[k].byte})) * kBitUs2;
    EXPECT_EQ(got[k].dwMsgId, expected[k].id) << k;
    EXPECT_EQ(got[k].uMsgInfo.Bits.dlc, 1u) << k;
    EXPECT_EQ(got[k].abData[0], expected[k].byte) << k;
    EXPECT_EQ(got[k].dwTime, static_cast<UINT32>(end_us)) << k;
  }
  // One callback per frame, after its acknowledged transmission, in the same order.
  std::map<uint32_t, MAX_HANDLE> channel_of{{0x010, excl[0]}};
  for (std::size_t k = 0; k < sends.size(); ++k) {
    channel_of[0x100 + static_cast<uint32_t>(k)] = sends[k];
  }
  const auto seen = take_seen(x.bus);
  ASSERT_EQ(seen.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(seen[k].channel, channel_of[expected[k].id]) << k;
    EXPECT_TRUE(seen[k].bytes.empty()) << k;
  }
  EXPECT_EQ(msg_count(sends[14]), 1u);  // two writes, one frame
  EXPECT_EQ(msg_count(sends[0]), 1u);
  EXPECT_EQ(msg_count(excl[1]), 0u);

  // The FIFO is empty again: a second round goes in buffer order, each object from the buffer
  // that still caches it (buffers 4 and 5 now hold 10Dh and 10Eh, 6..14 still 102h..10Ah).
  for (const std::size_t k : {std::size_t{14}, std::size_t{2}}) {
    const auto b = static_cast<uint8_t>(0x40 + k);
    ASSERT_EQ(max_write_channel_block(sends[k], &size, &b), ERR_OK);
  }
  step_ns(2'000'000);
  const auto again = alpha.frames();
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(again[0].dwMsgId, 0x10Eu);  // buffer 5 before buffer 6
  EXPECT_EQ(again[0].abData[0], 0x4E);
  EXPECT_EQ(again[1].dwMsgId, 0x102u);
  EXPECT_EQ(again[1].abData[0], 0x42);
  take_seen(x.bus);

  // Buffer 15 with 03h and 07h: 03h and 07h reach their objects, 05h and 0Bh nothing.
  for (const uint32_t id : {0x03u, 0x05u, 0x07u, 0x0Bu}) {
    alpha.post(data(id, {static_cast<uint8_t>(id)}));
  }
  step_ns(2'000'000);
  const auto received = take_seen(x.bus);
  ASSERT_EQ(received.size(), 2u);
  EXPECT_EQ(received[0].channel, receives[0]);
  EXPECT_EQ(received[0].bytes, (std::vector<uint8_t>{0x03}));
  EXPECT_EQ(received[1].channel, receives[1]);
  EXPECT_EQ(received[1].bytes, (std::vector<uint8_t>{0x07}));
}

// The manual's set-up for its examples: 13 active send objects and two passive receive objects
// `a` and `b` (15 objects, so the two share buffer 15), and the acceptance-filter device with
// the automatic ID. alpha sends every 11-bit identifier once, one byte each (the ID's low
// byte). Returns the identifiers that passed buffer 15, in order: those of the receive
// objects' callbacks and those of the filter device's. Checks the mask the filter reads back.
std::vector<uint32_t> passed_ids(uint32_t a, uint32_t b, ULONG mask) {
  XcanDaemon x;
  Adapter alpha("alpha");
  open_many(x, DEVICE_BUS_OUT, 0x100, 13);
  const auto rx_a = open_many(x, DEVICE_BUS_IN, a, 1)[0];
  const auto rx_b = open_many(x, DEVICE_BUS_IN, b, 1)[0];
  CPS_XCAN filter_cps = cps(DEVICE_CTRL, XCAN_AUTO_ID, _CP_SYNC_CALLBACK);
  filter_cps.usIndexFirst = filter_cps.usIndexLast = 0;
  const MAX_HANDLE filter = x.open(filter_cps, record);
  ULONG read_back = 0;
  EXPECT_EQ(max_read_channel_ulong(filter, &read_back), ERR_OK);
  EXPECT_EQ(read_back, mask);
  step_ns(1'000'000);
  // 64 frames (alpha's transmit FIFO) per 10 ms: about 7.4 ms on the wire.
  for (uint32_t first = 0; first < 0x800; first += 64) {
    for (uint32_t id = first; id < first + 64; ++id) {
      alpha.post(data(id, {static_cast<uint8_t>(id)}));
    }
    step_ns(10'000'000);
  }
  auto watcher = testing::connect(x.vci.daemon, "watcher");
  EXPECT_EQ(testing::status(watcher).buses[0].frames, 0x800u);  // every one went
  const auto seen = take_seen(x.bus);
  std::vector<uint32_t> ids;
  for (const Seen& s : seen) {
    if (s.channel == filter) {
      const XCAN_MESSAGE m = message_of(s);
      EXPECT_EQ(m.usDataSize, 1u);
      EXPECT_EQ(m.usFlags, 0u);
      EXPECT_EQ(m.aucData[0], static_cast<uint8_t>(m.ulCanId));
      ids.push_back(m.ulCanId);
    } else {
      EXPECT_TRUE(s.channel == rx_a || s.channel == rx_b);
      EXPECT_EQ(s.bytes.size(), 1u);
      const uint32_t id = s.channel == rx_a ? a : b;
      EXPECT_EQ(s.bytes.at(0), static_cast<uint8_t>(id));
      ids.push_back(id);
    }
  }
  EXPECT_EQ(msg_count(rx_a), 1u);
  EXPECT_EQ(msg_count(rx_b), 1u);
  return ids;
}

// Example 1: IDs 03h and 07h; acceptance mask 7FBh, ID mask 003h: only 03h and 07h pass.
TEST(XcanBuffersApi, FilterExample1PassesOnlyThreeAndSevenOfAllIdentifiers) {
  EXPECT_EQ(passed_ids(0x03, 0x07, 0x7FB), (std::vector<uint32_t>{0x03, 0x07}));
}

// Example 2: IDs 20h and 07h; acceptance mask 7D8h, ID mask 000h: 00h..07h and 20h..27h pass,
// «weitere 14 unerwünschte IDs» that reach the filter device's callback.
TEST(XcanBuffersApi, FilterExample2PassesZeroToSevenAndTwentyToTwentySevenOfAllIdentifiers) {
  std::vector<uint32_t> expected;
  for (uint32_t id = 0x00; id <= 0x07; ++id) {
    expected.push_back(id);
  }
  for (uint32_t id = 0x20; id <= 0x27; ++id) {
    expected.push_back(id);
  }
  EXPECT_EQ(passed_ids(0x20, 0x07, 0x7D8), expected);
}

}  // namespace
}  // namespace canemu::testing
