// The channel data path of the VCI libraries: reading and writing a channel's rings in shared
// memory, waiting on their eventfds, without a round trip to canemud.
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <mutex>
#include <string>

#include <sched.h>
#include <time.h>
#include <unistd.h>

#include <fmt/format.h>

#include "canemu/ipc/clock.hpp"
#include "vci_core.hpp"

namespace canemu::client::vci {

namespace {

int64_t now_ms() {
  return ipc::monotonic_ns() / 1'000'000;
}

// Milliseconds left until `deadline_ms` (-1: forever).
int left_ms(int64_t deadline_ms) {
  if (deadline_ms < 0) {
    return -1;
  }
  return static_cast<int>(std::max<int64_t>(0, deadline_ms - now_ms()));
}

}  // namespace

namespace {

// CLOCK_MONOTONIC_COARSE in milliseconds: a clock read without a system call, good to a few ms.
int64_t coarse_ms() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC_COARSE, &ts);
  return int64_t{ts.tv_sec} * 1000 + ts.tv_nsec / 1'000'000;
}

// A blocking wait on a ring looks at the connection at least this often.
constexpr int kLinkWaitSliceMs = 100;

}  // namespace

HRESULT channel_link(ChannelObj& c, bool now) {
  Rings& r = *c.rings;
  if (!r.link_lost.load(std::memory_order_acquire)) {
    if (!now) {
      const int64_t t = coarse_ms();
      if (t - r.link_checked_ms.load(std::memory_order_relaxed) < kLinkCheckMs) {
        return VCI_OK;
      }
      r.link_checked_ms.store(t, std::memory_order_relaxed);
    }
    std::string why;
    if (Library::get().link(r.generation, why) == VCI_OK) {
      return VCI_OK;
    }
    std::lock_guard lock(r.lost_mutex);
    if (!r.link_lost.load(std::memory_order_relaxed)) {
      r.lost_reason = std::move(why);
      r.link_lost.store(true, std::memory_order_release);
    }
  }
  std::lock_guard lock(r.lost_mutex);
  set_detail(r.lost_reason);
  return VCI_E_DISCONNECTED;
}

int timeout_of(uint32_t ms) {
  return ms == 0xFFFFFFFFU ? -1 : static_cast<int>(std::min<uint32_t>(ms, 0x7FFFFFFF));
}

namespace {
// A pollable channel after a read found its ring empty or a blocking wait drained the eventfd:
// arms the eventfd when the ring is empty (the next put writes it), makes it readable when
// messages wait.
void keep_pollable(ChannelObj& c) {
  if (!c.pollable.load(std::memory_order_relaxed)) {
    return;
  }
  ipc::RingReader& rx = c.rings->rx;
  if (rx.fill_count() == 0) {
    if (rx.own_event().waiting->load(std::memory_order_relaxed) != 0) {
      return;  // still armed: no signal came since, the next one writes the eventfd
    }
    rx.disarm();  // drops stale wake-ups
    if (rx.arm_unless_filled()) {
      return;
    }
  }
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(c.rings->pair.rx().reader_event(), &one, sizeof one);
}
}  // namespace

int channel_poll_fd(ChannelObj& c) {
  c.pollable.store(true, std::memory_order_relaxed);
  keep_pollable(c);
  return c.rings->pair.rx().reader_event();
}

namespace {
// One message if one waits; VCI_E_RXQUEUE_EMPTY otherwise, VCI_E_DISCONNECTED when canemud
// is gone (what it delivered before is read first).
HRESULT take_one(ChannelObj& c, void* msg) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  switch (c.rings->rx.get(msg)) {
    case ipc::RingStatus::ok:
      return VCI_OK;
    case ipc::RingStatus::empty:
      keep_pollable(c);
      return channel_link(c, false) == VCI_OK ? VCI_E_RXQUEUE_EMPTY : VCI_E_DISCONNECTED;
    default:
      set_detail("the receive ring is corrupted");
      return VCI_E_UNEXPECTED;
  }
}

// Waits for `ring`'s event up to `timeout` ms (-1: forever) in slices, looking at the connection
// after each: VCI_OK when signalled, VCI_E_TIMEOUT, or VCI_E_DISCONNECTED when canemud is gone.
template <class Ring>
HRESULT wait_event(ChannelObj& c, const Ring& ring, int timeout) {
  const int64_t deadline = timeout < 0 ? -1 : now_ms() + timeout;
  while (true) {
    const int left = left_ms(deadline);
    if (ring.wait(left < 0 ? kLinkWaitSliceMs : std::min(left, kLinkWaitSliceMs))) {
      return VCI_OK;
    }
    if (HRESULT hr = channel_link(c, true); hr != VCI_OK) {
      return hr;
    }
    if (left_ms(deadline) == 0) {
      return VCI_E_TIMEOUT;
    }
  }
}
}  // namespace

HRESULT channel_peek(ChannelObj& c, void* msg) {
  const HRESULT hr = take_one(c, msg);
  if (hr == VCI_E_RXQUEUE_EMPTY) {
    c.rings->rx_looks.missed();  // a polling loop gives canemud its turn
  } else if (hr == VCI_OK) {
    c.rings->rx_looks.hit();
  }
  return hr;
}

HRESULT channel_read(ChannelObj& c, uint32_t timeout_ms, void* msg) {
  if (timeout_ms == 0) {  // only a look
    const HRESULT hr = channel_peek(c, msg);
    return hr == VCI_E_RXQUEUE_EMPTY ? VCI_E_TIMEOUT : hr;
  }
  HRESULT hr = take_one(c, msg);
  if (hr != VCI_E_NOT_INITIALIZED) {
    c.rings->rx_looks.hit();  // a message, or waiting for one: not polling
  }
  if (hr != VCI_E_RXQUEUE_EMPTY) {
    return hr;
  }
  ipc::RingReader& rx = c.rings->rx;
  const int timeout = timeout_of(timeout_ms);
  const int64_t deadline = timeout < 0 ? -1 : now_ms() + timeout;
  // Waiting for one message whatever the application's threshold.
  const uint32_t threshold = rx.threshold();
  rx.set_threshold(1);
  while (true) {
    hr = take_one(c, msg);
    if (hr != VCI_E_RXQUEUE_EMPTY) {
      break;
    }
    hr = wait_event(c, rx, left_ms(deadline));
    if (hr != VCI_OK) {
      // One more look: a message that came as the time ran out.
      if (const HRESULT last = take_one(c, msg); last != VCI_E_RXQUEUE_EMPTY) {
        hr = last;
      }
      break;
    }
  }
  rx.set_threshold(threshold);
  keep_pollable(c);
  return hr;
}

HRESULT check_tx_message(const void* msg, std::size_t element_size, bool can_fd) {
  uint32_t id = 0;
  CANMSGINFO info{};
  if (element_size == sizeof(CANMSG2)) {
    std::memcpy(&id, static_cast<const uint8_t*>(msg) + offsetof(CANMSG2, dwMsgId), sizeof id);
    std::memcpy(&info, static_cast<const uint8_t*>(msg) + offsetof(CANMSG2, uMsgInfo), sizeof info);
  } else if (element_size == sizeof(CANMSG)) {
    std::memcpy(&id, static_cast<const uint8_t*>(msg) + offsetof(CANMSG, dwMsgId), sizeof id);
    std::memcpy(&info, static_cast<const uint8_t*>(msg) + offsetof(CANMSG, uMsgInfo), sizeof info);
  } else {
    return VCI_OK;
  }
  if (info.Bytes.bType != CAN_MSGTYPE_DATA) {
    return VCI_OK;  // the firmware drops what is not a data message (counted)
  }
  if (element_size == sizeof(CANMSG2) && !can_fd && (info.Bits.edl != 0 || info.Bits.fdr != 0)) {
    set_call_detail(VCI_E_INVALIDARG,
                    fmt::format("a CAN FD message (id 0x{:X}, edl = {}, fdr = {}) on a controller "
                                "without CAN FD (no CAN_FEATURE_EXTDATA); the message was not "
                                "queued",
                                id, unsigned{info.Bits.edl}, unsigned{info.Bits.fdr}));
    return VCI_E_INVALIDARG;
  }
  const bool ext = info.Bits.ext != 0;
  const uint32_t max = ext ? CAN_MSGID_MASK29 : CAN_MSGID_MASK11;
  if (id <= max) {
    return VCI_OK;
  }
  set_call_detail(VCI_E_INVALIDARG,
                  fmt::format("identifier 0x{:X} does not fit {} bits (ext = {}: at most 0x{:X}); "
                              "the message was not queued",
                              id, ext ? 29 : 11, ext ? 1 : 0, max));
  return VCI_E_INVALIDARG;
}

namespace {
// Puts one message if there is room; VCI_E_TXQUEUE_FULL otherwise, VCI_E_DISCONNECTED when
// canemud is gone (nobody would take it).
HRESULT put_one(ChannelObj& c, const void* msg) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  if (!c.rings->has_tx) {
    return VCI_E_ACCESSDENIED;  // initialized without a transmit FIFO
  }
  if (const HRESULT hr = check_tx_message(msg, c.rings->pair.element_size(), c.rings->can_fd);
      hr != VCI_OK) {
    return hr;
  }
  if (channel_link(c, false) != VCI_OK) {
    return VCI_E_DISCONNECTED;
  }
  switch (c.rings->tx.put(msg)) {
    case ipc::RingStatus::ok:
      return VCI_OK;
    case ipc::RingStatus::full:
      return VCI_E_TXQUEUE_FULL;
    default:
      set_detail("the transmit ring is corrupted");
      return VCI_E_UNEXPECTED;
  }
}
}  // namespace

HRESULT channel_post(ChannelObj& c, const void* msg) {
  const HRESULT hr = put_one(c, msg);
  if (hr == VCI_E_TXQUEUE_FULL) {
    c.rings->tx_looks.missed();  // a sender retrying in a loop gives canemud its turn
  } else if (hr == VCI_OK) {
    c.rings->tx_looks.hit();
  }
  return hr;
}

HRESULT channel_send(ChannelObj& c, uint32_t timeout_ms, const void* msg) {
  if (timeout_ms == 0) {
    return channel_post(c, msg);
  }
  HRESULT hr = put_one(c, msg);
  if (c.rings) {
    c.rings->tx_looks.hit();  // queued, or waiting for room: not polling
  }
  if (hr != VCI_E_TXQUEUE_FULL) {
    return hr;
  }
  ipc::RingWriter& tx = c.rings->tx;
  const int timeout = timeout_of(timeout_ms);
  const int64_t deadline = timeout < 0 ? -1 : now_ms() + timeout;
  const uint32_t threshold = tx.threshold();
  tx.set_threshold(1);
  while (true) {
    hr = put_one(c, msg);
    if (hr != VCI_E_TXQUEUE_FULL) {
      break;
    }
    hr = wait_event(c, tx, left_ms(deadline));
    if (hr != VCI_OK) {
      // One more try: room that came as the time ran out.
      if (const HRESULT last = put_one(c, msg); last != VCI_E_TXQUEUE_FULL) {
        hr = last;
      }
      break;
    }
  }
  tx.set_threshold(threshold);
  return hr;
}

HRESULT channel_read_many(ChannelObj& c, uint32_t timeout_ms, void* msgs, uint32_t count,
                          uint32_t& done) {
  done = 0;
  if (count == 0) {
    return VCI_OK;
  }
  auto* out = static_cast<uint8_t*>(msgs);
  HRESULT hr = timeout_ms == 0 ? channel_peek(c, out) : channel_read(c, timeout_ms, out);
  if (hr != VCI_OK) {
    return hr;
  }
  const std::size_t size = c.rings->pair.element_size();
  for (done = 1; done < count; ++done) {
    if (take_one(c, out + done * size) != VCI_OK) {
      break;
    }
  }
  return VCI_OK;
}

HRESULT channel_send_many(ChannelObj& c, uint32_t timeout_ms, const void* msgs, uint32_t count,
                          uint32_t& done) {
  done = 0;
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  const auto* in = static_cast<const uint8_t*>(msgs);
  const std::size_t size = c.rings->pair.element_size();
  for (; done < count; ++done) {
    const HRESULT hr = timeout_ms == 0 ? channel_post(c, in + done * size)
                                       : channel_send(c, timeout_ms, in + done * size);
    if (hr != VCI_OK) {
      // Some queued: success with their count (vcinpl.h); none: the FIFO's refusal.
      return done > 0 ? VCI_OK : hr;
    }
  }
  return VCI_OK;
}

HRESULT channel_wait_rx(ChannelObj& c, uint32_t timeout_ms) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  const HRESULT hr = wait_event(c, c.rings->rx, timeout_of(timeout_ms));
  keep_pollable(c);
  return hr;
}

HRESULT channel_wait_tx(ChannelObj& c, uint32_t timeout_ms) {
  if (!c.rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  // The C API's transmit event means room: at least the threshold's free entries. A FIFO that
  // has them already (a new one, or one canemud emptied) is not waited on (docs/vci.md).
  const ipc::RingWriter& tx = c.rings->tx;
  const uint32_t capacity = c.rings->pair.tx().memory().capacity();
  if (c.rings->has_tx && capacity - tx.fill_count() >= std::max<uint32_t>(tx.threshold(), 1)) {
    return VCI_OK;
  }
  return wait_event(c, tx, timeout_of(timeout_ms));
}

uint8_t rx_load(const ChannelObj& c) {
  if (!c.rings) {
    return 0;
  }
  return static_cast<uint8_t>(uint64_t{c.rings->rx.fill_count()} * 100 /
                              c.rings->pair.rx().memory().capacity());
}

uint8_t tx_load(const ChannelObj& c) {
  if (!c.rings || !c.rings->has_tx) {
    return 0;
  }
  return static_cast<uint8_t>(uint64_t{c.rings->tx.fill_count()} * 100 /
                              c.rings->pair.tx().memory().capacity());
}

}  // namespace canemu::client::vci
