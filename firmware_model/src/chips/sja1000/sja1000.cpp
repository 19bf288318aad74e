#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"

#include <algorithm>

namespace canemu::model {

using namespace sja1000;

Sja1000::Sja1000(uint32_t oscillator_hz) : oscillator_hz_(oscillator_hz) {}

void Sja1000::connect(CanBus& bus) {
  bus_ = &bus;
  node_ = bus.attach(*this);
}

void Sja1000::hardware_reset() {
  enter_reset();  // drops the request and the FIFO, tells the bus
  if (tx_) {
    tx_->single_shot = true;  // on the wire: completes, is not repeated
  }
  mod_ = MOD_RM;
  ier_ = 0;
  btr0_ = 0;
  btr1_ = 0;
  ocr_ = 0;
  cdr_ = 0x80;
  alc_ = 0;
  ecc_ = 0;
  alc_armed_ = true;
  ecc_armed_ = true;
  acr_ = {};
  amr_ = {0xFF, 0xFF, 0xFF, 0xFF};
  tx_buffer_ = {};
  tx_complete_ = true;
  fc_.reset();
  fc_.set_warning_limit(kDefaultWarningLimit);
  if (bus_ != nullptr) {
    bus_->controller_changed(node_);
  }
  counters_written();
}

SimTime Sja1000::now() const {
  return bus_ != nullptr ? bus_->now() : SimTime{};
}

NodeTiming Sja1000::timing() const {
  NodeTiming t;
  t.nominal = sja1000::timing_from_btr(btr0_, btr1_, oscillator_hz_);
  return t;
}

void Sja1000::set_ir(uint8_t bits, SimTime at) {
  const bool was = interrupt_line();
  ir_ |= static_cast<uint8_t>(bits & ier_ & ~IR_RI);
  if (!was && interrupt_line() && on_interrupt) {
    on_interrupt(at);
  }
}

uint8_t Sja1000::status() const {
  uint8_t sr = 0;
  if (rmc_ > 0) {
    sr |= SR_RBS;
  }
  if (data_overrun_) {
    sr |= SR_DOS;
  }
  if (!tx_) {
    sr |= SR_TBS;
  }
  if (tx_complete_) {
    sr |= SR_TCS;
  }
  if (mod_ & MOD_RM) {
    sr |= SR_RS | SR_TS;
  }
  return static_cast<uint8_t>(sr | error_bits());
}

uint8_t Sja1000::read(uint8_t address) {
  const bool reset = (mod_ & MOD_RM) != 0;
  switch (address) {
    case MOD:
      return mod_;
    case CMR:
      return 0xFF;
    case SR:
      return status();
    case IR: {
      const uint8_t r = ir_value();
      ir_ = 0;  // reading clears every bit but RI, which follows the FIFO
      return r;
    }
    case IER:
      return ier_;
    case BTR0:
      return btr0_;
    case BTR1:
      return btr1_;
    case OCR:
      return ocr_;
    case ALC:
      alc_armed_ = true;
      return alc_;
    case ECC:
      ecc_armed_ = true;
      return ecc_;
    case EWLR:
      return fc_.warning_limit();
    case RXERR:
      return fc_.bus_off() ? 0 : static_cast<uint8_t>(std::min<uint16_t>(fc_.rec(), 255));
    case TXERR:
      // In bus-off TXERR counts the recovery down from 127 (datasheet 6.4.13).
      if (fc_.bus_off()) {
        return static_cast<uint8_t>(fc_.recovering() ? fc_.recovery_sequences_left() - 1 : 127);
      }
      return static_cast<uint8_t>(std::min<uint16_t>(fc_.tec(), 255));
    case RMC:
      return rmc_;
    case RBSA:
      return static_cast<uint8_t>(rbsa_);
    case CDR:
      return cdr_;
    default:
      break;
  }
  if (address >= FRAME && address < FRAME + 13) {
    if (reset) {
      return address < AMR0       ? acr_[address - ACR0]
             : address < AMR0 + 4 ? amr_[address - AMR0]
                                  : 0xFF;
    }
    return fifo_byte(address - FRAME);  // receive buffer window at RBSA
  }
  if (address >= RX_FIFO && address < RX_FIFO + kRxFifoBytes) {
    return fifo_[address - RX_FIFO];
  }
  if (address >= TX_BUFFER && address < TX_BUFFER + 13) {
    return tx_buffer_[address - TX_BUFFER];
  }
  return 0xFF;
}

void Sja1000::write(uint8_t address, uint8_t value) {
  const bool reset = (mod_ & MOD_RM) != 0;
  switch (address) {
    case MOD:
      if (reset) {
        // LOM, STM and AFM are writable in reset mode only.
        mod_ = static_cast<uint8_t>((value & (MOD_LOM | MOD_STM | MOD_AFM | MOD_SM)) | MOD_RM);
        if (!(value & MOD_RM)) {
          leave_reset();
        } else {
          // The host's reset request. The chip may be in reset mode by itself (bus-off sets RM
          // and keeps the request for after recovery); the host's request aborts it all the
          // same: reset mode as entered from operating mode.
          enter_reset();
        }
      } else if (value & MOD_RM) {
        enter_reset();
      }
      return;
    case CMR:
      command(value);
      return;
    case IER: {
      const bool was = interrupt_line();
      ier_ = value;
      if (!was && interrupt_line() && on_interrupt) {
        on_interrupt(now());
      }
      return;
    }
    case CDR:
      cdr_ = static_cast<uint8_t>(value | 0x80);  // PeliCAN only
      return;
    default:
      break;
  }
  if (reset) {
    switch (address) {
      case BTR0:
        btr0_ = value;
        if (bus_ != nullptr) {
          bus_->controller_changed(node_);
        }
        return;
      case BTR1:
        btr1_ = value;
        if (bus_ != nullptr) {
          bus_->controller_changed(node_);
        }
        return;
      case OCR:
        ocr_ = value;
        return;
      case EWLR:
        fc_.set_warning_limit(value);
        return;
      case RXERR:
        fc_.set_counters(fc_.tec(), value);
        counters_written();
        return;
      case TXERR:
        // Writing 255 starts a bus-off (datasheet 6.4.13).
        fc_.set_counters(value == 255 ? kBusOffLimit : value, fc_.rec());
        counters_written();
        return;
      default:
        break;
    }
    if (address >= ACR0 && address < ACR0 + 4) {
      acr_[address - ACR0] = value;
    } else if (address >= AMR0 && address < AMR0 + 4) {
      amr_[address - AMR0] = value;
    }
    return;
  }
  // Operating mode: the transmit buffer, while it is released.
  if (address >= FRAME && address < FRAME + 13 && !tx_) {
    tx_buffer_[address - FRAME] = value;
  }
}

void Sja1000::write_transmit(const Frame& frame, uint8_t cmr) {
  const bool request = (cmr & (CMR_TR | CMR_SRR)) != 0;
  if ((mod_ & MOD_RM) != 0 || tx_ || !request || frame.fd()) {
    // Written where the buffer is not (reset mode: the acceptance registers), or ignored
    // (a request pending), or not requested, or not a frame the chip knows (the bytes say what
    // it sends): register by register.
    std::array<uint8_t, 13> bytes;
    const std::size_t n = pack_frame(frame, bytes);
    for (std::size_t k = 0; k < n; ++k) {
      write(static_cast<uint8_t>(FRAME + k), bytes[k]);
    }
    command(cmr);
    return;
  }
  // Operating mode, buffer released: the bytes land in the buffer (those past the frame's keep
  // what they held) and TR takes them, the frame being the one they describe.
  pack_frame(frame, tx_buffer_);
  tx_ = TxFrame{frame, (cmr & CMR_AT) != 0, (cmr & CMR_SRR) != 0};
  tx_complete_ = false;
  if (bus_ != nullptr) {
    bus_->tx_changed(node_);
  }
  if ((cmr & (CMR_RRB | CMR_CDO)) != 0) {
    command(static_cast<uint8_t>(cmr & (CMR_RRB | CMR_CDO)));  // what comes with TR
  }
}

void Sja1000::counters_written() {
  if (bus_ != nullptr) {
    bus_->counters_changed(node_);
  } else {
    update_error_status(now());
  }
}

void Sja1000::command(uint8_t cmr) {
  if (mod_ & MOD_RM) {
    return;  // commands have no effect in reset mode
  }
  if (cmr & (CMR_TR | CMR_SRR)) {
    if (!tx_) {
      if (auto frame = unpack_frame(tx_buffer_.data())) {
        // TR and AT together (or SRR and AT): single shot.
        tx_ = TxFrame{*frame, (cmr & CMR_AT) != 0, (cmr & CMR_SRR) != 0};
        tx_complete_ = false;
        if (bus_ != nullptr) {
          bus_->tx_changed(node_);
        }
      }
    }
  } else if ((cmr & CMR_AT) && tx_) {
    const SimTime at = now();
    const Frame f = tx_->frame;
    if (withdraw_tx(bus_, node_, tx_)) {
      tx_complete_ = false;
      set_ir(IR_TI, at);
      if (listener_ != nullptr) {
        listener_->transmission_dropped(at, f);
      }
    }
  }
  if (cmr & CMR_RRB) {
    fifo_release();
  }
  if (cmr & CMR_CDO) {
    data_overrun_ = false;
  }
}

void Sja1000::enter_reset() {
  mod_ |= MOD_RM;
  // Reset mode drops the pending request and empties the FIFO. Not modelled: aborting a frame
  // already on the wire (its outcome is fixed at its start of frame); it is not repeated.
  withdraw_tx(bus_, node_, tx_);
  tx_complete_ = true;
  rbsa_ = 0;
  fifo_used_ = 0;
  rmc_ = 0;
  data_overrun_ = false;
  ir_ = 0;
  if (bus_ != nullptr) {
    bus_->controller_changed(node_);
  }
}

void Sja1000::leave_reset() {
  mod_ &= static_cast<uint8_t>(~MOD_RM);
  if (bus_ == nullptr) {
    return;
  }
  bus_->controller_changed(node_);
  if (fc_.bus_off()) {
    bus_->restart(node_);  // bus-off recovery counts from here
  }
}

bool Sja1000::fifo_push(const Frame& frame) {
  const std::size_t n = packed_size(frame);
  if (fifo_used_ + n > kRxFifoBytes) {
    return false;
  }
  // The message goes in at the end of what the FIFO holds, wrapping round at its end.
  const std::size_t start = (rbsa_ + fifo_used_) % kRxFifoBytes;
  if (start + n <= kRxFifoBytes) {
    pack_frame(frame, fifo_.data() + start);  // in one piece: no copy
    fifo_used_ += n;
    ++rmc_;
    return true;
  }
  std::array<uint8_t, 13> bytes;
  pack_frame(frame, bytes);
  const std::size_t before_end = std::min(n, kRxFifoBytes - start);
  std::copy_n(bytes.begin(), before_end, fifo_.begin() + static_cast<std::ptrdiff_t>(start));
  std::copy_n(bytes.begin() + static_cast<std::ptrdiff_t>(before_end), n - before_end,
              fifo_.begin());
  fifo_used_ += n;
  ++rmc_;
  return true;
}

void Sja1000::fifo_release() {
  if (rmc_ == 0) {
    return;
  }
  const std::size_t n = packed_size(fifo_byte(0));  // the released message's bytes
  rbsa_ = (rbsa_ + n) % kRxFifoBytes;
  fifo_used_ -= std::min(n, fifo_used_);
  --rmc_;
}

void Sja1000::on_frame(SimTime at, const Frame& frame, bool own) {
  update_error_status(at);
  if (!accepts_all(amr_) && !accepts(acr_, amr_, (mod_ & MOD_AFM) != 0, frame)) {
    return;
  }
  const bool line_was_active = interrupt_line();
  if (!fifo_push(frame)) {
    // Data overrun: the message is lost, the ones already held stay.
    data_overrun_ = true;
    set_ir(IR_DOI, at);
    if (listener_ != nullptr) {
      listener_->overrun(at, frame);
    }
    return;
  }
  if (!line_was_active && interrupt_line() && on_interrupt) {
    on_interrupt(at);  // RI
  }
  if (listener_ != nullptr) {
    listener_->frame_received(at, frame, own);
  }
}

void Sja1000::on_tx_done(SimTime at) {
  update_error_status(at);
  if (!tx_) {
    return;
  }
  const Frame f = end_tx(at, true);
  if (listener_ != nullptr) {
    listener_->frame_transmitted(at, f);
  }
}

void Sja1000::on_tx_dropped(SimTime at) {
  if (!tx_) {
    return;
  }
  const Frame f = end_tx(at, false);
  if (listener_ != nullptr) {
    listener_->transmission_dropped(at, f);
  }
}

Frame Sja1000::end_tx(SimTime at, bool complete) {
  const Frame f = tx_->frame;
  tx_.reset();
  tx_complete_ = complete;
  set_ir(IR_TI, at);  // TI follows the end of a request, completed or not
  return f;
}

void Sja1000::on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed_bit) {
  // A new loss is captured, and raises ALI, only once ALC has been read (datasheet 6.4.8).
  if (!alc_armed_) {
    return;
  }
  // ALC holds the lost bit's number counted from ID.28 = 0 (SRTR 11, IDE 12, RTR 31).
  alc_ = static_cast<uint8_t>(std::clamp<int>(destuffed_bit - 1, 0, 31));
  alc_armed_ = false;
  set_ir(IR_ALI, at);
  if (listener_ != nullptr) {
    listener_->arbitration_lost(at, bit);
  }
}

void Sja1000::on_error(const BusErrorEvent& e) {
  update_error_status(e.at);
  if (ecc_armed_) {
    const uint8_t code = e.type == CanErrorType::bit     ? 0
                         : e.type == CanErrorType::form  ? 1
                         : e.type == CanErrorType::stuff ? 2
                                                         : 3;
    const uint8_t dir = e.role == ErrorRole::receiver ? 1 : 0;
    ecc_ = static_cast<uint8_t>((code << 6) | (dir << 5) |
                                ecc_segment(e, e.destuffed_bit, e.extended_frame));
    ecc_armed_ = false;
  }
  set_ir(IR_BEI, e.at);
  if (listener_ != nullptr) {
    listener_->bus_error(e);
  }
}

void Sja1000::on_state_change(SimTime at, ErrorState state) {
  const ErrorState before = state_;
  state_ = state;
  update_error_status(at);
  uint8_t bits = 0;
  // EPI: into error-passive, and from error-passive back to error-active (not into bus-off).
  const bool passive_before = before == ErrorState::passive;
  const bool passive_now = state == ErrorState::passive;
  if ((passive_now && !passive_before) ||
      (passive_before && (state == ErrorState::active || state == ErrorState::warning))) {
    bits |= IR_EPI;
  }
  if (state == ErrorState::bus_off) {
    // Bus-off puts the chip in reset mode; the host restarts it by clearing RM.
    mod_ |= MOD_RM;
    // A request stays in the transmit buffer and goes out after recovery, unless the host
    // requests reset mode meanwhile (write()).
    if (bus_ != nullptr) {
      bus_->controller_changed(node_);
    }
  }
  set_ir(bits, at);
  if (listener_ != nullptr) {
    listener_->state_changed(at, state, fc_.tec(), fc_.rec());
  }
}

}  // namespace canemu::model
