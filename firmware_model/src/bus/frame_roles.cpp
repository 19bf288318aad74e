#include "canemu/firmware_model/bus/frame_roles.hpp"

#include <algorithm>

namespace canemu::model {

uint16_t FrameRoles::place_injected(const EncodedFrame& e, CanErrorType type,
                                    std::optional<uint16_t> bit) {
  const uint16_t ack_slot = static_cast<uint16_t>(e.crc_delimiter_index + 1);
  switch (type) {
    case CanErrorType::bit:
      return std::clamp<uint16_t>(bit.value_or(e.arbitration_end), e.arbitration_end,
                                  static_cast<uint16_t>(e.length - 2));
    case CanErrorType::stuff:
      return std::clamp<uint16_t>(bit.value_or(e.arbitration_end), e.arbitration_end,
                                  static_cast<uint16_t>(ErrorPhase::stuffed_end(e) - 1));
    case CanErrorType::form: {
      // Fixed-form bits: CRC delimiter, ACK delimiter, EOF but its last bit.
      const uint16_t k = bit.value_or(e.crc_delimiter_index);
      if (k == e.crc_delimiter_index || (k > ack_slot && k + 1 < e.length)) {
        return k;
      }
      return e.crc_delimiter_index;
    }
    case CanErrorType::crc:
      return static_cast<uint16_t>(ack_slot + 1);  // flagged after the ACK delimiter
    case CanErrorType::ack:
      return ack_slot;
  }
  return e.arbitration_end;
}

}  // namespace canemu::model
