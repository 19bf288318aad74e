#include "canemu/firmware_model/bus/frame.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace canemu::model {

Result<Frame> Frame::create(const FrameSpec& spec) {
  const uint32_t max_id = spec.extended ? kMaxExtendedId : kMaxStandardId;
  if (spec.id > max_id) {
    return model_error(ModelErrc::invalid_identifier,
                       fmt::format("identifier 0x{:X} does not fit {} bits (maximum 0x{:X})",
                                   spec.id, spec.extended ? 29 : 11, max_id));
  }
  if (spec.remote && spec.fd) {
    return model_error(ModelErrc::invalid_flags,
                       "CAN FD has no remote frames: remote and fd cannot both be set");
  }
  if (!spec.fd && (spec.brs || spec.esi)) {
    return model_error(ModelErrc::invalid_flags, fmt::format("{} is a CAN FD bit: it needs fd set",
                                                             spec.brs ? "BRS" : "ESI"));
  }
  if (spec.remote && !spec.data.empty()) {
    return model_error(
        ModelErrc::data_length_mismatch,
        fmt::format("a remote frame carries no data, but {} bytes were given", spec.data.size()));
  }
  const std::size_t max_length = spec.fd ? kMaxFdLength : kMaxClassicLength;
  if (spec.data.size() > max_length) {
    return model_error(ModelErrc::data_length_mismatch,
                       fmt::format("{} data bytes exceed the {} bytes of a {} frame",
                                   spec.data.size(), max_length, spec.fd ? "CAN FD" : "classic"));
  }

  uint8_t dlc = 0;
  if (spec.dlc) {
    dlc = *spec.dlc;
    if (dlc > kMaxDlc) {
      return model_error(ModelErrc::invalid_dlc,
                         fmt::format("DLC {} is out of range 0..{}", dlc, kMaxDlc));
    }
    const std::size_t want = dlc_to_length(dlc, spec.fd);
    if (!spec.remote && spec.data.size() != want) {
      return model_error(ModelErrc::data_length_mismatch,
                         fmt::format("DLC {} means {} data bytes, but {} were given", dlc, want,
                                     spec.data.size()));
    }
  } else if (!spec.remote) {
    const auto code = length_to_dlc(spec.data.size(), spec.fd);
    if (!code) {
      return model_error(ModelErrc::data_length_mismatch,
                         fmt::format("no DLC gives {} data bytes (CAN FD lengths above 8 are "
                                     "12, 16, 20, 24, 32, 48, 64)",
                                     spec.data.size()));
    }
    dlc = *code;
  }

  Frame frame;
  frame.id_ = spec.id;
  frame.dlc_ = dlc;
  frame.extended_ = spec.extended;
  frame.remote_ = spec.remote;
  frame.fd_ = spec.fd;
  frame.brs_ = spec.brs;
  frame.esi_ = spec.esi;
  std::copy(spec.data.begin(), spec.data.end(), frame.data_.begin());
  return frame;
}

Result<Frame> Frame::classic(uint32_t id, std::span<const uint8_t> data, bool extended) {
  FrameSpec spec;
  spec.id = id;
  spec.extended = extended;
  spec.data = data;
  return create(spec);
}

Result<Frame> Frame::fd_frame(uint32_t id, std::span<const uint8_t> data, bool extended, bool brs) {
  FrameSpec spec;
  spec.id = id;
  spec.extended = extended;
  spec.fd = true;
  spec.brs = brs;
  spec.data = data;
  return create(spec);
}

}  // namespace canemu::model
