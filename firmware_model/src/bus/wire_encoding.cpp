#include "canemu/firmware_model/bus/wire_encoding.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

#include "wire_crc.hpp"

namespace canemu::model {

namespace {

using detail::Crc15Wide;
using detail::Crc17;
using detail::Crc21;

uint64_t to_big_endian(uint64_t v) {
  if constexpr (std::endian::native == std::endian::little) {
    return __builtin_bswap64(v);
  }
  return v;
}

// Gray code of the stuff count (0..7) in bits 3..1 and its even parity in bit 0.
constexpr std::array<uint8_t, 8> kStuffCountCode{0x0, 0x3, 0x6, 0x5, 0xC, 0xF, 0xA, 0x9};

// A bit string, first bit in the most significant position of the first word, so that fields
// are appended and runs found with word operations rather than bit by bit. Words past the end
// are not initialised (zeroing them costs more than the encoding): appending assigns a word
// when it starts one, and only bits before `size` are ever read.
struct BitString {
  EncodedFrame::Bits words;
  uint32_t size = 0;

  // Appends the low `count` (1..64) bits of `value`, most significant first.
  void append(uint64_t value, uint32_t count) {
    const uint64_t v = value << (64 - count);
    const uint32_t off = size & 63;
    const std::size_t w = size >> 6;
    if (off == 0) {
      words[w] = v;
    } else {
      words[w] |= v >> off;
      if (off + count > 64) {
        words[w + 1] = v << (64 - off);
      }
    }
    size += count;
    // Keep the bits after the end of the last word zero, so the next append can OR into it.
    if ((size & 63) != 0) {
      words[size >> 6] &= ~uint64_t{0} << (64 - (size & 63));
    }
  }
  void append_bit(bool bit) { append(bit ? 1u : 0u, 1); }
  // Appends zeros up to `new_size`.
  void pad_to(uint32_t new_size) {
    while (size < new_size) {
      append(0, new_size - size < 64 ? new_size - size : 64);
    }
  }
  void pop_back() {
    --size;
    words[size >> 6] &= ~(uint64_t{1} << (63 - (size & 63)));
  }

  bool bit(uint32_t i) const { return (words[i >> 6] >> (63 - (i & 63))) & 1u; }

  // Bits i..i+63 (i < size), most significant first; bits past the end read as 0 once sealed.
  uint64_t window(uint32_t i) const {
    const std::size_t w = i >> 6;
    const uint32_t off = i & 63;
    if (off == 0) {
      return words[w];
    }
    return (words[w] << off) | (words[w + 1] >> (64 - off));
  }

  // Zeroes the word a window at the last bit may read past the end.
  void seal() {
    const std::size_t next = (size & 63) == 0 ? size >> 6 : (size >> 6) + 1;
    if (next < words.size()) {
      words[next] = 0;
    }
  }

  // The 8 bits i..i+7 (i + 8 <= size).
  uint32_t byte_at(uint32_t i) const {
    const std::size_t w = i >> 6;
    const uint32_t off = i & 63;
    uint64_t v = words[w] << off;
    if (off > 56) {
      v |= words[w + 1] >> (64 - off);
    }
    return static_cast<uint32_t>(v >> 56);
  }

  // Copies the used words into `out`; words after them keep what they had.
  void store(EncodedFrame::Bits& out) const {
    const std::size_t used = (size + 63) / 64;
    for (std::size_t w = 0; w < used; ++w) {
      out[w] = words[w];
    }
  }
};

// A CAN FD frame's SOF..data, destuffed (field positions: EncodedFrame::fields()). Classic
// frames are put together in registers: classic_header_and_data.
void fd_header_and_data(const Frame& frame, BitString& d) {
  // RRS is always dominant: CAN FD has no remote frames.
  if (frame.extended()) {
    // SOF, base ID, SRR, IDE, extended ID, RRS, FDF, res
    d.append((uint64_t{frame.id() >> 18} << 2) | 0x3u, 14);  // SOF (0), ID-28..18, SRR, IDE
    d.append((uint64_t{frame.id() & 0x3FFFF} << 3) | 0x2u, 21);
  } else {
    // SOF, ID, RRS, IDE, FDF, res
    d.append((uint64_t{frame.id()} << 3) | 0x1u, 15);
    d.append(0, 1);
  }
  d.append((frame.brs() ? 2u : 0u) | (frame.esi() ? 1u : 0u), 2);
  d.append(frame.dlc(), 4);
  const auto data = frame.data();
  std::size_t i = 0;
  for (; i + 8 <= data.size(); i += 8) {
    uint64_t v;
    std::memcpy(&v, data.data() + i, 8);
    d.append(to_big_endian(v), 64);
  }
  for (; i < data.size(); ++i) {
    d.append(data[i], 8);
  }
}

// Dynamic bit stuffing of `d` into the frame bits `s`, marking stuff bits in `m`: after five
// equal bits a complementary bit, which starts the next run. `last_may_stuff` is false for
// CAN FD, where no dynamic stuff bit follows the last bit before the CRC field. (Classic frames
// are stuffed in registers: stuff_classic.)
//
// Runs are found a 64-bit window at a time (bit j equals bit j + 1 for four j in a row), and the
// bits between two stuff bits are copied as one block, so the cost grows with the number of
// stuff bits, not with the number of bits.
// Frame positions of two destuffed bits, worked out while stuffing.
struct Probes {
  std::array<uint32_t, 2> destuffed{UINT32_MAX, UINT32_MAX};
  std::array<uint16_t, 2> stuffed{};
};

// Wire bits and their stuff marks, gathered in registers and stored a word at a time.
struct WireWriter {
  EncodedFrame::Bits& bits;
  EncodedFrame::Bits& marks;
  std::size_t w = 0;
  uint64_t acc_bits = 0;
  uint64_t acc_marks = 0;
  uint32_t used = 0;  // bits in the accumulators, from the top

  // Appends `count` (1..64) bits and as many stuff marks; neither value has bits above count.
  void put(uint64_t v, uint64_t mark, uint32_t count) {
    const uint32_t space = 64 - used;
    if (count < space) {
      acc_bits |= v << (space - count);
      acc_marks |= mark << (space - count);
      used += count;
      return;
    }
    const uint32_t rest = count - space;
    bits[w] = acc_bits | (v >> rest);
    marks[w] = acc_marks | (mark >> rest);
    ++w;
    acc_bits = rest != 0 ? v << (64 - rest) : 0;
    acc_marks = rest != 0 ? mark << (64 - rest) : 0;
    used = rest;
  }
  // Appends `count` bits of `from` from bit `begin` on, unmarked.
  template <class Bits>
  void copy(const Bits& from, uint32_t begin, uint32_t count) {
    while (count > 0) {
      const uint32_t c = count < 64 ? count : 64;
      put(from.window(begin) >> (64 - c), 0, c);
      begin += c;
      count -= c;
    }
  }
  uint32_t size() const { return static_cast<uint32_t>(w * 64 + used); }
  // Stores what the accumulators hold.
  void close() {
    if (used != 0) {
      bits[w] = acc_bits;
      marks[w] = acc_marks;
    }
  }
  void close(BitString& a, BitString& b) {
    close();
    a.size = b.size = size();
  }
};

template <class Bits>
void stuff(Bits& d, bool last_may_stuff, BitString& s, BitString& m, Probes& probes) {
  d.seal();
  WireWriter out{s.words, m.words};  // both outputs grow in step
  const uint32_t n = d.size;
  const uint32_t last_allowed = last_may_stuff ? n - 1 : n - 2;  // highest bit a stuff may follow
  uint32_t pos = 0;                                              // next destuffed bit to copy
  uint32_t count = 0;                                            // stuff bits so far
  auto settle = [&](uint32_t upto) {  // probes at or before destuffed bit `upto`
    for (std::size_t k = 0; k < 2; ++k) {
      if (probes.destuffed[k] <= upto) {
        probes.stuffed[k] = static_cast<uint16_t>(probes.destuffed[k] + count);
        probes.destuffed[k] = UINT32_MAX;
      }
    }
  };
  while (true) {
    uint32_t p = UINT32_MAX;  // the destuffed bit after which the next stuff bit goes
    if (pos > 0 && pos + 3 < n) {
      // Right after a stuff bit, that bit is the first of the run: four more like it suffice.
      const uint64_t four = d.window(pos) >> 60;
      if (four == (d.bit(pos - 1) ? 0x0u : 0xFu)) {
        p = pos + 3;
      }
    }
    for (uint32_t i = pos; p == UINT32_MAX && i + 4 < n; i += 60) {
      const uint64_t x = d.window(i);
      const uint64_t eq = ~(x ^ (x << 1));  // bit 63 - j: bit j equals bit j + 1
      const uint64_t runs = eq & (eq << 1) & (eq << 2) & (eq << 3) & (~uint64_t{0} << 4);
      if (runs != 0) {
        p = i + static_cast<uint32_t>(__builtin_clzll(runs)) + 4;
      }
    }
    if (p >= n || p > last_allowed) {
      out.copy(d, pos, n - pos);
      break;
    }
    settle(p);
    out.copy(d, pos, p + 1 - pos);
    out.put(d.bit(p) ? 0u : 1u, 1u, 1);
    ++count;
    pos = p + 1;
  }
  settle(UINT32_MAX - 1);
  out.close(s, m);
}

// CRC delimiter, ACK slot (sent recessive), ACK delimiter and EOF: ten recessive bits.
void finish(BitString& s, BitString& m, EncodedFrame& out) {
  out.crc_delimiter_index = static_cast<uint16_t>(s.size);
  s.append(0x3FF, 3 + kEofBits);
  out.length = static_cast<uint16_t>(s.size);
  s.store(out.level);
  m.pad_to(s.size);
  m.store(out.stuff);
}

// The destuffed positions of the bits the bus engine needs on every frame: the end of the
// arbitration field and BRS. Field order (fd_header_and_data): standard SOF, ID, RTR/RRS,
// IDE, FDF, [res, BRS]; extended SOF, ID, SRR, IDE, ID-ext, RTR/RRS, FDF, res, [BRS].
Probes probes_for(const EncodedFrame& out) {
  Probes p;
  p.destuffed[0] = out.extended ? 33 : 13;
  if (out.fd) {
    p.destuffed[1] = out.extended ? 35 : 16;
  }
  return p;
}

void apply(const Probes& p, EncodedFrame& out) {
  out.arbitration_end = p.stuffed[0];
  if (out.fd) {
    out.brs_index = p.stuffed[1];
  }
}

// A classic frame's destuffed bits SOF..data, first bit at bit 127: at most 39 + 64 bits. Field
// order as fd_header_and_data's, without the FD bits: standard SOF, ID, RTR, IDE, r0,
// DLC; extended SOF, ID-28..18, SRR, IDE, ID-17..0, RTR, r1, r0, DLC. Returns their number.
[[gnu::always_inline]] inline uint32_t classic_header_and_data(const Frame& frame, uint128& x) {
  const uint64_t rtr = frame.remote() ? 1u : 0u;
  const uint64_t id = frame.id();
  const uint32_t length = static_cast<uint32_t>(frame.length());
  uint64_t data = 0;
  if (length != 0) {
    std::memcpy(&data, frame.data().data(), 8);  // the frame keeps 64 bytes, zero or not
    data = to_big_endian(data) & (~uint64_t{0} << (64 - 8 * length));
  }
  if (frame.extended()) {
    const uint64_t head =
        ((((id >> 18) << 2) | 0x3u) << 25) | ((id & 0x3FFFF) << 7) | (rtr << 6) | frame.dlc();
    x = (uint128{head} << 89) | (uint128{data} << 25);
    return 39 + 8 * length;
  }
  const uint64_t head = (id << 7) | (rtr << 6) | frame.dlc();
  x = (uint128{head} << 109) | (uint128{data} << 45);
  return 19 + 8 * length;
}

// Bit `i` (0..127, from the top) of the two words `hi`, `lo`.
inline uint64_t bit_of(uint64_t hi, uint64_t lo, uint32_t i) {
  return i < 64 ? (hi >> (63 - i)) & 1u : (lo >> (127 - i)) & 1u;
}

// The first set bit at index `from` (0..127) or later of `hi`, `lo`; 128 if none.
inline uint32_t next_set(uint64_t hi, uint64_t lo, uint32_t from) {
  if (from < 64) {
    const uint64_t m = hi & (~uint64_t{0} >> from);
    if (m != 0) {
      return static_cast<uint32_t>(__builtin_clzll(m));
    }
    return lo != 0 ? 64 + static_cast<uint32_t>(__builtin_clzll(lo)) : 128;
  }
  const uint64_t m = lo & (~uint64_t{0} >> (from - 64));
  return m != 0 ? 64 + static_cast<uint32_t>(__builtin_clzll(m)) : 128;
}

// For each index in a word (first bit at the top): the bits before it, and its own bit.
constexpr std::array<uint64_t, 64> kBitsBefore = [] {
  std::array<uint64_t, 64> t{};
  for (uint32_t i = 1; i < 64; ++i) {
    t[i] = ~(~uint64_t{0} >> i);
  }
  return t;
}();
constexpr std::array<uint64_t, 64> kBitAt = [] {
  std::array<uint64_t, 64> t{};
  for (uint32_t i = 0; i < 64; ++i) {
    t[i] = uint64_t{1} << (63 - i);
  }
  return t;
}();

// Bits i..i+63 (i > 0) of the 128 bits `hi`, `lo` (first bit at the top of `hi`); bits past
// their end read as 0.
inline uint64_t window_of(uint64_t hi, uint64_t lo, uint32_t i) {
  if (i < 64) {
    return (hi << i) | (lo >> (64 - i));
  }
  return i < 128 ? lo << (i - 64) : 0;
}

// Dynamic stuffing of a classic frame's `n` destuffed bits `x` (SOF..CRC, zeros after them)
// into the words of `wire` and `marks` that the frame uses; returns the number of stuff bits.
// Where five equal destuffed bits in a row begin is found for the whole frame at once (bit j
// equals bit j + 1 for four j in a row). A stuff bit, the complement of the bit p before it,
// starts the next run: if the four bits after p are all its like, the next stuff bit follows
// them (found at once too: bit p differs from bit p + 1, which the next three equal); otherwise
// the next one ends the first run of five that begins after p. The wire is written a word at a
// time, left to right: a word starts as the 64 destuffed bits that land there past the stuff
// bits before it, and each stuff bit inside it is inserted into that one word (the bit it
// pushes out of the word's end is read again for the next word). So the work grows with the
// number of stuff bits, a few per frame, and a frame with many (long runs of equal bits, zero
// bytes) pays a handful of instructions for each.
//
// With kWhole false only the first word (and its marks) is written: the stuff bits past it are
// counted, not inserted (encode_head).
template <bool kWhole>
uint32_t stuff_classic(uint128 x, uint32_t n, EncodedFrame::Bits& wire, EncodedFrame::Bits& marks) {
  const uint128 eq = ~(x ^ (x << 1));  // bit 127 - j: bit j equals bit j + 1
  // Only what begins at j <= n - 5 lies inside the frame.
  const uint128 inside = ~uint128{0} << (128 - (n - 4));
  const uint128 four = (eq << 1) & (eq << 2) & (eq << 3) & inside;
  const uint128 runs = eq & four;    // bits j..j+4 equal
  const uint128 after = ~eq & four;  // bit j differs from bits j+1..j+4, which are equal
  const auto xh = static_cast<uint64_t>(x >> 64);
  const auto xl = static_cast<uint64_t>(x);
  const auto rh = static_cast<uint64_t>(runs >> 64);
  const auto rl = static_cast<uint64_t>(runs);
  const auto ah = static_cast<uint64_t>(after >> 64);
  const auto al = static_cast<uint64_t>(after);
  // The word being written and its marks, in registers; `end` is the wire index after it.
  uint64_t cur = xh;  // word 0 begins with destuffed bit 0
  uint64_t cur_marks = 0;
  uint32_t end = 64;
  uint32_t count = 0;  // stuff bits so far
  uint64_t last = 0;   // the last bit of the word before, at the top
  auto store = [&] {
    wire[end / 64 - 1] = cur;
    marks[end / 64 - 1] = cur_marks;
  };
  auto next_word = [&] {
    // The next word begins at wire index `end`, destuffed index `end - count`.
    store();
    last = cur << 63;
    cur = window_of(xh, xl, end - count);
    cur_marks = 0;
    end += 64;
  };
  uint32_t p = next_set(rh, rl, 0) + 4;  // the destuffed bit the next stuff bit follows
  while (p < 128) {
    const uint32_t q = p + 1 + count;  // the stuff bit's index on the wire
    if constexpr (kWhole) {
      while (q >= end) {
        next_word();
      }
    }
    if (kWhole || q < 64) {
      // The stuff bit goes in at `off`: the bits from there on move one place on, and the bit
      // before it is copied there and flipped (at the word's start, the word before's last).
      const uint32_t off = q & 63;
      const uint64_t keep = kBitsBefore[off];
      const uint64_t at = kBitAt[off];
      const uint64_t moved = (cur & ~(keep << 1)) >> 1;
      cur = ((cur & keep) | moved | (off == 0 ? last : 0)) ^ at;
      cur_marks |= at;
    }
    ++count;
    p = bit_of(ah, al, p) != 0 ? p + 4 : next_set(rh, rl, p + 1) + 4;
  }
  // The words the frame uses, its ten recessive bits after the CRC included; the words after
  // them keep what they held (bits at and after the frame's length are unspecified).
  if constexpr (kWhole) {
    while (end < n + count + 3 + kEofBits) {
      next_word();
    }
  }
  store();
  return count;
}

template <bool kWhole>
void encode_classic(const Frame& frame, EncodedFrame& out) {
  uint128 x = 0;
  const uint32_t head = classic_header_and_data(frame, x);
  // CRC-15 over the destuffed bits; the CRC sequence is then stuffed like the rest.
  const uint32_t crc = Crc15Wide::over(x, head);
  x |= uint128{crc} << (113 - head);
  const uint32_t n = head + 15;

  const uint32_t stuffed = n + stuff_classic<kWhole>(x, n, out.level, out.stuff);
  // CRC delimiter, ACK slot (sent recessive), ACK delimiter and EOF: ten recessive bits (the
  // words that hold them are written, zero past the CRC).
  out.crc_delimiter_index = static_cast<uint16_t>(stuffed);
  constexpr uint64_t kTen = ~(~uint64_t{0} >> 10);
  const uint32_t off = stuffed & 63;
  if (kWhole || stuffed < 64) {
    out.level[stuffed / 64] |= kTen >> off;
  }
  if (kWhole && off > 54) {
    out.level[stuffed / 64 + 1] |= kTen << (64 - off);
  }
  const uint32_t length = stuffed + 3 + kEofBits;
  out.length = static_cast<uint16_t>(length);
  out.dynamic_stuff_bits = static_cast<uint16_t>(stuffed - n);
  out.crc = crc;
  out.crc_bits = 15;
  // The first bit after the arbitration field (destuffed 13 or 33) moves on by every stuff bit
  // before it; they all lie in the first word.
  uint32_t pos = out.extended ? 33 : 13;
  for (uint64_t m = out.stuff[0]; m != 0;) {
    const uint32_t q = static_cast<uint32_t>(__builtin_clzll(m));
    if (q > pos) {
      break;
    }
    ++pos;
    m &= ~(uint64_t{1} << (63 - q));
  }
  out.arbitration_end = static_cast<uint16_t>(pos);
}

void encode_fd(const Frame& frame, EncodedFrame& out) {
  BitString d;
  fd_header_and_data(frame, d);
  BitString s;
  BitString m;
  Probes probes = probes_for(out);
  stuff(d, false, s, m, probes);
  apply(probes, out);
  const uint32_t count = s.size - d.size;
  out.dynamic_stuff_bits = static_cast<uint16_t>(count);

  // Stuff count field: a fixed stuff bit, the Gray-coded count and its parity (in the CRC).
  auto fixed_stuff = [&] {
    const uint32_t at = s.size;
    s.append_bit(!s.bit(at - 1));
    m.pad_to(at);
    m.append(1, 1);
    ++out.fixed_stuff_bits;
  };
  const uint32_t dynamic_end = s.size;
  out.stuff_count_begin = static_cast<uint16_t>(dynamic_end);
  fixed_stuff();
  out.stuff_count = static_cast<uint8_t>(count % 8);
  const uint8_t code = kStuffCountCode[out.stuff_count];
  s.append(code, 4);

  // ISO CAN FD: CRC over the stuffed bits SOF..data (dynamic stuff bits included) and the
  // stuff count, starting with the top bit set; fixed stuff bits are not part of it.
  const bool crc21 = frame.length() > 16;
  const uint8_t width = crc21 ? 21 : 17;
  uint32_t crc =
      crc21 ? Crc21::over(s, dynamic_end, 1u << 20) : Crc17::over(s, dynamic_end, 1u << 16);
  for (int i = 3; i >= 0; --i) {
    const bool b = (code >> i) & 1u;
    crc = crc21 ? Crc21::step_bit(crc, b) : Crc17::step_bit(crc, b);
  }
  // A fixed stuff bit, the complement of the bit before it, precedes every four CRC bits.
  for (int i = width - 1; i >= 0; --i) {
    if ((width - 1 - i) % 4 == 0) {
      fixed_stuff();
    }
    s.append_bit((crc >> i) & 1u);
  }
  out.crc = crc;
  out.crc_bits = width;
  finish(s, m, out);
}

template <bool kWhole>
void encode_frame(const Frame& frame, EncodedFrame& out) {
  out.dynamic_stuff_bits = 0;
  out.fixed_stuff_bits = 0;
  out.extended = frame.extended();
  out.data_bytes = static_cast<uint8_t>(frame.length());
  out.brs_index = 0;
  out.stuff_count = 0;
  out.fd = frame.fd();
  out.brs = frame.brs();
  if (frame.fd()) {
    encode_fd(frame, out);
  } else {
    encode_classic<kWhole>(frame, out);
  }
}

}  // namespace

void encode(const Frame& frame, EncodedFrame& out) {
  encode_frame<true>(frame, out);
}

bool encode_head(const Frame& frame, EncodedFrame& out) {
  encode_frame<false>(frame, out);
  return frame.fd() || out.length <= 64;
}

EncodedFrame encode(const Frame& frame) {
  EncodedFrame out;
  encode(frame, out);
  return out;
}

}  // namespace canemu::model
