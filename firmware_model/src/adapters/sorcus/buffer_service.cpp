// The SORCUS buffer manager's interrupt service: the 82527's status changes (to the owner),
// buffers 1..14 (transmissions done, receptions), buffer 15 (passive objects, unconfigured
// messages), and the FIFO's next request.
#include <algorithm>

#include "canemu/firmware_model/adapters/sorcus/buffer_manager.hpp"

namespace canemu::model::sorcus {

using namespace i82527;

uint8_t serve_status_register(I82527& chip, uint8_t& error_bits, uint16_t& last_lec) {
  const uint8_t s = chip.read(STATUS);
  const uint8_t lec = s & STATUS_LEC;
  if (lec != LEC_NONE && lec != LEC_UNUSED) {
    last_lec = lec;
  }
  chip.write(STATUS, LEC_UNUSED);
  const uint8_t bits = s & (STATUS_WARN | STATUS_BOFF);
  const uint8_t rising = bits & ~error_bits;
  error_bits = bits;
  return rising;
}

void BufferManager::service() {
  // Served until the interrupt register reads 0; serving one source may raise the next (message
  // 15's shadow register moving in).
  for (int guard = 0; guard < 64 && !events_.hold(); ++guard) {
    const uint8_t v = chip_.read(INTERRUPT);
    if (v == INTERRUPT_NONE) {
      return;
    }
    if (v == INTERRUPT_STATUS) {
      events_.status_changed();  // the owner reads STATUS, which ends this source
    } else if (v == INTERRUPT_MSG15) {
      serve_buffer15();
    } else {
      serve_buffer(static_cast<uint8_t>(v - 2));
    }
  }
}

Frame BufferManager::read_frame(uint8_t n, bool remote) {
  MessageObject o;
  for (uint8_t k = 0; k < kObjectBytes; ++k) {
    o.write(k, chip_.read(static_cast<uint8_t>(message(n) + k)));
  }
  return o.frame_as(remote);
}

void BufferManager::serve_buffer(uint8_t n) {
  const uint8_t base = message(n);
  chip_.write(base + CTRL0, pair_write(0, INTPND));
  const uint8_t ctrl1 = chip_.read(base + CTRL1);
  const bool transmit = (chip_.read(base + CONFIG) & CONFIG_DIR) != 0;
  const Buffer& b = buffers_[n - 1];
  if (!transmit && pair_is_set(ctrl1, NEWDAT)) {
    const Frame frame = read_frame(n, false);
    chip_.write(base + CTRL1, pair_write(0, NEWDAT | MSGLST));
    if (b.busy && !pair_is_set(ctrl1, TXRQST)) {
      tx_done(n);  // its remote frame went before the answer came
    }
    if (b.owner >= 0) {
      events_.received(b.owner, frame, pair_is_set(ctrl1, MSGLST));
    }
    return;
  }
  if (!pair_is_set(ctrl1, TXRQST)) {
    tx_done(n);
  }
}

void BufferManager::tx_done(uint8_t n) {
  Buffer& b = buffers_[n - 1];
  if (b.busy) {
    b.busy = false;
    const SendRequest r = b.sending;
    b.sending = SendRequest{};
    if (r.message && r.message->remote) {
      chip_.write(message(n) + CTRL0, pair_write(0, MSGVAL));
    }
    events_.sent(r, false);
  } else if (b.owner >= 0) {
    const ManagedObject& o = objects_[static_cast<std::size_t>(b.owner)];
    if (o.send && o.passive) {
      events_.sent(SendRequest{b.owner, false, std::nullopt}, true);  // answered by itself
    }
  }
  if (b.owner >= 0) {
    const ManagedObject& o = objects_[static_cast<std::size_t>(b.owner)];
    if (o.send && !o.passive && !o.general) {
      chip_.write(message(n) + CTRL1, pair_write(CPUUPD));
    }
  }
  next_from_fifo(n);
}

void BufferManager::next_from_fifo(uint8_t n) {
  Buffer& b = buffers_[n - 1];
  if (b.busy) {
    return;
  }
  auto busy_elsewhere = [this](int object) {
    return std::any_of(buffers_.begin(), buffers_.end(), [object](const Buffer& x) {
      return x.busy && x.sending.object == object && !x.sending.message;
    });
  };
  for (auto it = fifo_.begin(); it != fifo_.end(); ++it) {
    const ManagedObject& o = objects_[static_cast<std::size_t>(it->object)];
    const bool fits = b.permanent ? o.buffer == n : o.buffer == 0 || o.buffer == 15;
    // An object whose frame is still pending in another buffer waits, so its frames keep
    // their order.
    if (fits && (it->message || !busy_elsewhere(it->object))) {
      const SendRequest r = *it;
      fifo_.erase(it);
      start_on(n, r);
      return;
    }
  }
}

void BufferManager::serve_buffer15() {
  const uint8_t base = message(15);
  const bool remote = (chip_.read(base + CONFIG) & CONFIG_DIR) != 0;
  const Frame frame = read_frame(15, remote);
  const bool lost = pair_is_set(chip_.read(base + CTRL1), MSGLST);
  // IntPnd first, then NewDat and MsgLst: resetting NewDat lets the shadow register's frame in
  // (which raises the next interrupt).
  chip_.write(base + CTRL0, pair_write(0, INTPND));
  chip_.write(base + CTRL1, pair_write(0, NEWDAT | MSGLST));
  const int k = find(frame.id(), frame.extended());
  if (k < 0) {
    events_.unconfigured(frame);
    return;
  }
  const ManagedObject& o = objects_[static_cast<std::size_t>(k)];
  if (remote) {
    if (o.send && o.passive) {
      // Strategy C: the driver loads the object into a temporary buffer and sends its data.
      (void)request(SendRequest{k, false, std::nullopt});
    }
    return;
  }
  events_.received(k, frame, lost);
}

}  // namespace canemu::model::sorcus
