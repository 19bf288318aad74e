// The IXXAT line's transmission: the next frame for the controller from the cyclic list or the
// channels' transmit FIFOs (through the distributor), its conversion, the transmit delay of a
// staged message, and the frames loaded into the controller until they are done or dropped.
// The rest of the line (status, control, filters, channels, reception, time stamps) is in
// can_line.cpp, its bit-rate detection in can_line_detection.cpp.
#include <algorithm>

#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"

namespace canemu::model::ixxat {

void CanLine::release_loaded(bool keep) {
  if (staged_ && !keep) {
    count_dropped(*staged_);
    staged_.reset();
  }
  if (!loaded_.empty() && !node_.frame_on_wire()) {
    // The first is kept when asked; the others (a node of another daemon's bus has up to its
    // window of frames loaded) are dropped and counted, as the staging slot holds one.
    for (const Loaded& l : loaded_) {
      if (keep && !staged_) {
        staged_ = Staged{l, std::nullopt, 0, 0};
        staged_not_before_ = scheduler_.now();
      } else {
        count_dropped(l);
      }
    }
    loaded_.clear();
  }
  // A frame on the wire completes; its outcome reaches frame_transmitted() or
  // transmission_dropped() with loaded_ still holding it.
}

void CanLine::count_dropped(const Loaded& l) {
  if (l.channel) {
    distributor_.count_dropped(*l.channel);
  }
}

void CanLine::transmission_dropped(SimTime, const Frame&) {
  if (!loaded_.empty()) {
    count_dropped(loaded_.front());
    loaded_.erase(loaded_.begin());
  }
}

std::optional<TxFrame> CanLine::to_frame(const CANMSG2& msg) const {
  const auto& b = msg.uMsgInfo.Bits;
  if (b.type != CAN_MSGTYPE_DATA) {
    return std::nullopt;
  }
  const bool ext = b.ext != 0;
  if ((init_.op_mode & (ext ? CAN_OPMODE_EXTENDED : CAN_OPMODE_STANDARD)) == 0) {
    return std::nullopt;
  }
  // fdr alone asks for an FD frame with a fast data phase (the guide's own example).
  const bool fd = b.edl != 0 || b.fdr != 0;
  if ((b.edl != 0 && (init_.ex_mode & CAN_EXMODE_EXTDATA) == 0) ||
      (b.fdr != 0 && (init_.ex_mode & CAN_EXMODE_FASTDATA) == 0)) {
    return std::nullopt;
  }
  FrameSpec spec;
  spec.id = msg.dwMsgId;
  spec.extended = ext;
  spec.remote = b.rtr != 0 && !fd;
  spec.fd = fd;
  spec.brs = b.fdr != 0;
  spec.dlc = static_cast<uint8_t>(b.dlc);
  if (!spec.remote) {
    spec.data = std::span<const uint8_t>(msg.abData, dlc_to_length(*spec.dlc, fd));
  }
  auto frame = Frame::create(spec);
  if (!frame) {
    return std::nullopt;
  }
  return TxFrame{*frame, b.ssm != 0, false};
}

std::optional<TxFrame> CanLine::load(const Loaded& l, std::optional<TxFrame>& frame) {
  if (!frame) {
    frame = to_frame(l.msg);
    if (!frame) {
      count_dropped(l);  // the line's modes changed since the message was taken
      return std::nullopt;
    }
  }
  loaded_.push_back(l);
  last_load_ = scheduler_.now();
  loaded_once_ = true;
  return frame;
}

std::optional<TxFrame> CanLine::next_tx() {
  if (state_ != LineState::online) {
    return std::nullopt;
  }
  if ((init_.op_mode & CAN_OPMODE_LISTONLY) != 0) {
    // A listen-only line never sends (docs/vci.md): nothing reaches the controller (no TXPEND);
    // the transmit FIFOs keep their messages for when the line is initialized to send again,
    // and entries of the cyclic list that fall due are skipped, counted as rejected.
    while (cyclic_.take()) {
      ++cyclic_rejected_;
    }
    return std::nullopt;
  }
  const SimTime now = scheduler_.now();
  if (std::optional<CANMSG2> m = cyclic_.take()) {
    std::optional<TxFrame> none;
    if (auto tx = load(Loaded{*m, std::nullopt}, none)) {
      return tx;
    }
    ++cyclic_rejected_;
  }
  if (!staged_) {
    auto m = distributor_.take_converted([this](const CANMSG2& msg) { return to_frame(msg); });
    if (!m) {
      return std::nullopt;
    }
    staged_.emplace(Staged{{m->msg, m->channel}, m->converted, init_.op_mode, init_.ex_mode});
    staged_not_before_ = now;
    const uint32_t delay = std::min(staged_->msg.dwTime, clocks_.dtx_max_ticks);
    if (delay > 0 && loaded_once_) {
      staged_not_before_ =
          last_load_ + SimDuration(ticks_to_ns(delay, clocks_.dtx_divisor, clocks_.clock_hz));
    }
  }
  if (now < staged_not_before_) {
    if (delay_event_ != 0) {
      scheduler_.cancel(delay_event_);
    }
    delay_event_ = scheduler_.schedule_at(staged_not_before_, *this, kDelay);
    return std::nullopt;
  }
  if (staged_->op_mode != init_.op_mode || staged_->ex_mode != init_.ex_mode) {
    staged_->frame.reset();  // made again under the modes now
  }
  std::optional<TxFrame> tx = load(*staged_, staged_->frame);
  staged_.reset();
  return tx;
}

}  // namespace canemu::model::ixxat
