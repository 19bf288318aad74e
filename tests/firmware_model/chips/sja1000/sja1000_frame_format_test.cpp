// The PeliCAN buffer layout (sja1000_frame_format.cpp): packing and unpacking both formats, the
// data bytes it holds at most, and the packed size read back from the frame information byte.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"
#include "test_controller.hpp"

namespace canemu::model {
namespace {

using namespace sja1000;
using testing::frame;

TEST(Sja1000FrameFormat, PacksAndUnpacksBothFormats) {
  std::array<uint8_t, 13> bytes;
  const Frame ext = frame(0x1ABCDEF0, {1, 2, 3}, true);
  EXPECT_EQ(pack_frame(ext, bytes), 8u);
  EXPECT_EQ(bytes[0], 0x83);
  EXPECT_EQ(bytes[1], 0xD5);  // ID.28-21
  EXPECT_EQ(bytes[4], 0x80);  // ID.4-0 = 10000, RTR 0
  EXPECT_EQ(unpack_frame(bytes.data()), ext);
  FrameSpec s;
  s.id = 0x7FF;
  s.remote = true;
  s.dlc = 4;
  const Frame rtr = *Frame::create(s);
  EXPECT_EQ(pack_frame(rtr, bytes), 3u);
  EXPECT_EQ(bytes[0], 0x44);
  EXPECT_EQ(bytes[2], 0xF0);
  EXPECT_EQ(unpack_frame(bytes.data()), rtr);
}

// The layout holds at most 8 data bytes: a CAN FD frame's are cut there, within the 13 bytes,
// and its DLC above 8 reads back as 8 bytes.
TEST(Sja1000FrameFormat, PacksNoMoreThanEightDataBytes) {
  std::array<uint8_t, 16> bytes;
  bytes.fill(0xEE);
  std::vector<uint8_t> data(64);
  for (std::size_t k = 0; k < data.size(); ++k) {
    data[k] = static_cast<uint8_t>(k + 1);
  }
  const Frame fd = *Frame::fd_frame(0x1ABCDEF0, data, true);
  EXPECT_EQ(pack_frame(fd, bytes.data()), 13u);
  EXPECT_EQ(bytes[0], 0x8F);  // extended, DLC 15
  EXPECT_EQ(bytes[5], 1);
  EXPECT_EQ(bytes[12], 8);
  EXPECT_EQ(bytes[13], 0xEE);  // nothing written past the 13
  EXPECT_EQ(packed_size(bytes[0]), 13u);
}

// What a released message frees in the receive FIFO is read from its frame information byte:
// the size pack_frame() wrote, for every format, RTR bit and DLC (9..15 carry 8 data bytes).
TEST(Sja1000FrameFormat, ThePackedSizeFollowsFromTheFrameInformation) {
  std::array<uint8_t, 13> bytes;
  for (const bool extended : {false, true}) {
    for (const bool remote : {false, true}) {
      for (uint8_t dlc = 0; dlc <= 15; ++dlc) {
        FrameSpec s;
        s.id = 0x123;
        s.extended = extended;
        s.remote = remote;
        s.dlc = dlc;
        const std::vector<uint8_t> data(remote ? 0 : std::min<std::size_t>(dlc, 8), 0xA5);
        s.data = data;
        const Frame f = *Frame::create(s);
        const std::size_t n = pack_frame(f, bytes);
        EXPECT_EQ(packed_size(bytes[0]), n)
            << "ext " << extended << " rtr " << remote << " dlc " << int{dlc};
        EXPECT_EQ(n, (extended ? 5u : 3u) + data.size());
      }
    }
  }
}

}  // namespace
}  // namespace canemu::model
