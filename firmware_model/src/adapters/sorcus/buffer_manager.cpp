// The SORCUS buffer manager's plan and chip programming: which object lives in which buffer,
// buffer 15 and its mask, and sending through own, exclusive and temporary buffers and the
// FIFO. The interrupt service is in buffer_service.cpp.
#include "canemu/firmware_model/adapters/sorcus/buffer_manager.hpp"

#include <algorithm>

namespace canemu::model::sorcus {

using namespace i82527;

namespace {

constexpr uint8_t kRunControl = CONTROL_IE | CONTROL_SIE | CONTROL_EIE;
constexpr uint8_t kLastBuffer = 14;

}  // namespace

// --- chip set-up ---

void BufferManager::init_chip(bool divide_clock) {
  // Configuration access with INI; the clock divider (X-CAN-2i: the 16 MHz crystal halved to
  // the 8 MHz / 125 ns system clock); the global masks "every bit must match" (buffers 1..14
  // match their object's ID exactly, digest §6.20); every object invalid.
  chip_.write(CONTROL, CONTROL_CCE | CONTROL_INI);
  chip_.write(CPU_INTERFACE, divide_clock ? CPUIF_DSC : 0);
  const auto s = encode_id(0x7FF, false);
  const auto e = encode_id(0x1FFFFFFF, true);
  for (uint8_t k = 0; k < 4; ++k) {
    if (k < 2) {
      chip_.write(static_cast<uint8_t>(GMS + k), s[k]);
    }
    chip_.write(static_cast<uint8_t>(GML + k), e[k]);
    chip_.write(static_cast<uint8_t>(MSG15_MASK + k), e[k]);
  }
  for (uint8_t n = 1; n <= kObjects; ++n) {
    chip_.write(message(n) + CTRL0, pair_write(0, MSGVAL | TXIE | RXIE | INTPND));
    chip_.write(message(n) + CTRL1, pair_write(0, RMTPND | TXRQST | CPUUPD | NEWDAT));
  }
  chip_.write(CONTROL, kRunControl | CONTROL_INI);
}

void BufferManager::program_timing(const BitTiming& t) {
  // BIT_TIMING0/1 (the SJA1000 field layout, tq = (BRP + 1) clock periods):
  // BTR0 = (SJW - 1) << 6 | BRP, BTR1 = SAM << 7 | (TSEG2 - 1) << 4 | (TSEG1 - 1).
  // Example: X-CAN-2i 500 kbit/s (125 ns, 13, 2, 1, 1) -> 00 1C, the digest §2.4 table;
  // SL-CANi 20 kbit/s (2500 ns at 100 ns, 16, 3, 2, 1) -> 58 2F.
  const auto btr0 = static_cast<uint8_t>(((t.sjw - 1u) << 6) | (t.prescaler - 1u));
  const auto btr1 =
      static_cast<uint8_t>((t.samples == 3 ? 0x80u : 0u) | ((t.tseg2 - 1u) << 4) | (t.tseg1 - 1u));
  const uint8_t control = chip_.read(CONTROL);
  chip_.write(CONTROL, control | CONTROL_CCE | CONTROL_INI);
  chip_.write(BIT_TIMING0, btr0);
  chip_.write(BIT_TIMING1, btr1);
  chip_.write(CONTROL, control & ~CONTROL_CCE);
}

void BufferManager::set_bus_on(bool on) {
  chip_.write(CONTROL, on ? kRunControl : kRunControl | CONTROL_INI);
}

// --- the plan ---

int BufferManager::find(uint32_t id, bool extended) const {
  for (std::size_t k = 0; k < objects_.size(); ++k) {
    const ManagedObject& o = objects_[k];
    if (!o.general && o.id == id && o.extended == extended) {
      return static_cast<int>(k);
    }
  }
  return -1;
}

PlanError BufferManager::check(const ManagedObject* added, const ManualFilter& manual) const {
  std::size_t exclusive = 0;
  for (const ManagedObject& o : objects_) {
    exclusive += o.excl ? 1 : 0;
  }
  if (added != nullptr && added->excl && exclusive + 1 > kMaxExclusive) {
    // «Diese Eigenschaft darf nur maximal 13 Message-Objekten zugeteilt werden!»
    return PlanError::excl_limit;
  }
  const std::size_t count = objects_.size() + (added != nullptr ? 1 : 0);
  if (count > max_objects_) {
    return PlanError::no_memory;
  }
  if (count <= 14 && !manual.open) {
    return PlanError::none;
  }
  // Buffer 15 takes one kind of frame in one format: its passive non-exclusive objects must all
  // be send objects (remote frames) or all receive objects (data frames), and agree with the
  // manual filter.
  std::optional<bool> remote;
  std::optional<bool> extended;
  if (manual.open) {
    remote = manual.remote;
  }
  auto take = [&](const ManagedObject& o) {
    if (!o.passive || o.excl || count <= 14) {
      return true;
    }
    if ((remote && *remote != o.send) || (extended && *extended != o.extended)) {
      return false;
    }
    remote = o.send;
    extended = o.extended;
    return true;
  };
  for (const ManagedObject& o : objects_) {
    if (!take(o)) {
      return PlanError::buffer15_mixed;
    }
  }
  if (added != nullptr && !take(*added)) {
    return PlanError::buffer15_mixed;
  }
  return PlanError::none;
}

int BufferManager::add(const ManagedObject& o) {
  objects_.push_back(o);
  objects_.back().buffer = 0;
  plan();
  return static_cast<int>(objects_.size() - 1);
}

void BufferManager::reset() {
  objects_.clear();
  buffers_ = {};
  shared_ = false;
  fifo_.clear();
  manual_ = ManualFilter{};
}

void BufferManager::plan() {
  // Decision (digest §1.4, §7.15): the plan is made again on every new object. Up to 14
  // objects each has a buffer of its own among 1..14. From the 15th on, exclusive objects
  // keep one of 1..13, passive non-exclusive objects go to buffer 15, everything else uses the
  // temporary pool; a buffer an object leaves stays loaded with it as a temporary buffer (its
  // pending request, if any, completes there).
  shared_ = objects_.size() > 14;
  const uint8_t limit = shared_ ? 13 : kLastBuffer;
  auto keeps_own = [&](const ManagedObject& o) {
    return (!shared_ || o.excl) && o.buffer >= 1 && o.buffer <= limit;
  };
  // First every object that leaves its buffer, so the buffers they free can be given out.
  for (ManagedObject& o : objects_) {
    if (keeps_own(o)) {
      continue;
    }
    if (o.buffer >= 1 && o.buffer <= kLastBuffer) {
      buffers_[o.buffer - 1].permanent = false;  // left: a cached temporary buffer now
    }
    o.buffer = shared_ && !o.excl && o.passive ? 15 : 0;
  }
  // Then a buffer for every object that needs one of its own.
  for (std::size_t k = 0; k < objects_.size(); ++k) {
    ManagedObject& o = objects_[k];
    if ((shared_ && !o.excl) || keeps_own(o)) {
      continue;
    }
    // The lowest buffer that is no object's own; a free one before one that is busy. There is
    // always one: at most 13 objects are exclusive, at most 14 exist without the shared plan.
    uint8_t pick = 0;
    for (int pass = 0; pass < 2 && pick == 0; ++pass) {
      for (uint8_t n = 1; n <= limit; ++n) {
        const Buffer& b = buffers_[n - 1];
        if (!b.permanent && (pass == 1 || !b.busy)) {
          pick = n;
          break;
        }
      }
    }
    Buffer& b = buffers_[pick - 1];
    if (b.busy) {
      // The request on it goes back to the head of the FIFO.
      fifo_.push_front(b.sending);
      b.busy = false;
    }
    b.owner = static_cast<int>(k);
    b.permanent = true;
    o.buffer = pick;
    program_object(pick, static_cast<int>(k));
  }
  program_buffer15();
}

void BufferManager::program_object(uint8_t n, int object) {
  const ManagedObject& o = objects_[static_cast<std::size_t>(object)];
  const uint8_t base = message(n);
  const bool send = o.send || o.general;
  chip_.write(base + CTRL0, pair_write(0, MSGVAL | INTPND));
  chip_.write(base + CTRL1,
              pair_write(send ? CPUUPD : 0,
                         static_cast<uint8_t>(RMTPND | TXRQST | NEWDAT | (send ? 0 : MSGLST))));
  if (o.general) {
    chip_.write(base + CTRL0, pair_write(TXIE | RXIE, 0));  // loaded per message
    return;
  }
  const auto arb = encode_id(o.id, o.extended);
  for (uint8_t k = 0; k < 4; ++k) {
    chip_.write(static_cast<uint8_t>(base + ARB0 + k), arb[k]);
  }
  chip_.write(base + CONFIG,
              static_cast<uint8_t>((o.size << kConfigDlcShift) | (send ? CONFIG_DIR : 0) |
                                   (o.extended ? CONFIG_XTD : 0)));
  for (uint8_t k = 0; k < 8; ++k) {
    chip_.write(static_cast<uint8_t>(base + DATA0 + k), o.data[k]);
  }
  chip_.write(base + CTRL0, pair_write(MSGVAL | TXIE | RXIE, 0));
  if (o.send && o.passive) {
    // A passive send object answers remote frames in hardware: CPUUpd reset. An active-only
    // send object keeps CPUUpd set between its own requests, so it answers none.
    chip_.write(base + CTRL1, pair_write(0, CPUUPD));
  }
}

std::vector<int> BufferManager::buffer15_objects() const {
  std::vector<int> out;
  for (std::size_t k = 0; k < objects_.size(); ++k) {
    if (objects_[k].buffer == 15) {
      out.push_back(static_cast<int>(k));
    }
  }
  return out;
}

AcceptanceFilter BufferManager::buffer15_filter() const {
  std::vector<uint32_t> ids;
  bool ext = false;
  for (const int k : buffer15_objects()) {
    ids.push_back(objects_[static_cast<std::size_t>(k)].id);
    ext = objects_[static_cast<std::size_t>(k)].extended;
  }
  if (ids.empty()) {
    return AcceptanceFilter{};
  }
  return automatic_filter(ids, ext);
}

void BufferManager::program_buffer15() {
  const uint8_t base = message(15);
  chip_.write(base + CTRL0, pair_write(0, MSGVAL | INTPND));
  chip_.write(base + CTRL1, pair_write(0, RMTPND | TXRQST | MSGLST | NEWDAT));
  const std::vector<int> in15 = buffer15_objects();
  bool ext = manual_.extended;
  bool remote = manual_.remote;
  AcceptanceFilter filter;
  if (!in15.empty()) {
    const ManagedObject& first = objects_[static_cast<std::size_t>(in15.front())];
    ext = first.extended;
    remote = first.send;
    filter = buffer15_filter();
    if (manual_.mask) {
      // The manual mask only opens bits (checked when it was set); with objects added since,
      // the automatic mask's zeros stay zeros.
      filter.acc &= *manual_.mask;
    }
  } else if (manual_.open) {
    // «Sind alle Bits der Bitmaske =0, bedeutet dies folglich, dass alle Identifizier-Werte über
    // den Nur-Empfangspuffer empfangen werden.»
    filter.acc = manual_.mask.value_or(0xFFFFFFFFu) & id_width_mask(ext);
    filter.idm = manual_.id.value_or(0) & id_width_mask(ext);
  } else {
    return;  // buffer 15 unused
  }
  // Mask and identifier in the 82527's layout; message 15's mask register is in the extended
  // layout, whose first 11 bits are the standard one's.
  const auto mask = encode_id(filter.acc, ext);
  const auto arb = encode_id(filter.idm, ext);
  for (uint8_t k = 0; k < 4; ++k) {
    chip_.write(static_cast<uint8_t>(MSG15_MASK + k), mask[k]);
    chip_.write(static_cast<uint8_t>(base + ARB0 + k), arb[k]);
  }
  // DIR on message 15 chooses remote frames (the model's 82527, docs/i82527.md): «Nur-
  // Empfangspuffer» for Remote frames with passive send objects, Data frames otherwise.
  chip_.write(base + CONFIG,
              static_cast<uint8_t>((remote ? CONFIG_DIR : 0) | (ext ? CONFIG_XTD : 0)));
  chip_.write(base + CTRL0, pair_write(MSGVAL | RXIE, TXIE));
}

// --- sending ---

void BufferManager::update_data(int object) {
  const ManagedObject& o = objects_[static_cast<std::size_t>(object)];
  // The buffers that hold the object (its own, or a temporary one caching it) get the data
  // under CPUUpd, so a remote frame meanwhile is answered with the old or the new data whole.
  for (uint8_t n = 1; n <= kLastBuffer; ++n) {
    if (buffers_[n - 1].owner != object) {
      continue;
    }
    const uint8_t base = message(n);
    const bool held = pair_is_set(chip_.read(base + CTRL1), CPUUPD);
    chip_.write(base + CTRL1, pair_write(CPUUPD));
    for (uint8_t k = 0; k < 8; ++k) {
      chip_.write(static_cast<uint8_t>(base + DATA0 + k), o.data[k]);
    }
    const uint8_t config = chip_.read(base + CONFIG);
    chip_.write(base + CONFIG, static_cast<uint8_t>((config & 0x0F) | (o.size << kConfigDlcShift)));
    if (!held) {
      chip_.write(base + CTRL1, pair_write(0, CPUUPD));
    }
  }
}

RequestResult BufferManager::request(const SendRequest& r) {
  const ManagedObject& o = objects_[static_cast<std::size_t>(r.object)];
  auto enqueue = [this](const SendRequest& q) {
    if (fifo_.size() >= fifo_depth_) {
      return RequestResult::fifo_full;
    }
    fifo_.push_back(q);
    return RequestResult::queued;
  };
  // Decision: a request for an object that already waits in the FIFO merges with it (one frame
  // goes, with the data current when it leaves); so does a remote request while the object's
  // remote frame is still pending (one answer serves both). A data frame for an object whose
  // buffer is still busy waits in the FIFO and follows, so that each request sends its own data
  // (the buffer's registers change only when the frame before has gone).
  if (!r.message) {
    for (const SendRequest& q : fifo_) {
      if (q.object == r.object && !q.message && q.remote == r.remote) {
        return RequestResult::merged;
      }
    }
    for (const Buffer& b : buffers_) {
      if (b.busy && b.sending.object == r.object && !b.sending.message) {
        return r.remote && b.sending.remote ? RequestResult::merged : enqueue(r);
      }
    }
  }
  if (o.buffer >= 1 && o.buffer <= kLastBuffer) {
    if (buffers_[o.buffer - 1].busy) {
      return enqueue(r);  // the general-ID channel's next message
    }
    start_on(o.buffer, r);
    return RequestResult::started;
  }
  // The temporary pool: the buffer that still caches the object, else the lowest free one.
  uint8_t pick = 0;
  for (uint8_t n = 1; n <= kLastBuffer; ++n) {
    const Buffer& b = buffers_[n - 1];
    if (!b.permanent && !b.busy && b.owner == r.object) {
      pick = n;
      break;
    }
  }
  for (uint8_t n = 1; n <= kLastBuffer && pick == 0; ++n) {
    const Buffer& b = buffers_[n - 1];
    if (!b.permanent && !b.busy) {
      pick = n;
    }
  }
  // «…können … die Sendeanforderung eines Message-Objekts mit gesetztem _SL064_DISABLE_INT-
  // Flag löschen»: a pending request of such an object without an exclusive buffer gives its
  // temporary buffer to this one.
  for (uint8_t n = 1; n <= kLastBuffer && pick == 0; ++n) {
    const Buffer& b = buffers_[n - 1];
    if (!b.permanent && b.busy && !b.sending.message && b.sending.object != r.object &&
        objects_[static_cast<std::size_t>(b.sending.object)].preemptible) {
      stop_buffer(n);
      pick = n;
    }
  }
  if (pick == 0) {
    // «…wird die Nachricht in den FIFO-Puffer … eingetragen»: the FIFO holds the object, not
    // its data; the data that go are those current when it leaves.
    return enqueue(r);
  }
  start_on(pick, r);
  return RequestResult::started;
}

BufferManager::~BufferManager() {
  for (const auto& [token, id] : loads_) {
    scheduler_->cancel(id);
  }
}

void BufferManager::start_on(uint8_t n, const SendRequest& r) {
  Buffer& b = buffers_[n - 1];
  const uint8_t base = message(n);
  bool loaded = true;
  if (r.message) {
    // A direct message: identifier, format, DLC and data loaded for this one frame.
    const DirectMessage& m = *r.message;
    chip_.write(base + CTRL0, pair_write(0, MSGVAL | INTPND));
    chip_.write(base + CTRL1, pair_write(0, RMTPND | TXRQST | CPUUPD | NEWDAT));
    const auto arb = encode_id(m.id, m.extended);
    for (uint8_t k = 0; k < 4; ++k) {
      chip_.write(static_cast<uint8_t>(base + ARB0 + k), arb[k]);
    }
    // A remote message's buffer is a receive object (DIR = 0) for the remote frame; the answer
    // it would catch is read only through buffer 15, so the buffer goes invalid after the
    // transmission.
    chip_.write(base + CONFIG,
                static_cast<uint8_t>((m.size << kConfigDlcShift) | (m.remote ? 0 : CONFIG_DIR) |
                                     (m.extended ? CONFIG_XTD : 0)));
    for (uint8_t k = 0; k < 8; ++k) {
      chip_.write(static_cast<uint8_t>(base + DATA0 + k), m.data[k]);
    }
    chip_.write(base + CTRL0, pair_write(MSGVAL | TXIE, RXIE));
  } else {
    const ManagedObject& o = objects_[static_cast<std::size_t>(r.object)];
    if (b.owner != r.object) {
      b.owner = r.object;
      program_object(n, r.object);
    } else {
      loaded = false;  // cached: only its data change
      if (o.send) {
        update_data(r.object);
      }
    }
  }
  b.busy = true;
  b.sending = r;
  if (!loaded || load_ns_ == 0 || scheduler_ == nullptr) {
    request_transmission(n);
    return;
  }
  // The load takes its time; the transmit request follows unless the buffer was taken from the
  // request meanwhile (stopped, a new plan, a reset).
  const uint64_t token = next_load_++;
  b.load = token;
  loads_[token] = scheduler_->schedule_after(SimDuration(load_ns_), [this, n, token](SimTime) {
    loads_.erase(token);
    Buffer& x = buffers_[n - 1];
    if (x.busy && x.load == token) {
      x.load = 0;
      request_transmission(n);
    }
  });
}

void BufferManager::request_transmission(uint8_t n) {
  const SendRequest& r = buffers_[n - 1].sending;
  if (r.message || objects_[static_cast<std::size_t>(r.object)].send) {
    chip_.write(message(n) + CTRL1, pair_write(TXRQST | NEWDAT, CPUUPD));
  } else {
    chip_.write(message(n) + CTRL1, pair_write(TXRQST));  // a receive object's remote frame
  }
}

void BufferManager::stop_buffer(uint8_t n) {
  Buffer& b = buffers_[n - 1];
  // TxRqst reset: a frame on the wire completes, no repetition follows.
  chip_.write(message(n) + CTRL1, pair_write(0, TXRQST));
  const ManagedObject& o = objects_[static_cast<std::size_t>(b.owner)];
  if (o.send && !o.passive) {
    chip_.write(message(n) + CTRL1, pair_write(CPUUPD));
  }
  b.busy = false;
  b.load = 0;
  b.sending = SendRequest{};
}

bool BufferManager::abort(int object) {
  bool found = false;
  const auto before = fifo_.size();
  std::erase_if(fifo_, [object](const SendRequest& q) { return q.object == object && !q.message; });
  found = fifo_.size() != before;
  for (uint8_t n = 1; n <= kLastBuffer; ++n) {
    const Buffer& b = buffers_[n - 1];
    if (b.busy && b.sending.object == object && !b.sending.message) {
      stop_buffer(n);
      next_from_fifo(n);
      found = true;
    }
  }
  return found;
}

bool BufferManager::pending(int object) const {
  return std::any_of(fifo_.begin(), fifo_.end(),
                     [object](const SendRequest& q) { return q.object == object; }) ||
         std::any_of(buffers_.begin(), buffers_.end(), [object](const Buffer& b) {
           return b.busy && b.sending.object == object && !b.sending.message;
         });
}

BufferView BufferManager::buffer(uint8_t n) const {
  BufferView v;
  if (n == 15) {
    if (!buffer15_objects().empty() || manual_.open) {
      v.use = BufferView::Use::receive_only;
    }
    return v;
  }
  const Buffer& b = buffers_[n - 1];
  v.busy = b.busy;
  if (b.owner < 0) {
    return v;
  }
  const ManagedObject& o = objects_[static_cast<std::size_t>(b.owner)];
  if (!o.general) {
    v.id = o.id;
  }
  if (!b.permanent) {
    v.use = BufferView::Use::temporary;
  } else if (o.general) {
    v.use = BufferView::Use::general;
  } else {
    v.use = shared_ ? BufferView::Use::exclusive : BufferView::Use::own;
  }
  return v;
}

}  // namespace canemu::model::sorcus
