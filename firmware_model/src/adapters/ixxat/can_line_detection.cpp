// The IXXAT line's bit-rate detection: DetectBaud on a line that is not started, and the
// automatic detection of a line started with CAN_OPMODE_AUTOBAUD, which locks in the rate found
// (the detector itself is bitrate_detector.cpp). The rest of the line is in can_line.cpp and
// can_line_transmit.cpp.
#include <utility>
#include <vector>

#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"

namespace canemu::model::ixxat {

HRESULT CanLine::start_detection(const std::vector<LineInit>& entries, SimDuration per_entry) {
  if (detector_.running()) {
    return VCI_E_BUSY;
  }
  if (state_ == LineState::online) {
    return VCI_E_INVALID_STATE;
  }
  if (entries.empty() || per_entry.ns() <= 0) {
    return VCI_E_INVALIDARG;
  }
  std::vector<HostedNodeSettings> settings;
  for (const LineInit& e : entries) {
    const auto s = line_settings(e, fd_controller(), low_speed_);
    if (!s) {
      return s.error();
    }
    settings.push_back(*s);
  }
  release_loaded(false);
  state_ = LineState::not_initialized;
  configured_ = false;
  detector_.start(std::move(settings), per_entry);
  return VCI_OK;
}

void CanLine::detection_ended() {
  if (autobaud_detecting_) {
    autobaud_detecting_ = false;
    const Detection r = detector_.result();
    if (r.hr != VCI_OK) {
      return;  // cancelled: stop, reset or InitLine, which leave the line as they do
    }
    // Lock-in: the line takes the rate found and runs from this instant in its own modes.
    const LineInit& found = autobaud_table_[r.index];
    settings_ = *line_settings(found, fd_controller(), low_speed_);
    init_.btr0 = found.btr0;
    init_.btr1 = found.btr1;
    init_.sdr = found.sdr;
    shown_ = init_.v2 ? shown_timings(init_, fd_controller()) : LineTimings{};
    autobaud_pending_ = false;
    node_.configure(settings_, this, [this] { return next_tx(); });
    node_.go_online();
    update_status(scheduler_.now());
    return;
  }
  state_ = LineState::not_initialized;
  configured_ = false;
  autobaud_pending_ = false;
  error_state_ = ErrorState::active;
}

}  // namespace canemu::model::ixxat
