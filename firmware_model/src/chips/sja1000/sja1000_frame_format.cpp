// PeliCAN frame buffer layout, acceptance filter and error code segments of the SJA1000.
#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"

#include <algorithm>
#include <cstring>

namespace canemu::model::sja1000 {

std::size_t pack_frame(const Frame& frame, uint8_t* out) {
  const uint32_t id = frame.id();
  const uint8_t rtr = frame.remote() ? 1 : 0;
  std::size_t n = 0;
  if (frame.extended()) {
    out[n++] = static_cast<uint8_t>(0x80 | (rtr << 6) | frame.dlc());
    out[n++] = static_cast<uint8_t>(id >> 21);
    out[n++] = static_cast<uint8_t>(id >> 13);
    out[n++] = static_cast<uint8_t>(id >> 5);
    out[n++] = static_cast<uint8_t>(((id & 0x1F) << 3) | (rtr << 2));
  } else {
    out[n++] = static_cast<uint8_t>((rtr << 6) | frame.dlc());
    out[n++] = static_cast<uint8_t>(id >> 3);
    out[n++] = static_cast<uint8_t>(((id & 0x07) << 5) | (rtr << 4));
  }
  // At most 8 data bytes: the layout has no room for more (a CAN FD frame's are cut there, as
  // its DLC above 8 reads as 8 bytes).
  const auto data = frame.data().first(std::min<std::size_t>(frame.length(), 8));
  if (data.size() == 8) {  // most frames: one move, not eight
    std::memcpy(out + n, data.data(), 8);
    return n + 8;
  }
  for (uint8_t b : data) {
    out[n++] = b;
  }
  return n;
}

std::optional<Frame> unpack_frame(const uint8_t* bytes) {
  const uint8_t info = bytes[0];
  FrameSpec spec;
  spec.extended = (info & 0x80) != 0;
  spec.remote = (info & 0x40) != 0;
  spec.dlc = static_cast<uint8_t>(info & 0x0F);
  const uint8_t* data;
  if (spec.extended) {
    spec.id = (uint32_t{bytes[1]} << 21) | (uint32_t{bytes[2]} << 13) | (uint32_t{bytes[3]} << 5) |
              (uint32_t{bytes[4]} >> 3);
    data = bytes + 5;
  } else {
    spec.id = (uint32_t{bytes[1]} << 3) | (uint32_t{bytes[2]} >> 5);
    data = bytes + 3;
  }
  const std::size_t len = spec.remote ? 0 : dlc_to_length(*spec.dlc, false);
  spec.data = std::span<const uint8_t>(data, len);
  auto f = Frame::create(spec);
  if (!f) {
    return std::nullopt;
  }
  return *f;
}

namespace {

bool byte_matches(uint8_t value, uint8_t acr, uint8_t amr, uint8_t compared = 0xFF) {
  return ((value ^ acr) & ~amr & compared) == 0;
}

}  // namespace

bool accepts(const std::array<uint8_t, 4>& acr, const std::array<uint8_t, 4>& amr, bool single,
             const Frame& frame) {
  if (accepts_all(amr)) {
    return true;  // every bit "don't care", in either mode: the driver's usual accept-all
  }
  const uint32_t id = frame.id();
  const uint8_t rtr = frame.remote() ? 1 : 0;
  const auto data = frame.data();
  if (frame.extended()) {
    const uint8_t b0 = static_cast<uint8_t>(id >> 21);
    const uint8_t b1 = static_cast<uint8_t>(id >> 13);
    if (single) {
      const uint8_t b2 = static_cast<uint8_t>(id >> 5);
      const uint8_t b3 = static_cast<uint8_t>(((id & 0x1F) << 3) | (rtr << 2));
      return byte_matches(b0, acr[0], amr[0]) && byte_matches(b1, acr[1], amr[1]) &&
             byte_matches(b2, acr[2], amr[2]) && byte_matches(b3, acr[3], amr[3], 0xFC);
    }
    const bool f1 = byte_matches(b0, acr[0], amr[0]) && byte_matches(b1, acr[1], amr[1]);
    const bool f2 = byte_matches(b0, acr[2], amr[2]) && byte_matches(b1, acr[3], amr[3]);
    return f1 || f2;
  }
  const uint8_t b0 = static_cast<uint8_t>(id >> 3);
  const uint8_t b1 = static_cast<uint8_t>(((id & 0x07) << 5) | (rtr << 4));
  if (single) {
    return byte_matches(b0, acr[0], amr[0]) && byte_matches(b1, acr[1], amr[1], 0xF0) &&
           (data.empty() || byte_matches(data[0], acr[2], amr[2])) &&
           (data.size() < 2 || byte_matches(data[1], acr[3], amr[3]));
  }
  // Filter 1: ACR0, ACR1 high nibble (ID.20-18, RTR), ACR1 low nibble and ACR3 low nibble
  // (first data byte). Filter 2: ACR2, ACR3 high nibble.
  bool f1 = byte_matches(b0, acr[0], amr[0]) && byte_matches(b1, acr[1], amr[1], 0xF0);
  if (f1 && !data.empty()) {
    f1 = byte_matches(static_cast<uint8_t>(data[0] >> 4), acr[1], amr[1], 0x0F) &&
         byte_matches(static_cast<uint8_t>(data[0] & 0x0F), acr[3], amr[3], 0x0F);
  }
  const bool f2 = byte_matches(b0, acr[2], amr[2]) && byte_matches(b1, acr[3], amr[3], 0xF0);
  return f1 || f2;
}

uint8_t ecc_segment(const BusErrorEvent& e, uint16_t d, bool extended) {
  if (!e.in_frame) {
    return 0x13;  // tolerate dominant bits
  }
  switch (e.field) {
    case Field::sof:
      return 0x03;
    case Field::base_id:
      return d <= 8 ? 0x02 : 0x06;
    case Field::srr:
      return 0x04;
    case Field::ide:
      return 0x05;
    case Field::ext_id:
      return d <= 18 ? 0x07 : d <= 26 ? 0x0F : 0x0E;
    case Field::rtr:
    case Field::rrs:
      return 0x0C;
    case Field::fdf:
      return extended ? 0x0D : 0x09;
    case Field::res:
      return 0x09;
    case Field::dlc:
    case Field::brs:
    case Field::esi:
      return 0x0B;
    case Field::data:
      return 0x0A;
    case Field::stuff_count:
    case Field::crc:
      return 0x08;
    case Field::crc_delimiter:
      return 0x18;
    case Field::ack_slot:
      return 0x19;
    case Field::ack_delimiter:
      return 0x1B;
    case Field::eof:
      return 0x1A;
  }
  return 0x03;
}

}  // namespace canemu::model::sja1000
