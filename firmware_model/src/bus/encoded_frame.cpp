// Reading an encoded frame: its fields and where they begin, stuffed and destuffed indexes,
// its bits as text, and how long it and any prefix of it take on the wire (the encoding itself
// is in wire_encoding.cpp).
#include <algorithm>

#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace canemu::model {

namespace {

// Population count without a library call on CPUs where the compiler may not use POPCNT.
uint32_t count_ones(uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
  return static_cast<uint32_t>((x * 0x0101010101010101ULL) >> 56);
}

// The stuff bits among the frame's first `i` bits.
uint32_t stuff_bits_before(const EncodedFrame& f, uint32_t i) {
  uint32_t n = 0;
  for (uint32_t w = 0; w < i / 64; ++w) {
    n += count_ones(f.stuff[w]);
  }
  if (i % 64 != 0) {
    n += count_ones(f.stuff[i / 64] >> (64 - i % 64));
  }
  return n;
}

// The first `length` bits of `words` (the first at the top of words[0]) as '0' and '1'.
std::string bits_text(const EncodedFrame::Bits& words, std::size_t length) {
  std::string s(length, '0');
  for (std::size_t i = 0; i < length; ++i) {
    if ((words[i >> 6] >> (63 - (i & 63))) & 1u) {
      s[i] = '1';
    }
  }
  return s;
}

}  // namespace

std::string_view to_string(Field field) {
  switch (field) {
    case Field::sof:
      return "SOF";
    case Field::base_id:
      return "ID";
    case Field::srr:
      return "SRR";
    case Field::ide:
      return "IDE";
    case Field::ext_id:
      return "ID-ext";
    case Field::rtr:
      return "RTR";
    case Field::rrs:
      return "RRS";
    case Field::fdf:
      return "FDF";
    case Field::res:
      return "res";
    case Field::brs:
      return "BRS";
    case Field::esi:
      return "ESI";
    case Field::dlc:
      return "DLC";
    case Field::data:
      return "data";
    case Field::stuff_count:
      return "SBC";
    case Field::crc:
      return "CRC";
    case Field::crc_delimiter:
      return "CRC-del";
    case Field::ack_slot:
      return "ACK";
    case Field::ack_delimiter:
      return "ACK-del";
    case Field::eof:
      return "EOF";
  }
  return "?";
}

uint16_t EncodedFrame::stuffed_index(uint16_t destuffed) const {
  // The frame index s of a destuffed bit has exactly `destuffed` non-stuff bits before it and is
  // not a stuff bit itself.
  uint32_t s = destuffed;
  while (true) {
    const uint32_t t = destuffed + stuff_bits_before(*this, s);
    if (t > s) {
      s = t;
    } else if (is_stuff(s)) {
      ++s;
    } else {
      return static_cast<uint16_t>(s);
    }
  }
}

uint16_t EncodedFrame::destuffed_index_far(uint16_t i) const {
  return static_cast<uint16_t>(i - stuff_bits_before(*this, i));
}

uint8_t EncodedFrame::fields(std::array<FieldSpan, 19>& out) const {
  uint8_t n = 0;
  auto at = [&](Field f, uint32_t index) { out[n++] = FieldSpan{f, static_cast<uint16_t>(index)}; };
  auto destuffed = [&](Field f, uint32_t d) { at(f, stuffed_index(static_cast<uint16_t>(d))); };
  const Field rtr = fd ? Field::rrs : Field::rtr;
  uint32_t d = 0;
  destuffed(Field::sof, 0);
  destuffed(Field::base_id, 1);
  if (extended) {
    destuffed(Field::srr, 12);
    destuffed(Field::ide, 13);
    destuffed(Field::ext_id, 14);
    destuffed(rtr, 32);
    destuffed(Field::fdf, 33);
    destuffed(Field::res, 34);
    d = 35;
  } else {
    destuffed(rtr, 12);
    destuffed(Field::ide, 13);
    destuffed(Field::fdf, 14);
    d = 15;
    if (fd) {
      destuffed(Field::res, 15);
      d = 16;
    }
  }
  if (fd) {
    destuffed(Field::brs, d);
    destuffed(Field::esi, d + 1);
    d += 2;
  }
  destuffed(Field::dlc, d);
  d += 4;
  if (data_bytes > 0) {
    destuffed(Field::data, d);
    d += 8u * data_bytes;
  }
  if (fd) {
    at(Field::stuff_count, stuff_count_begin);
    at(Field::crc, stuff_count_begin + 5u);
  } else {
    destuffed(Field::crc, d);
  }
  at(Field::crc_delimiter, crc_delimiter_index);
  at(Field::ack_slot, crc_delimiter_index + 1u);
  at(Field::ack_delimiter, crc_delimiter_index + 2u);
  at(Field::eof, crc_delimiter_index + 3u);
  return n;
}

uint16_t EncodedFrame::field_begin(Field field) const {
  std::array<FieldSpan, 19> f;
  const uint8_t n = fields(f);
  for (uint8_t k = 0; k < n; ++k) {
    if (f[k].field == field) {
      return f[k].begin;
    }
  }
  return length;
}

Field EncodedFrame::field_at(std::size_t i) const {
  std::array<FieldSpan, 19> f;
  const uint8_t n = fields(f);
  Field result = Field::sof;
  for (uint8_t k = 0; k < n && f[k].begin <= i; ++k) {
    result = f[k].field;
  }
  return result;
}

std::string EncodedFrame::to_string() const {
  return bits_text(level, length);
}

std::string EncodedFrame::stuff_marks() const {
  return bits_text(stuff, length);
}

BitCounts bit_counts(const EncodedFrame& frame) {
  if (!frame.brs) {
    return BitCounts{frame.length, 0};
  }
  // Data phase: from the bit after BRS up to the bit before the CRC delimiter.
  const uint32_t data = frame.crc_delimiter_index - frame.brs_index - 1u;
  return BitCounts{frame.length - data, data};
}

SimDuration frame_prefix_duration(const EncodedFrame& frame, const BitTiming& nominal,
                                  const BitTiming& data, uint32_t bits) {
  if (!frame.brs || bits <= frame.brs_index) {
    return nominal.bits_duration(bits);
  }
  // Nominal bits before BRS; BRS = nominal quanta up to its sample point, then data phase 2;
  // data bits; CRC delimiter = data quanta up to its sample point, then nominal phase 2; nominal
  // bits after it. A prefix ending inside the data phase ends on a whole data bit.
  uint64_t nominal_quanta =
      uint64_t{frame.brs_index} * nominal.quanta_per_bit() + (1u + nominal.tseg1);
  uint64_t data_quanta = data.tseg2;
  const uint32_t data_end = std::min<uint32_t>(bits, frame.crc_delimiter_index);
  data_quanta += uint64_t{data_end - frame.brs_index - 1u} * data.quanta_per_bit();
  if (bits > frame.crc_delimiter_index) {
    data_quanta += 1u + data.tseg1;
    nominal_quanta += nominal.tseg2;
    nominal_quanta += uint64_t{bits - frame.crc_delimiter_index - 1u} * nominal.quanta_per_bit();
  }
  return quanta_duration(nominal, nominal_quanta, data, data_quanta);
}

SimDuration frame_duration(const EncodedFrame& frame, const BitTiming& nominal,
                           const BitTiming& data) {
  return frame_prefix_duration(frame, nominal, data, frame.length);
}

}  // namespace canemu::model
