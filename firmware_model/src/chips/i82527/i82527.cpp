#include "canemu/firmware_model/chips/i82527/i82527.hpp"

#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model {

using namespace i82527;

namespace {

constexpr uint8_t kControlBits = CONTROL_INI | CONTROL_IE | CONTROL_SIE | CONTROL_EIE | CONTROL_CCE;
constexpr uint8_t kStatusWritable = STATUS_LEC | STATUS_TXOK | STATUS_RXOK;
constexpr uint8_t kLastTxObject = 14;  // object 15 is receive-only

}  // namespace

I82527::I82527(uint32_t crystal_hz) : crystal_hz_(crystal_hz) {}

void I82527::connect(CanBus& bus) {
  bus_ = &bus;
  node_ = bus.attach(*this);
}

SimTime I82527::now() const {
  return bus_ != nullptr ? bus_->now() : SimTime{};
}

void I82527::hardware_reset() {
  withdraw_tx(bus_, node_, tx_);  // one on the wire completes and updates no object
  tx_object_ = 0;
  control_ = CONTROL_INI;
  status_ = 0;
  cpu_interface_ = 0;
  clkout_ = 0;
  bus_config_ = 0;
  btr0_ = 0;
  btr1_ = 0;
  gms_ = {};
  gml_ = {};
  msg15_mask_ = {};
  objects_ = {};
  shadow_.reset();
  status_pending_ = false;
  error_status_ = 0;
  fc_.reset();
  if (bus_ != nullptr) {
    bus_->controller_changed(node_);
    bus_->counters_changed(node_);
  }
}

uint32_t I82527::sclk_hz() const {
  return (cpu_interface_ & CPUIF_DSC) ? crystal_hz_ / 2 : crystal_hz_;
}

NodeTiming I82527::timing() const {
  // BIT_TIMING0/1 have the SJA1000's BTR0/BTR1 fields (SJW, BRP; SPL, TSEG2, TSEG1), but one
  // quantum is (BRP + 1) periods of the system clock where the SJA1000's is 2 (BRP + 1) periods
  // of its oscillator: the same decoder on twice the clock, then stated in the 82527's own clock.
  // Decision: SCLK = crystal / 2 with DSC, the crystal without; DMC divides only the memory
  // clock (register access timing), which the model does not time.
  const uint32_t sclk = sclk_hz();
  NodeTiming t;
  t.nominal = sja1000::timing_from_btr(btr0_, btr1_, 2 * sclk);
  t.nominal.clock_hz = sclk;
  t.nominal.prescaler /= 2;
  return t;
}

// --- interrupts and status ---

uint8_t I82527::interrupt_value() const {
  // Highest priority first: status change, message 15, then messages 1..14 by number.
  // Decision: the register shows pending sources whatever CONTROL.IE says; IE gates the pin.
  if (status_pending_) {
    return INTERRUPT_STATUS;
  }
  if (objects_[kObjects - 1].flag0(INTPND)) {
    return INTERRUPT_MSG15;
  }
  for (uint8_t n = 1; n <= kLastTxObject; ++n) {
    if (objects_[n - 1].flag0(INTPND)) {
      return interrupt_for_message(n);
    }
  }
  return INTERRUPT_NONE;
}

bool I82527::interrupt_line() const {
  return (control_ & CONTROL_IE) != 0 && interrupt_value() != INTERRUPT_NONE;
}

template <typename F>
void I82527::raising(SimTime at, F change) {
  const bool was = interrupt_line();
  change();
  if (!was && interrupt_line() && on_interrupt) {
    on_interrupt(at);
  }
}

uint8_t I82527::status() const {
  uint8_t s = status_ & kStatusWritable;
  // WARN: a counter has reached the warning limit (96); BOFF: bus-off (TEC above 255). Both
  // follow the counters, and recovery clears them.
  if (fc_.bus_off() || fc_.tec() >= fc_.warning_limit() || fc_.rec() >= fc_.warning_limit()) {
    s |= STATUS_WARN;
  }
  if (fc_.bus_off()) {
    s |= STATUS_BOFF;
  }
  return s;
}

// Decision: with SIE, every TXOK, every RXOK and every new error code (LEC 1..6) raises the
// status change source; with EIE, every change of WARN or BOFF, both ways. Reading STATUS ends
// it, whatever raised it.
void I82527::status_change(SimTime at) {
  if (control_ & CONTROL_SIE) {
    raising(at, [this] { status_pending_ = true; });
  }
}

void I82527::update_error_status(SimTime at) {
  // EIE: an interrupt on every change of WARN or BOFF, both ways.
  const uint8_t bits = status() & (STATUS_WARN | STATUS_BOFF);
  if (bits == error_status_) {
    return;
  }
  error_status_ = bits;
  if (control_ & CONTROL_EIE) {
    raising(at, [this] { status_pending_ = true; });
  }
}

// --- registers ---

uint8_t I82527::read(uint8_t address) {
  switch (address) {
    case CONTROL:
      return control_;
    case STATUS: {
      const uint8_t s = status();
      status_pending_ = false;  // reading the status register ends the status change interrupt
      return s;
    }
    case CPU_INTERFACE:
      return cpu_interface_;  // RstSt reads 0: the model is never in the middle of a reset
    case HIGH_SPEED_READ:
    case HIGH_SPEED_READ + 1:
      return 0;
    case GMS:
    case GMS + 1:
      return gms_[address - GMS];
    case CLKOUT:
      return clkout_;
    case BUS_CONFIG:
      return bus_config_;
    case BIT_TIMING0:
      return btr0_;
    case BIT_TIMING1:
      return btr1_;
    case INTERRUPT:
      return interrupt_value();
    default:
      break;
  }
  if (address >= GML && address < GML + 4) {
    return gml_[address - GML];
  }
  if (address >= MSG15_MASK && address < MSG15_MASK + 4) {
    return msg15_mask_[address - MSG15_MASK];
  }
  const uint8_t row = address >> 4;
  const uint8_t offset = address & 0x0F;
  if (row >= 1 && row <= kObjects && offset < kObjectBytes) {
    return object(row).read(offset);
  }
  // Reserved addresses, among them 0x6F/0x7F where the CC770 shows its error counters: the
  // 82527 has no such registers.
  return 0xFF;
}

void I82527::write(uint8_t address, uint8_t value) {
  const bool cce = (control_ & CONTROL_CCE) != 0;
  switch (address) {
    case CONTROL:
      write_control(value);
      return;
    case STATUS:
      // Decision: the CPU may write LEC (7 to watch for the next code), TXOK and RXOK; WAKE, WARN
      // and BOFF are the chip's.
      status_ = static_cast<uint8_t>(value & kStatusWritable);
      return;
    case CPU_INTERFACE:
      // Decision: CCE alone opens the configuration registers (INI need not be set); the masks
      // and the message objects are writable at any time.
      if (cce) {
        cpu_interface_ = static_cast<uint8_t>(value & ~CPUIF_RSTST);
        config_changed();  // DSC changes the system clock
      }
      return;
    case GMS:
    case GMS + 1:
      gms_[address - GMS] = value;
      return;
    case CLKOUT:
      if (cce) {
        clkout_ = value;
      }
      return;
    case BUS_CONFIG:
      if (cce) {
        bus_config_ = value;
      }
      return;
    case BIT_TIMING0:
    case BIT_TIMING1:
      if (cce) {
        (address == BIT_TIMING0 ? btr0_ : btr1_) = value;
        config_changed();
      }
      return;
    default:
      break;
  }
  if (address >= GML && address < GML + 4) {
    gml_[address - GML] = value;
    return;
  }
  if (address >= MSG15_MASK && address < MSG15_MASK + 4) {
    msg15_mask_[address - MSG15_MASK] = value;
    return;
  }
  const uint8_t row = address >> 4;
  const uint8_t offset = address & 0x0F;
  if (row >= 1 && row <= kObjects && offset < kObjectBytes) {
    write_object(row, offset, value);
  }
}

void I82527::config_changed() {
  if (bus_ != nullptr) {
    bus_->controller_changed(node_);
  }
}

void I82527::write_control(uint8_t value) {
  const uint8_t before = control_;
  raising(now(), [&] { control_ = static_cast<uint8_t>(value & kControlBits); });
  if ((before ^ control_) & CONTROL_INI) {
    config_changed();
    // Clearing INI is the only way out of bus-off: recovery counts 128 x 11 recessive bits from
    // here (the chip set INI itself when it went bus-off).
    if (!(control_ & CONTROL_INI) && fc_.bus_off() && bus_ != nullptr) {
      bus_->restart(node_);
    }
  }
  refresh_tx();
}

void I82527::write_object(uint8_t n, uint8_t offset, uint8_t value) {
  MessageObject& o = object(n);
  raising(now(), [&] {
    const bool had_new = o.flag1(NEWDAT);
    o.write(offset, value);
    // Message 15: resetting NewDat releases the buffer, and the frame waiting in the shadow
    // register moves in (cc770.c reads message 15 before it clears NewDat for this reason).
    if (n == kObjects && offset == CTRL1 && had_new && !o.flag1(NEWDAT) && shadow_) {
      release_shadow();
    }
  });
  refresh_tx();
}

void I82527::release_shadow() {
  MessageObject& o = object(kObjects);
  o.store(*shadow_);
  shadow_.reset();
  o.set1(NEWDAT, true);
  if (o.flag0(RXIE)) {
    o.set0(INTPND, true);
  }
}

// --- transmission ---

uint8_t I82527::next_tx_object() const {
  // Lowest object number first, whatever the identifiers. A transmit object waits while CPUUpd
  // is set; for a receive object the same bit is MsgLst and does not hold a remote request back.
  for (uint8_t n = 1; n <= kLastTxObject; ++n) {
    const MessageObject& o = objects_[n - 1];
    if (o.valid() && o.flag1(TXRQST) && !(o.transmit() && o.flag1(CPUUPD))) {
      return n;
    }
  }
  return 0;
}

void I82527::refresh_tx() {
  if (tx_ && bus_ != nullptr && bus_->in_flight(node_)) {
    return;  // the frame on the wire stays; its end brings the next choice
  }
  const uint8_t n = next_tx_object();
  if (n == 0) {
    if (tx_) {
      tx_.reset();
      tx_object_ = 0;
      if (bus_ != nullptr) {
        bus_->tx_changed(node_);
      }
    }
    return;
  }
  const Frame f = object(n).frame();
  if (tx_ && tx_object_ == n && tx_->frame == f) {
    return;
  }
  tx_ = TxFrame{f, false, false};
  tx_object_ = n;
  if (bus_ != nullptr) {
    bus_->tx_changed(node_);
  }
}

void I82527::on_tx_done(SimTime at) {
  update_error_status(at);
  if (!tx_) {
    return;
  }
  const Frame f = tx_->frame;
  const uint8_t n = tx_object_;
  tx_.reset();
  tx_object_ = 0;
  raising(at, [&] {
    if (n != 0) {
      MessageObject& o = object(n);
      // Not modelled: NewDat of a transmit object (the chip's repetition when the CPU sets it
      // again during the transmission); a transmission leaves it as the CPU wrote it.
      o.set1(TXRQST, false);
      if (o.transmit()) {
        o.set1(RMTPND, false);  // a remote request, if there was one, is answered
      }
      // TXIE: IntPnd after the successful transmission (decision: also for the remote frame of
      // a receive object). An object that answered a remote frame interrupts only
      // now, not when the remote frame came (X-CAN-2i manual §10.9.2.5, SL-CANi footnote 1).
      if (o.flag0(TXIE)) {
        o.set0(INTPND, true);
      }
    }
    status_ = static_cast<uint8_t>((status_ & ~STATUS_LEC) | STATUS_TXOK);
    if (control_ & CONTROL_SIE) {
      status_pending_ = true;
    }
  });
  if (listener_ != nullptr) {
    listener_->frame_transmitted(at, f);
  }
  refresh_tx();
}

void I82527::on_tx_dropped(SimTime at) {
  // Only a frame that was on the wire at a hardware reset is single shot.
  if (!tx_) {
    return;
  }
  const Frame f = tx_->frame;
  tx_.reset();
  tx_object_ = 0;
  if (listener_ != nullptr) {
    listener_->transmission_dropped(at, f);
  }
  refresh_tx();
}

void I82527::on_arbitration_lost(SimTime at, uint16_t bit, uint16_t /*destuffed_bit*/) {
  // The 82527 retries by itself and has no arbitration-lost capture.
  if (listener_ != nullptr) {
    listener_->arbitration_lost(at, bit);
  }
  refresh_tx();
}

// --- reception ---

std::array<uint8_t, 4> I82527::mask_for(uint8_t n, bool extended) const {
  std::array<uint8_t, 4> mask = extended ? gml_ : std::array<uint8_t, 4>{gms_[0], gms_[1], 0, 0};
  if (n == kObjects) {
    // Message 15: its own mask AND the global one. Its extended layout starts with the
    // standard one, so the first 11 bits serve standard frames.
    for (std::size_t k = 0; k < 4; ++k) {
      mask[k] &= msg15_mask_[k];
    }
  }
  return mask;
}

void I82527::on_frame(SimTime at, const Frame& frame, bool /*own*/) {
  update_error_status(at);
  // Decision: RXOK for any frame received without error, whether an object takes it or not;
  // LEC back to 0 on every error-free transfer.
  raising(at, [&] {
    status_ = static_cast<uint8_t>((status_ & ~STATUS_LEC) | STATUS_RXOK);
    if (control_ & CONTROL_SIE) {
      status_pending_ = true;
    }
  });
  // The first matching object by number takes the frame: data frames go to receive objects
  // (DIR = 0), remote frames to transmit objects (DIR = 1). Object 15 comes last.
  // Decision: object 15 is receive-only and its DIR bit chooses which kind it stores (0: data
  // frames, 1: remote frames), the original 82527's one-kind-only message 15 (datasheet; Linux
  // cc770) as the SORCUS buffer 15 uses it (Data-only or Remote-only, X-CAN-2i manual §10.9.2.8).
  uint8_t taker = 0;
  for (uint8_t n = 1; n <= kObjects && taker == 0; ++n) {
    const MessageObject& o = object(n);
    if (o.valid() && o.transmit() == frame.remote() &&
        matches(o, frame, mask_for(n, o.extended()))) {
      taker = n;
    }
  }
  if (taker == 0) {
    return;
  }
  if (frame.remote() && taker != kObjects) {
    // A transmit object asked for by a remote frame: RmtPnd and TxRqst; it answers by itself
    // unless CPUUpd holds it (then it goes once the CPU resets CPUUpd). Decision: the remote
    // frame's DLC is not stored, the object answers with its own.
    MessageObject& o = object(taker);
    o.set1(RMTPND, true);
    o.set1(TXRQST, true);
    if (listener_ != nullptr) {
      listener_->frame_received(at, frame, false);
    }
    refresh_tx();
    return;
  }
  receive_into(taker, frame, at);
}

void I82527::receive_into(uint8_t n, const Frame& frame, SimTime at) {
  MessageObject& o = object(n);
  if (n == kObjects && o.flag1(NEWDAT)) {
    // Message 15 still holds unread data: the frame waits in the shadow register; a frame that
    // finds the shadow register full overwrites it and sets MsgLst. Decision: a frame entering
    // the shadow raises no interrupt of its own; it sets NewDat and IntPnd (RXIE) when it
    // moves in.
    if (shadow_) {
      const Frame lost = *shadow_;
      shadow_ = frame;
      o.set1(MSGLST, true);
      if (listener_ != nullptr) {
        listener_->overrun(at, lost);
      }
    } else {
      shadow_ = frame;
    }
    if (listener_ != nullptr) {
      listener_->frame_received(at, frame, false);
    }
    return;
  }
  const bool overwritten = o.flag1(NEWDAT);
  const Frame lost = o.frame_as(frame.remote());
  bool request_answered = false;
  raising(at, [&] {
    o.store(frame);
    o.set1(NEWDAT, true);
    if (overwritten) {
      o.set1(MSGLST, true);  // MsgLst: stored while NewDat was still set
    }
    // Decision: a receive object whose remote request is still pending drops it when the data
    // frame it asks for arrives anyway.
    if (n != kObjects && o.flag1(TXRQST)) {
      o.set1(TXRQST, false);
      request_answered = true;
    }
    if (o.flag0(RXIE)) {
      o.set0(INTPND, true);
    }
  });
  if (listener_ != nullptr) {
    if (overwritten) {
      listener_->overrun(at, lost);
    }
    listener_->frame_received(at, frame, false);
  }
  if (request_answered) {
    refresh_tx();
  }
}

// --- errors ---

void I82527::on_error(const BusErrorEvent& e) {
  update_error_status(e.at);
  uint8_t lec = LEC_BIT1;
  switch (e.type) {
    case CanErrorType::stuff:
      lec = LEC_STUFF;
      break;
    case CanErrorType::form:
      lec = LEC_FORM;
      break;
    case CanErrorType::ack:
      lec = LEC_ACK;
      break;
    case CanErrorType::crc:
      lec = LEC_CRC;
      break;
    case CanErrorType::bit:
      // Bit1Error when the node sent recessive and saw dominant, Bit0Error the other way.
      // Decision: the level the node sent at that bit of its own frame decides; a bit error
      // outside its frame counts as Bit1Error.
      if (tx_ && e.role == ErrorRole::transmitter && e.in_frame) {
        const EncodedFrame bits = encode(tx_->frame);
        if (e.bit < bits.length && !bits.level_at(e.bit)) {
          lec = LEC_BIT0;
        }
      }
      break;
  }
  raising(e.at, [&] {
    status_ = static_cast<uint8_t>((status_ & ~STATUS_LEC) | lec);
    if (control_ & CONTROL_SIE) {
      status_pending_ = true;
    }
  });
  if (listener_ != nullptr) {
    listener_->bus_error(e);
  }
  // The frame on the wire is destroyed: the next attempt sends what the objects want now. A
  // request withdrawn while its frame was on the wire (TxRqst reset by the CPU) is not
  // repeated (datasheet: the chip chooses the object to send before each attempt).
  if (e.role == ErrorRole::transmitter && tx_ && bus_ != nullptr) {
    const uint8_t n = next_tx_object();
    if (n != tx_object_ || (n != 0 && object(n).frame() != tx_->frame)) {
      tx_.reset();
      tx_object_ = 0;
      if (n != 0) {
        tx_ = TxFrame{object(n).frame(), false, false};
        tx_object_ = n;
      }
      bus_->tx_changed(node_);
    }
  }
}

void I82527::on_state_change(SimTime at, ErrorState state) {
  if (state == ErrorState::bus_off) {
    // Bus-off sets INI; the CPU leaves it by clearing INI. Pending requests stay in the objects.
    control_ |= CONTROL_INI;
    config_changed();
  }
  update_error_status(at);
  if (listener_ != nullptr) {
    listener_->state_changed(at, state, fc_.tec(), fc_.rec());
  }
}

}  // namespace canemu::model
