// The X-CAN-2i MDD's interrupt service: the 82527's status changes (the error callback), buffers
// 1..14 (transmissions done, receptions), buffer 15 (passive objects, unconfigured messages),
// and what follows from them: callbacks, completions, the FIFO's next request.
#include <algorithm>

#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

namespace canemu::model::sorcus {

using namespace i82527;

void XcanModule::service(unsigned i) {
  Interface& f = ifaces_[i];
  // Served until the interrupt register reads 0; serving one source may raise the next (message
  // 15's shadow register moving in).
  for (int guard = 0; guard < 64; ++guard) {
    const uint8_t v = f.chip.read(INTERRUPT);
    if (v == INTERRUPT_NONE) {
      return;
    }
    if (v == INTERRUPT_STATUS) {
      serve_status(i);
    } else if (v == INTERRUPT_MSG15) {
      serve_buffer15(i);
    } else {
      serve_buffer(i, static_cast<uint8_t>(v - 2));
    }
  }
}

void XcanModule::serve_status(unsigned i) {
  Interface& f = ifaces_[i];
  const uint8_t s = f.chip.read(STATUS);
  const uint8_t lec = s & STATUS_LEC;
  if (lec != LEC_NONE && lec != LEC_UNUSED) {
    f.last_lec = lec;  // the high word of the state word: the 82527's codes are the manual's
  }
  f.chip.write(STATUS, LEC_UNUSED);  // TXOK, RXOK reset; LEC 7 shows whether a new code comes
  const uint8_t bits = s & (STATUS_WARN | STATUS_BOFF);
  const uint8_t rising = bits & ~f.error_bits;
  f.error_bits = bits;
  // «Ein Fehlerstand > 96 wird als 'Stark gestörter Bus' interpretiert und genau wie der
  // Übergang in die Betriebsart 'Bus-Off' mit einem Interrupt signalisiert.» The 82527's WARN
  // is that level (decision: its limit, 96, as the chip has it). One callback per rise of WARN
  // or BOFF; none when they fall (decision: the manual names only these two events).
  if (rising != 0) {
    error_callback(i);
  }
}

void XcanModule::error_callback(unsigned i) {
  const ULONG state = bus_state(i);
  for (const auto& [h, c] : channels_) {
    if (c.iface == i && c.kind == Kind::bus_control) {
      XcanCallback cb;
      cb.arg = CallbackArg::status;
      cb.status = state;
      emit(h, c, cb);
    }
  }
}

Frame XcanModule::read_frame(unsigned i, uint8_t n, bool remote) {
  MessageObject o;
  for (uint8_t k = 0; k < kObjectBytes; ++k) {
    o.write(k, ifaces_[i].chip.read(static_cast<uint8_t>(message(n) + k)));
  }
  return o.frame_as(remote);
}

void XcanModule::serve_buffer(unsigned i, uint8_t n) {
  Interface& f = ifaces_[i];
  I82527& chip = f.chip;
  const uint8_t base = message(n);
  chip.write(base + CTRL0, pair_write(0, INTPND));
  const uint8_t ctrl1 = chip.read(base + CTRL1);
  const bool transmit = (chip.read(base + CONFIG) & CONFIG_DIR) != 0;
  const Buffer& b = f.buffers[n - 1];
  if (!transmit && pair_is_set(ctrl1, NEWDAT)) {
    const Frame frame = read_frame(i, n, false);
    chip.write(base + CTRL1, pair_write(0, NEWDAT | MSGLST));
    if (b.busy && !pair_is_set(ctrl1, TXRQST)) {
      tx_done(i, n);  // its remote frame went before the answer came
    }
    if (b.owner >= 0) {
      received(i, b.owner, frame);
    }
    return;
  }
  if (!pair_is_set(ctrl1, TXRQST)) {
    tx_done(i, n);
  }
}

void XcanModule::tx_done(unsigned i, uint8_t n) {
  Interface& f = ifaces_[i];
  Buffer& b = f.buffers[n - 1];
  if (b.busy) {
    b.busy = false;
    const Request r = b.sending;
    b.sending = Request{};
    if (r.message && (r.message->usFlags & XCAN_REMOTE)) {
      f.chip.write(message(n) + CTRL0, pair_write(0, MSGVAL));
    }
    finished(i, r);
  } else if (b.owner >= 0) {
    const Object& o = f.objects[static_cast<std::size_t>(b.owner)];
    if (o.role == Role::passive_send) {
      finished(i, Request{b.owner, false, std::nullopt});  // answered a remote frame by itself
    }
  }
  if (b.owner >= 0 && f.objects[static_cast<std::size_t>(b.owner)].role == Role::active_send) {
    f.chip.write(message(n) + CTRL1, pair_write(CPUUPD));
  }
  next_from_fifo(i, n);
}

void XcanModule::next_from_fifo(unsigned i, uint8_t n) {
  Interface& f = ifaces_[i];
  Buffer& b = f.buffers[n - 1];
  if (b.busy) {
    return;
  }
  auto busy_elsewhere = [&f](int object) {
    return std::any_of(f.buffers.begin(), f.buffers.end(), [object](const Buffer& x) {
      return x.busy && x.owner == object && !x.sending.message;
    });
  };
  for (auto it = f.fifo.begin(); it != f.fifo.end(); ++it) {
    const Object& o = f.objects[static_cast<std::size_t>(it->object)];
    const bool fits = b.permanent ? o.buffer == n : o.buffer == 0 || o.buffer == 15;
    // An object whose frame is still pending in another buffer waits, so its frames keep
    // their order.
    if (fits && (it->message || !busy_elsewhere(it->object))) {
      const Request r = *it;
      f.fifo.erase(it);
      start_on(i, n, r);
      return;
    }
  }
}

void XcanModule::finished(unsigned i, const Request& r) {
  Interface& f = ifaces_[i];
  Object& o = f.objects[static_cast<std::size_t>(r.object)];
  if (r.remote) {
    return;  // a remote request: the answer ends it
  }
  ++o.count;
  if (!o.no_int) {
    for (const auto& [h, c] : channels_) {
      if (c.iface == i && c.object == r.object) {
        emit(h, c, XcanCallback{});
      }
    }
  }
  complete_waiters(i, r.object, false, {});
}

void XcanModule::received(unsigned i, int object, const Frame& frame) {
  Interface& f = ifaces_[i];
  Object& o = f.objects[static_cast<std::size_t>(object)];
  if (o.role != Role::active_receive && o.role != Role::passive_receive) {
    return;
  }
  o.size = frame.dlc() > 8 ? 8 : frame.dlc();
  std::fill(o.data.begin(), o.data.end(), uint8_t{0});
  std::copy_n(frame.data().begin(), o.size, o.data.begin());
  ++o.count;
  const std::vector<uint8_t> data(o.data.begin(), o.data.begin() + o.size);
  for (auto& [h, c] : channels_) {
    if (c.iface != i || c.object != object) {
      continue;
    }
    c.new_data = true;
    if (o.role == Role::passive_receive || c.start_pending) {
      c.start_pending = false;
      XcanCallback cb;
      cb.arg = CallbackArg::data;
      cb.size = o.size;
      cb.data = o.data;
      emit(h, c, cb);
    }
  }
  complete_waiters(i, object, true, data);
}

void XcanModule::serve_buffer15(unsigned i) {
  Interface& f = ifaces_[i];
  I82527& chip = f.chip;
  const uint8_t base = message(15);
  const bool remote = (chip.read(base + CONFIG) & CONFIG_DIR) != 0;
  const Frame frame = read_frame(i, 15, remote);
  // IntPnd first, then NewDat and MsgLst: resetting NewDat lets the shadow register's frame in
  // (which raises the next interrupt).
  chip.write(base + CTRL0, pair_write(0, INTPND));
  chip.write(base + CTRL1, pair_write(0, NEWDAT | MSGLST));
  const int k = find_object(f, frame.id(), frame.extended());
  if (k < 0) {
    unconfigured(i, frame);
    return;
  }
  const Object& o = f.objects[static_cast<std::size_t>(k)];
  if (remote) {
    if (o.role == Role::passive_send) {
      // Strategy C: the driver loads the object into a temporary buffer and sends its data.
      (void)request(i, Request{k, false, std::nullopt});
    }
    return;
  }
  received(i, k, frame);
}

void XcanModule::unconfigured(unsigned i, const Frame& frame) {
  Interface& f = ifaces_[i];
  // «…werden zwar vom MDD verworfen, belasten aber dennoch die CPU», unless a filter channel
  // is open: its callback gets every unconfigured message that passed.
  const Channel* c = f.filter_channel != 0 ? find(f.filter_channel) : nullptr;
  if (c == nullptr || !c->callback) {
    ++f.discarded;
    return;
  }
  XcanCallback cb;
  cb.arg = CallbackArg::message;
  cb.message.ulCanId = frame.id();
  cb.message.usFlags = static_cast<USHORT>((frame.extended() ? XCAN_29BIT_ID : 0) |
                                           (frame.remote() ? XCAN_REMOTE : 0));
  // «usDataSize … 0 wenn der Nur-Empfangspuffer für Remote-Frames konfiguriert ist»
  cb.message.usDataSize = frame.remote() ? 0 : static_cast<USHORT>(frame.data().size());
  if (!frame.remote()) {
    std::copy(frame.data().begin(), frame.data().end(), cb.message.aucData);
  }
  emit(f.filter_channel, *c, cb);
}

}  // namespace canemu::model::sorcus
