#include "canemu/firmware_model/chips/i82527/message_object.hpp"

#include <algorithm>

namespace canemu::model::i82527 {

uint8_t MessageObject::read(uint8_t offset) const {
  if (offset == CTRL0) {
    return ctrl0;
  }
  if (offset == CTRL1) {
    return ctrl1;
  }
  if (offset >= ARB0 && offset < ARB0 + 4) {
    return arb[offset - ARB0];
  }
  if (offset == CONFIG) {
    return config;
  }
  if (offset >= DATA0 && offset < DATA0 + 8) {
    return data[offset - DATA0];
  }
  return 0xFF;
}

void MessageObject::write(uint8_t offset, uint8_t value) {
  if (offset == CTRL0) {
    ctrl0 = apply_pair_write(ctrl0, value);
  } else if (offset == CTRL1) {
    ctrl1 = apply_pair_write(ctrl1, value);
  } else if (offset >= ARB0 && offset < ARB0 + 4) {
    arb[offset - ARB0] = value;
  } else if (offset == CONFIG) {
    config = value;
  } else if (offset >= DATA0 && offset < DATA0 + 8) {
    data[offset - DATA0] = value;
  }
}

Frame MessageObject::frame_as(bool remote) const {
  FrameSpec spec;
  spec.id = id();
  spec.extended = extended();
  spec.remote = remote;
  spec.dlc = static_cast<uint8_t>(dlc() & 0x0F);
  // DLC 9..15 carries 8 bytes on a classic bus.
  spec.data = std::span<const uint8_t>(data.data(), spec.remote ? 0 : dlc_to_length(dlc(), false));
  // Every identifier the registers can hold and every DLC is valid: create() cannot fail.
  return *Frame::create(spec);
}

void MessageObject::store(const Frame& frame) {
  arb = encode_id(frame.id(), frame.extended());
  config = static_cast<uint8_t>((frame.dlc() << kConfigDlcShift) | (config & 0x0F));
  const auto payload = frame.data();
  std::copy(payload.begin(), payload.end(), data.begin());
}

bool matches(const MessageObject& object, const Frame& frame, const std::array<uint8_t, 4>& mask) {
  if (frame.extended() != object.extended()) {
    return false;
  }
  const auto got = encode_id(frame.id(), frame.extended());
  const auto want = encode_id(object.id(), object.extended());
  for (std::size_t k = 0; k < 4; ++k) {
    if ((got[k] ^ want[k]) & mask[k]) {
      return false;
    }
  }
  return true;
}

}  // namespace canemu::model::i82527
