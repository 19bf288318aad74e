#include "canemu/firmware_model/wire_encoding.hpp"

#include <algorithm>

namespace canemu::model {

namespace {

// CRC generator polynomials without their top bit (ISO 11898-1:2015, 10.4.2.6).
constexpr uint32_t kCrc15Poly = 0x4599;
constexpr uint32_t kCrc17Poly = 0x1685B;
constexpr uint32_t kCrc21Poly = 0x102899;

// Gray code of the stuff count (0..7) in bits 3..1 and its even parity in bit 0.
constexpr std::array<uint8_t, 8> kStuffCountCode{0x0, 0x3, 0x6, 0x5, 0xC, 0xF, 0xA, 0x9};

// Writes bits into an EncodedFrame, doing the dynamic bit stuffing and the CRC as it goes.
class BitWriter {
 public:
  BitWriter(EncodedFrame& out, uint8_t crc_bits) : out_(out), crc_bits_(crc_bits) {
    crc_top_ = 1u << (crc_bits - 1);
    crc_mask_ = (1u << crc_bits) - 1;
    crc_poly_ = crc_bits == 15 ? kCrc15Poly : crc_bits == 17 ? kCrc17Poly : kCrc21Poly;
    // ISO CAN FD starts CRC-17/21 with the top bit set; classic CRC-15 starts at zero.
    crc_ = crc_bits == 15 ? 0u : crc_top_;
  }

  void begin(Field field) {
    out_.fields[out_.field_count++] = FieldSpan{field, pos_};
  }

  // A bit of the dynamically stuffed part. `may_stuff` is false for the last bit before the CAN FD
  // CRC field, where the fixed stuff bit takes the place of a dynamic one.
  void stuffed(bool bit, bool may_stuff = true) {
    emit(bit, false);
    crc_step(bit);
    if (bit == last_) {
      ++run_;
    } else {
      last_ = bit;
      run_ = 1;
    }
    if (run_ == 5 && may_stuff) {
      const bool s = !bit;
      emit(s, true);
      if (crc_bits_ != 15) {
        crc_step(s);  // ISO CAN FD: dynamic stuff bits are part of the CRC
      }
      ++out_.dynamic_stuff_bits;
      last_ = s;
      run_ = 1;
    }
  }

  void stuffed_field(uint32_t value, int bits) {
    for (int i = bits - 1; i >= 0; --i) {
      stuffed((value >> i) & 1u);
    }
  }

  // A bit that is not stuffed but enters the CRC (the CAN FD stuff count).
  void crc_only(bool bit) {
    emit(bit, false);
    crc_step(bit);
  }

  // A bit neither stuffed nor in the CRC (fixed stuff bits, CRC, delimiters, ACK, EOF).
  void plain(bool bit) { emit(bit, false); }
  void fixed_stuff() {
    emit(!previous(), true);
    ++out_.fixed_stuff_bits;
  }

  bool previous() const { return out_.level_at(pos_ - 1u); }
  uint16_t pos() const { return pos_; }
  uint32_t crc() const { return crc_ & crc_mask_; }

 private:
  void emit(bool bit, bool is_stuff) {
    const std::size_t w = pos_ >> 6;
    const uint64_t m = uint64_t{1} << (pos_ & 63);
    if (bit) {
      out_.level[w] |= m;
    }
    if (is_stuff) {
      out_.stuff[w] |= m;
    }
    ++pos_;
  }

  void crc_step(bool bit) {
    const bool feedback = bit ^ ((crc_ & crc_top_) != 0);
    crc_ = (crc_ << 1) & crc_mask_;
    if (feedback) {
      crc_ ^= crc_poly_;
    }
  }

  EncodedFrame& out_;
  uint8_t crc_bits_;
  uint32_t crc_ = 0;
  uint32_t crc_top_ = 0;
  uint32_t crc_mask_ = 0;
  uint32_t crc_poly_ = 0;
  uint16_t pos_ = 0;
  bool last_ = true;  // the idle bus is recessive
  int run_ = 0;
};

constexpr bool kDominant = false;
constexpr bool kRecessive = true;

void encode_arbitration_and_control(const Frame& frame, BitWriter& w, EncodedFrame& out) {
  const bool fd = frame.fd();
  w.begin(Field::sof);
  w.stuffed(kDominant);
  w.begin(Field::base_id);
  const Field rtr_field = fd ? Field::rrs : Field::rtr;
  const bool rtr_level = frame.remote();  // RRS is always dominant
  if (frame.extended()) {
    w.stuffed_field(frame.id() >> 18, 11);
    w.begin(Field::srr);
    w.stuffed(kRecessive);
    w.begin(Field::ide);
    w.stuffed(kRecessive);
    w.begin(Field::ext_id);
    w.stuffed_field(frame.id() & 0x3FFFF, 18);
    w.begin(rtr_field);
    w.stuffed(rtr_level);
    out.arbitration_end = w.pos();
    w.begin(Field::fdf);
    w.stuffed(fd ? kRecessive : kDominant);
    w.begin(Field::res);
    w.stuffed(kDominant);
  } else {
    w.stuffed_field(frame.id(), 11);
    w.begin(rtr_field);
    w.stuffed(rtr_level);
    out.arbitration_end = w.pos();
    w.begin(Field::ide);
    w.stuffed(kDominant);
    w.begin(Field::fdf);
    w.stuffed(fd ? kRecessive : kDominant);
    if (fd) {
      w.begin(Field::res);
      w.stuffed(kDominant);
    }
  }
  if (fd) {
    w.begin(Field::brs);
    out.brs_index = w.pos();
    w.stuffed(frame.brs());
    w.begin(Field::esi);
    w.stuffed(frame.esi());
  }
}

// CRC delimiter, ACK slot (sent recessive), ACK delimiter and EOF: fixed form, never stuffed.
void encode_tail(BitWriter& w, EncodedFrame& out) {
  w.begin(Field::crc_delimiter);
  out.crc_delimiter_index = w.pos();
  w.plain(kRecessive);
  w.begin(Field::ack_slot);
  w.plain(kRecessive);
  w.begin(Field::ack_delimiter);
  w.plain(kRecessive);
  w.begin(Field::eof);
  for (uint32_t i = 0; i < kEofBits; ++i) {
    w.plain(kRecessive);
  }
  out.length = w.pos();
}

void encode_classic(const Frame& frame, EncodedFrame& out) {
  BitWriter w(out, 15);
  encode_arbitration_and_control(frame, w, out);
  w.begin(Field::dlc);
  w.stuffed_field(frame.dlc(), 4);
  if (frame.length() > 0) {
    w.begin(Field::data);
    for (uint8_t byte : frame.data()) {
      w.stuffed_field(byte, 8);
    }
  }
  // The CRC sequence is stuffed like the rest, and stuff bits do not enter the CRC.
  const uint32_t crc = w.crc();
  w.begin(Field::crc);
  w.stuffed_field(crc, 15);
  out.crc = crc;
  out.crc_bits = 15;
  encode_tail(w, out);
}

void encode_fd(const Frame& frame, EncodedFrame& out) {
  const uint8_t crc_bits = frame.length() > 16 ? 21 : 17;
  BitWriter w(out, crc_bits);
  encode_arbitration_and_control(frame, w, out);
  w.begin(Field::dlc);
  const auto data = frame.data();
  for (int i = 3; i >= 0; --i) {
    // No dynamic stuff bit after the last bit before the CRC field (ISO 11898-1:2015 10.5).
    w.stuffed((frame.dlc() >> i) & 1u, i > 0 || !data.empty());
  }
  if (!data.empty()) {
    w.begin(Field::data);
    for (std::size_t b = 0; b < data.size(); ++b) {
      for (int i = 7; i >= 0; --i) {
        const bool last = b + 1 == data.size() && i == 0;
        w.stuffed((data[b] >> i) & 1u, !last);
      }
    }
  }
  w.begin(Field::stuff_count);
  w.fixed_stuff();
  out.stuff_count = static_cast<uint8_t>(out.dynamic_stuff_bits % 8);
  const uint8_t code = kStuffCountCode[out.stuff_count];
  for (int i = 3; i >= 0; --i) {
    w.crc_only((code >> i) & 1u);
  }
  const uint32_t crc = w.crc();
  w.begin(Field::crc);
  // A fixed stuff bit, the complement of the bit before it, precedes every four CRC bits.
  for (int i = crc_bits - 1; i >= 0; --i) {
    if ((crc_bits - 1 - i) % 4 == 0) {
      w.fixed_stuff();
    }
    w.plain((crc >> i) & 1u);
  }
  out.crc = crc;
  out.crc_bits = crc_bits;
  encode_tail(w, out);
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

Field EncodedFrame::field_at(std::size_t i) const {
  Field f = Field::sof;
  for (uint8_t k = 0; k < field_count && fields[k].begin <= i; ++k) {
    f = fields[k].field;
  }
  return f;
}

uint16_t EncodedFrame::field_begin(Field field) const {
  for (uint8_t k = 0; k < field_count; ++k) {
    if (fields[k].field == field) {
      return fields[k].begin;
    }
  }
  return length;
}

std::string EncodedFrame::to_string() const {
  std::string s(length, '0');
  for (std::size_t i = 0; i < length; ++i) {
    if (level_at(i)) {
      s[i] = '1';
    }
  }
  return s;
}

void encode(const Frame& frame, EncodedFrame& out) {
  out.level.fill(0);
  out.stuff.fill(0);
  out.dynamic_stuff_bits = 0;
  out.fixed_stuff_bits = 0;
  out.field_count = 0;
  out.brs_index = 0;
  out.stuff_count = 0;
  out.fd = frame.fd();
  out.brs = frame.brs();
  if (frame.fd()) {
    encode_fd(frame, out);
  } else {
    encode_classic(frame, out);
  }
}

BitCounts bit_counts(const EncodedFrame& frame) {
  if (!frame.brs) {
    return BitCounts{frame.length, 0};
  }
  // Data phase: from the bit after BRS up to the bit before the CRC delimiter.
  const uint32_t data = frame.crc_delimiter_index - frame.brs_index - 1u;
  return BitCounts{frame.length - data, data};
}

SimDuration frame_duration(const EncodedFrame& frame, const BitTiming& nominal,
                           const BitTiming& data) {
  if (!frame.brs) {
    return nominal.bits_duration(frame.length);
  }
  const BitCounts counts = bit_counts(frame);
  // BRS: nominal quanta up to its sample point, then data phase 2. CRC delimiter: data quanta up
  // to its sample point, then nominal phase 2.
  const uint64_t nominal_quanta = uint64_t{counts.nominal - 2u} * nominal.quanta_per_bit() +
                                  (1u + nominal.tseg1) + nominal.tseg2;
  const uint64_t data_quanta =
      uint64_t{counts.data} * data.quanta_per_bit() + data.tseg2 + (1u + data.tseg1);
  return quanta_duration(nominal, nominal_quanta, data, data_quanta);
}

EncodedFrame encode(const Frame& frame) {
  EncodedFrame out;
  encode(frame, out);
  return out;
}

}  // namespace canemu::model
