// The longest and shortest frames that really exist, found by exhaustive search, and the
// encoder's agreement with them.
//
// The kernel's worst case (L + (L - 1) / 4) assumes that every run between two stuff bits can be
// four bits long. The fixed control bits (RTR, IDE, FDF, r0) and, for classic frames, the CRC
// make some of those runs impossible, so the true maximum is lower. This test finds it by
// dynamic programming over every frame of a format (state: level and length of the current run,
// plus the CRC-15 register for classic frames, whose CRC sequence is stuffed too), rebuilds the
// frame that reaches it, encodes that frame and checks the encoder counts the same stuff bits.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace canemu::model {
namespace {

constexpr uint32_t kCrc15Poly = 0x4599;

uint32_t crc15_step(uint32_t crc, int bit) {
  const bool fb = (bit != 0) ^ ((crc >> 14) & 1u);
  crc = (crc << 1) & 0x7FFF;
  return fb ? crc ^ kCrc15Poly : crc;
}

// Inverse of crc15_step for a known input bit (the polynomial is odd, so the feedback shows in
// bit 0 of the result).
uint32_t crc15_unstep(uint32_t crc, int bit) {
  const uint32_t fb = crc & 1u;
  const uint32_t low = ((fb ? crc ^ kCrc15Poly : crc) >> 1) & 0x3FFF;
  return ((fb ^ static_cast<uint32_t>(bit)) << 14) | low;
}

// One bit of the destuffed stream: 0, 1, or free (-1).
using Layout = std::vector<int8_t>;

void put(Layout& l, int value, int count) {
  l.insert(l.end(), count, static_cast<int8_t>(value));
}

struct Format {
  bool fd;
  bool extended;
  std::size_t length;  // payload bytes
};

// The destuffed bits from SOF to the end of the data field, with what each may be. The DLC is
// free where several codes give the same length (classic 8 bytes: 8..15).
Layout layout_of(const Format& f) {
  Layout l;
  put(l, 0, 1);    // SOF
  put(l, -1, 11);  // base identifier
  if (f.extended) {
    put(l, 1, 2);             // SRR, IDE
    put(l, -1, 18);           // extended identifier
    put(l, 0, 1);             // RTR (data frame) / RRS
    put(l, f.fd ? 1 : 0, 1);  // FDF (r1)
    put(l, 0, 1);             // r0 / res
  } else {
    put(l, 0, 2);             // RTR / RRS, IDE
    put(l, f.fd ? 1 : 0, 1);  // FDF (r0)
    if (f.fd) {
      put(l, 0, 1);  // res
    }
  }
  if (f.fd) {
    put(l, -1, 2);  // BRS, ESI
  }
  const auto dlc = *length_to_dlc(f.length, f.fd);
  for (int i = 3; i >= 0; --i) {
    const bool free_bit = !f.fd && f.length == 8 && i < 3;
    put(l, free_bit ? -1 : (dlc >> i) & 1, 1);
  }
  put(l, -1, static_cast<int>(8 * f.length));
  return l;
}

struct Optimum {
  int stuff_bits = -1;
  std::vector<int> bits;  // destuffed SOF..data of a frame reaching it
};

// Stuff bits in the classic CRC sequence `crc`, entering with a run of `run` bits at `last`.
int crc_tail_stuff(uint32_t crc, int last, int run) {
  int count = 0;
  for (int i = 14; i >= 0; --i) {
    const int b = (crc >> i) & 1;
    run = b == last ? run + 1 : 1;
    last = b;
    if (run == 5) {
      ++count;
      last ^= 1;
      run = 1;
    }
  }
  return count;
}

// Exhaustive search. State after each bit: level of the current run, its length 1..4 and (for
// classic frames) the CRC register. `maximise` picks the most stuff bits, else the fewest.
Optimum search(const Format& f, bool maximise) {
  const Layout layout = layout_of(f);
  const bool track_crc = !f.fd;
  const uint32_t crc_states = track_crc ? 0x8000 : 1;
  const std::size_t states = crc_states * 8;
  auto index = [](uint32_t crc, int last, int run) {
    return (static_cast<std::size_t>(crc) << 3) | (static_cast<std::size_t>(last) << 2) |
           static_cast<std::size_t>(run - 1);
  };
  constexpr int16_t kNone = INT16_MIN;
  std::vector<int16_t> cur(states, kNone), next(states, kNone);
  // Back-pointers: per bit and state, the bit chosen and the previous run's level and length.
  std::vector<std::vector<uint8_t>> back(layout.size(), std::vector<uint8_t>(states, 0));

  cur[index(0, 0, 1)] = 0;  // after SOF: dominant run of 1, CRC-15 of a 0 bit is 0
  for (std::size_t pos = 1; pos < layout.size(); ++pos) {
    std::fill(next.begin(), next.end(), kNone);
    const bool last_bit = pos + 1 == layout.size();
    for (std::size_t s = 0; s < states; ++s) {
      if (cur[s] == kNone) {
        continue;
      }
      const uint32_t crc = static_cast<uint32_t>(s >> 3);
      const int last = static_cast<int>((s >> 2) & 1);
      const int run = static_cast<int>(s & 3) + 1;
      for (int b = 0; b <= 1; ++b) {
        if (layout[pos] >= 0 && layout[pos] != b) {
          continue;
        }
        int nrun = b == last ? run + 1 : 1;
        int nlast = b;
        int gained = 0;
        // CAN FD: no dynamic stuff bit after the last data bit (the fixed one replaces it).
        if (nrun == 5 && !(f.fd && last_bit)) {
          gained = 1;
          nlast ^= 1;
          nrun = 1;
        }
        if (nrun == 5) {
          nrun = 4;  // end of an FD stream: the run length no longer matters
        }
        const uint32_t ncrc = track_crc ? crc15_step(crc, b) : 0;
        const std::size_t n = index(ncrc, nlast, nrun);
        const int16_t value = static_cast<int16_t>(cur[s] + gained);
        if (next[n] == kNone || (maximise ? value > next[n] : value < next[n])) {
          next[n] = value;
          back[pos][n] = static_cast<uint8_t>(b | (last << 1) | ((run - 1) << 2));
        }
      }
    }
    std::swap(cur, next);
  }

  Optimum best;
  std::size_t best_state = 0;
  int best_value = 0;
  bool found = false;
  for (std::size_t s = 0; s < states; ++s) {
    if (cur[s] == kNone) {
      continue;
    }
    const int tail =
        track_crc ? crc_tail_stuff(static_cast<uint32_t>(s >> 3), static_cast<int>((s >> 2) & 1),
                                   static_cast<int>(s & 3) + 1)
                  : 0;
    const int value = cur[s] + tail;
    if (!found || (maximise ? value > best_value : value < best_value)) {
      found = true;
      best_value = value;
      best_state = s;
    }
  }
  best.stuff_bits = best_value;
  best.bits.assign(layout.size(), 0);
  std::size_t s = best_state;
  for (std::size_t pos = layout.size() - 1; pos >= 1; --pos) {
    const uint8_t bp = back[pos][s];
    const int b = bp & 1;
    best.bits[pos] = b;
    const uint32_t crc = static_cast<uint32_t>(s >> 3);
    const uint32_t prev_crc = track_crc ? crc15_unstep(crc, b) : 0;
    s = index(prev_crc, (bp >> 1) & 1, ((bp >> 2) & 3) + 1);
  }
  return best;
}

// Rebuilds the frame from its destuffed bits (inverse of layout_of()).
Frame frame_from_bits(const Format& f, const std::vector<int>& bits) {
  std::size_t pos = 1;
  auto take = [&](int n) {
    uint32_t v = 0;
    for (int i = 0; i < n; ++i) {
      v = (v << 1) | static_cast<uint32_t>(bits[pos++]);
    }
    return v;
  };
  FrameSpec spec;
  spec.fd = f.fd;
  spec.extended = f.extended;
  spec.id = take(11);
  if (f.extended) {
    pos += 2;
    spec.id = (spec.id << 18) | take(18);
    pos += 3;
  } else {
    pos += f.fd ? 4 : 3;
  }
  if (f.fd) {
    spec.brs = take(1) != 0;
    spec.esi = take(1) != 0;
  }
  spec.dlc = static_cast<uint8_t>(take(4));
  std::vector<uint8_t> data(f.length);
  for (auto& byte : data) {
    byte = static_cast<uint8_t>(take(8));
  }
  spec.data = data;
  auto frame = Frame::create(spec);
  EXPECT_TRUE(frame.has_value()) << frame.error().message;
  return *frame;
}

struct Case {
  Format format;
  uint32_t kernel_min;  // with intermission
  uint32_t kernel_max;
  uint32_t true_max;  // with intermission: what the search finds (docs/wire-model.md)
};

class MaxStuffing : public ::testing::TestWithParam<Case> {};

TEST_P(MaxStuffing, LongestRealFrameIsFoundEncodedAndWithinTheKernelBound) {
  const Case& c = GetParam();
  const Optimum worst = search(c.format, true);
  const Frame frame = frame_from_bits(c.format, worst.bits);
  const EncodedFrame e = encode(frame);
  EXPECT_EQ(e.dynamic_stuff_bits, worst.stuff_bits);
  EXPECT_EQ(e.length + kIntermissionBits, c.true_max);
  EXPECT_LE(e.length + kIntermissionBits, c.kernel_max);
  EXPECT_EQ(
      frame_length_bound(c.format.fd, c.format.extended, c.format.length, Stuffing::worst_case),
      c.kernel_max);
}

TEST_P(MaxStuffing, ShortestRealFrameHasNoStuffBitAndMatchesTheKernelMinimum) {
  const Case& c = GetParam();
  const Optimum best = search(c.format, false);
  const Frame frame = frame_from_bits(c.format, best.bits);
  const EncodedFrame e = encode(frame);
  EXPECT_EQ(best.stuff_bits, 0);
  EXPECT_EQ(e.dynamic_stuff_bits, 0);
  EXPECT_EQ(e.length + kIntermissionBits, c.kernel_min);
  EXPECT_EQ(frame_length_bound(c.format.fd, c.format.extended, c.format.length, Stuffing::none),
            c.kernel_min);
}

INSTANTIATE_TEST_SUITE_P(KernelTable, MaxStuffing,
                         ::testing::Values(Case{{false, false, 8}, 111, 135, 133},
                                           Case{{false, true, 8}, 131, 160, 159},
                                           Case{{true, false, 64}, 579, 712, 710},
                                           Case{{true, true, 64}, 598, 736, 733}),
                         [](const auto& param_info) {
                           const Format& f = param_info.param.format;
                           return std::string(f.fd ? "Fd" : "Classic") +
                                  (f.extended ? "Extended" : "Standard") +
                                  std::to_string(f.length) + "Bytes";
                         });

}  // namespace
}  // namespace canemu::model
