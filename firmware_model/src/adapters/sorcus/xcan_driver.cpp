// The X-CAN-2i MDD's driver side: how it programs each 82527 (bit timing, buffers, buffer 15
// and its mask), plans the buffers, and sends through own, exclusive and temporary buffers and
// the FIFO. The interrupt service is in xcan_interrupt.cpp.
#include <algorithm>

#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

namespace canemu::model::sorcus {

using namespace i82527;

namespace {

constexpr uint8_t kRunControl = CONTROL_IE | CONTROL_SIE | CONTROL_EIE;
constexpr uint8_t kLastBuffer = 14;

}  // namespace

// --- chip set-up ---

void XcanModule::init_chip(unsigned i) {
  I82527& chip = ifaces_[i].chip;
  // As the driver starts the chip: configuration access with INI; the 16 MHz crystal halved
  // (DSC) to the 8 MHz / 125 ns system clock; the global masks "every bit must match" (buffers
  // 1..14 match their object's ID exactly, digest §6.20); every object invalid.
  chip.write(CONTROL, CONTROL_CCE | CONTROL_INI);
  chip.write(CPU_INTERFACE, CPUIF_DSC);
  const auto s = encode_id(0x7FF, false);
  const auto e = encode_id(0x1FFFFFFF, true);
  for (uint8_t k = 0; k < 4; ++k) {
    if (k < 2) {
      chip.write(static_cast<uint8_t>(GMS + k), s[k]);
    }
    chip.write(static_cast<uint8_t>(GML + k), e[k]);
    chip.write(static_cast<uint8_t>(MSG15_MASK + k), e[k]);
  }
  for (uint8_t n = 1; n <= kObjects; ++n) {
    chip.write(message(n) + CTRL0, pair_write(0, MSGVAL | TXIE | RXIE | INTPND));
    chip.write(message(n) + CTRL1, pair_write(0, RMTPND | TXRQST | CPUUPD | NEWDAT));
  }
  chip.write(CONTROL, kRunControl | CONTROL_INI);
  program_timing(i);
}

void XcanModule::program_timing(unsigned i) {
  Interface& f = ifaces_[i];
  const XCAN_BITPARAMS& p = f.params;
  // XCAN_BITPARAMS -> BIT_TIMING0/1 (the SJA1000 field layout, tq = (BRP + 1) x 125 ns):
  // BTR0 = (SJW - 1) << 6 | BRP, BTR1 = SAM << 7 | (TSEG2 - 1) << 4 | (TSEG1 - 1).
  // Example: 500 kbit/s (125 ns, 13, 2, 1, 1) -> 00 1C, the digest §2.4 table.
  const auto btr0 = static_cast<uint8_t>(((p.Tsjw - 1u) << 6) | (p.Tq / 125u - 1u));
  const auto btr1 =
      static_cast<uint8_t>((p.SpB == 3 ? 0x80u : 0u) | ((p.Tseg2 - 1u) << 4) | (p.Tseg1 - 1u));
  const uint8_t control = f.chip.read(CONTROL);
  f.chip.write(CONTROL, control | CONTROL_CCE | CONTROL_INI);
  f.chip.write(BIT_TIMING0, btr0);
  f.chip.write(BIT_TIMING1, btr1);
  f.chip.write(CONTROL, control & ~CONTROL_CCE);
}

void XcanModule::bus_on(unsigned i) {
  Interface& f = ifaces_[i];
  // «Nach dem Öffnen des ersten Kanals zu einem Sende- oder Empfangsobjekt ist der Bus
  // standardmäßig eingeschaltet.» Decision: unless the bus-control device switched it already.
  if (!f.controlled) {
    f.chip.write(CONTROL, kRunControl);
  }
}

ULONG XcanModule::bus_state(unsigned i) const {
  const Interface& f = ifaces_[i];
  // WARN and BOFF as the interrupt service last saw them: a query does not touch the status
  // register (reading it would end a status change interrupt).
  const uint8_t s = f.error_bits;
  USHORT flags = 0;
  if (f.chip.participating() && !(s & STATUS_BOFF)) {  // INI clear
    flags |= XCAN_BUS_ON;
  }
  if (s & STATUS_WARN) {
    flags |= XCAN_BUS_HEAVY;
  }
  if (s & STATUS_BOFF) {
    flags |= XCAN_BUS_OFF;
  }
  if (f.line_error) {
    flags |= XCAN_LINE_ERROR;
  }
  return XCAN_STATUS(flags, f.last_lec);
}

// --- the buffer plan ---

int XcanModule::find_object(const Interface& f, uint32_t id, bool extended) const {
  for (std::size_t k = 0; k < f.objects.size(); ++k) {
    const Object& o = f.objects[k];
    if (o.role != Role::general && o.id == id && o.extended == extended) {
      return static_cast<int>(k);
    }
  }
  return -1;
}

std::vector<int> XcanModule::buffer15_objects(const Interface& f) const {
  std::vector<int> out;
  for (std::size_t k = 0; k < f.objects.size(); ++k) {
    if (f.objects[k].buffer == 15) {
      out.push_back(static_cast<int>(k));
    }
  }
  return out;
}

AcceptanceFilter XcanModule::buffer15_filter(unsigned i) const {
  const Interface& f = ifaces_[i];
  std::vector<uint32_t> ids;
  bool ext = false;
  for (const int k : buffer15_objects(f)) {
    ids.push_back(f.objects[static_cast<std::size_t>(k)].id);
    ext = f.objects[static_cast<std::size_t>(k)].extended;
  }
  if (ids.empty()) {
    return AcceptanceFilter{};
  }
  return automatic_filter(ids, ext);
}

void XcanModule::plan(unsigned i) {
  Interface& f = ifaces_[i];
  // Decision (digest §1.4, §7.15): the plan is made again on every new object. Up to 14
  // objects each has a buffer of its own among 1..14. From the 15th on, exclusive objects
  // (and the general-ID channel) keep one of 1..13, passive non-exclusive objects go to buffer
  // 15, everything else uses the temporary pool; a buffer an object leaves stays loaded with
  // it as a temporary buffer (its pending request, if any, completes there).
  f.shared = f.objects.size() > 14;
  const uint8_t limit = f.shared ? 13 : kLastBuffer;
  auto keeps_own = [&](const Object& o) {
    return (!f.shared || o.excl) && o.buffer >= 1 && o.buffer <= limit;
  };
  // First every object that leaves its buffer, so the buffers they free can be given out.
  for (Object& o : f.objects) {
    if (keeps_own(o)) {
      continue;
    }
    if (o.buffer >= 1 && o.buffer <= kLastBuffer) {
      f.buffers[o.buffer - 1].permanent = false;  // left: a cached temporary buffer now
    }
    const bool passive = o.role == Role::passive_send || o.role == Role::passive_receive;
    o.buffer = f.shared && !o.excl && passive ? 15 : 0;
  }
  // Then a buffer for every object that needs one of its own.
  for (std::size_t k = 0; k < f.objects.size(); ++k) {
    Object& o = f.objects[k];
    if ((f.shared && !o.excl) || keeps_own(o)) {
      continue;
    }
    // The lowest buffer that is no object's own; a free one before one that is busy. There is
    // always one: at most 13 objects are exclusive, at most 14 exist without the shared plan.
    uint8_t pick = 0;
    for (int pass = 0; pass < 2 && pick == 0; ++pass) {
      for (uint8_t n = 1; n <= limit; ++n) {
        const Buffer& b = f.buffers[n - 1];
        if (!b.permanent && (pass == 1 || !b.busy)) {
          pick = n;
          break;
        }
      }
    }
    Buffer& b = f.buffers[pick - 1];
    if (b.busy) {
      // The request on it goes back to the head of the FIFO.
      f.fifo.push_front(b.sending);
      b.busy = false;
    }
    b.owner = static_cast<int>(k);
    b.permanent = true;
    o.buffer = pick;
    program_object(i, pick, static_cast<int>(k));
  }
  program_buffer15(i);
}

void XcanModule::program_object(unsigned i, uint8_t n, int object) {
  Interface& f = ifaces_[i];
  const Object& o = f.objects[static_cast<std::size_t>(object)];
  I82527& chip = f.chip;
  const uint8_t base = message(n);
  const bool send =
      o.role == Role::active_send || o.role == Role::passive_send || o.role == Role::general;
  chip.write(base + CTRL0, pair_write(0, MSGVAL | INTPND));
  chip.write(base + CTRL1,
             pair_write(send ? CPUUPD : 0,
                        static_cast<uint8_t>(RMTPND | TXRQST | NEWDAT | (send ? 0 : MSGLST))));
  if (o.role == Role::general) {
    chip.write(base + CTRL0, pair_write(TXIE | RXIE, 0));  // loaded per message
    return;
  }
  const auto arb = encode_id(o.id, o.extended);
  for (uint8_t k = 0; k < 4; ++k) {
    chip.write(static_cast<uint8_t>(base + ARB0 + k), arb[k]);
  }
  chip.write(base + CONFIG,
             static_cast<uint8_t>((o.size << kConfigDlcShift) | (send ? CONFIG_DIR : 0) |
                                  (o.extended ? CONFIG_XTD : 0)));
  for (uint8_t k = 0; k < 8; ++k) {
    chip.write(static_cast<uint8_t>(base + DATA0 + k), o.data[k]);
  }
  chip.write(base + CTRL0, pair_write(MSGVAL | TXIE | RXIE, 0));
  if (o.role == Role::passive_send) {
    // A passive send object answers remote frames in hardware: CPUUpd reset. An active-only
    // send object keeps CPUUpd set between its own requests, so it answers none.
    chip.write(base + CTRL1, pair_write(0, CPUUPD));
  }
}

void XcanModule::program_buffer15(unsigned i) {
  Interface& f = ifaces_[i];
  I82527& chip = f.chip;
  const uint8_t base = message(15);
  chip.write(base + CTRL0, pair_write(0, MSGVAL | INTPND));
  chip.write(base + CTRL1, pair_write(0, RMTPND | TXRQST | MSGLST | NEWDAT));
  const std::vector<int> in15 = buffer15_objects(f);
  bool ext = false;
  bool remote = f.filter_remote;
  AcceptanceFilter filter;
  if (!in15.empty()) {
    const Object& first = f.objects[static_cast<std::size_t>(in15.front())];
    ext = first.extended;
    remote = first.role == Role::passive_send;
    filter = buffer15_filter(i);
    if (f.manual_mask) {
      // The manual mask only opens bits (checked when it was written); with objects added
      // since, the automatic mask's zeros stay zeros.
      filter.acc &= *f.manual_mask;
    }
  } else if (f.filter_channel != 0) {
    ext = extended_format(f, channels_.at(f.filter_channel).cps);
    // «Sind alle Bits der Bitmaske =0, bedeutet dies folglich, dass alle Identifizier-Werte über
    // den Nur-Empfangspuffer empfangen werden.»
    filter.acc = f.manual_mask.value_or(0xFFFFFFFFu) & id_width_mask(ext);
    filter.idm = (f.filter_id == XCAN_AUTO_ID ? 0 : f.filter_id) & id_width_mask(ext);
  } else {
    return;  // buffer 15 unused
  }
  // Mask and identifier in the 82527's layout; message 15's mask register is in the extended
  // layout, whose first 11 bits are the standard one's.
  const auto mask = encode_id(filter.acc, ext);
  const auto arb = encode_id(filter.idm, ext);
  for (uint8_t k = 0; k < 4; ++k) {
    chip.write(static_cast<uint8_t>(MSG15_MASK + k), mask[k]);
    chip.write(static_cast<uint8_t>(base + ARB0 + k), arb[k]);
  }
  // DIR on message 15 chooses remote frames (the model's 82527, docs/i82527.md): «Nur-
  // Empfangspuffer» for Remote frames with passive send objects, Data frames otherwise.
  chip.write(base + CONFIG,
             static_cast<uint8_t>((remote ? CONFIG_DIR : 0) | (ext ? CONFIG_XTD : 0)));
  chip.write(base + CTRL0, pair_write(MSGVAL | RXIE, TXIE));
}

// --- sending ---

void XcanModule::update_data(unsigned i, const Object& o) {
  Interface& f = ifaces_[i];
  // The buffers that hold the object (its own, or a temporary one caching it) get the data
  // under CPUUpd, so a remote frame meanwhile is answered with the old or the new data whole.
  for (uint8_t n = 1; n <= kLastBuffer; ++n) {
    const Buffer& b = f.buffers[n - 1];
    if (b.owner < 0 || &f.objects[static_cast<std::size_t>(b.owner)] != &o) {
      continue;
    }
    const uint8_t base = message(n);
    const bool held = pair_is_set(f.chip.read(base + CTRL1), CPUUPD);
    f.chip.write(base + CTRL1, pair_write(CPUUPD));
    for (uint8_t k = 0; k < 8; ++k) {
      f.chip.write(static_cast<uint8_t>(base + DATA0 + k), o.data[k]);
    }
    const uint8_t config = f.chip.read(base + CONFIG);
    f.chip.write(base + CONFIG,
                 static_cast<uint8_t>((config & 0x0F) | (o.size << kConfigDlcShift)));
    if (!held) {
      f.chip.write(base + CTRL1, pair_write(0, CPUUPD));
    }
  }
}

uint32_t XcanModule::request(unsigned i, Request r) {
  Interface& f = ifaces_[i];
  if (f.error_bits & STATUS_BOFF) {
    return ERR_XCAN_NOT_READY;  // Decision: a bus-off interface takes no send requests
  }
  const Object& o = f.objects[static_cast<std::size_t>(r.object)];
  auto enqueue = [&f](const Request& q) {
    if (f.fifo.size() >= kFifoDepth) {
      return uint32_t{ERR_XCAN_FIFO_FULL};
    }
    f.fifo.push_back(q);
    return uint32_t{ERR_OK};
  };
  // Decision: a request for an object that already waits in the FIFO merges with it (one frame
  // goes, with the data current when it leaves); so does a remote request while the object's
  // remote frame is still pending (one answer serves both). A data frame for an object whose
  // buffer is still busy waits in the FIFO and follows, so that each write sends its own data
  // (the buffer's registers change only when the frame before has gone).
  if (!r.message) {
    for (const Request& q : f.fifo) {
      if (q.object == r.object && !q.message && q.remote == r.remote) {
        return ERR_OK;
      }
    }
    for (uint8_t n = 1; n <= kLastBuffer; ++n) {
      const Buffer& b = f.buffers[n - 1];
      if (b.busy && b.owner == r.object && !b.sending.message) {
        return r.remote && b.sending.remote ? uint32_t{ERR_OK} : enqueue(r);
      }
    }
  }
  if (o.buffer >= 1 && o.buffer <= kLastBuffer) {
    if (f.buffers[o.buffer - 1].busy) {
      return enqueue(r);  // the general-ID channel's next message
    }
    start_on(i, o.buffer, r);
    return ERR_OK;
  }
  // The temporary pool: the buffer that still caches the object, else the lowest free one.
  uint8_t pick = 0;
  for (uint8_t n = 1; n <= kLastBuffer; ++n) {
    const Buffer& b = f.buffers[n - 1];
    if (!b.permanent && !b.busy && b.owner == r.object) {
      pick = n;
      break;
    }
  }
  for (uint8_t n = 1; n <= kLastBuffer && pick == 0; ++n) {
    const Buffer& b = f.buffers[n - 1];
    if (!b.permanent && !b.busy) {
      pick = n;
    }
  }
  if (pick == 0) {
    // «…wird die Nachricht in den FIFO-Puffer des MDD eingetragen.» Decision: the FIFO holds
    // the object, not its data (as SL-CANi): the data that go are those current when it leaves.
    return enqueue(r);
  }
  start_on(i, pick, r);
  return ERR_OK;
}

void XcanModule::start_on(unsigned i, uint8_t n, const Request& r) {
  Interface& f = ifaces_[i];
  Buffer& b = f.buffers[n - 1];
  I82527& chip = f.chip;
  const uint8_t base = message(n);
  const Object& o = f.objects[static_cast<std::size_t>(r.object)];
  bool loaded = true;
  if (r.message) {
    // A general-ID message: identifier, format, DLC and data loaded for this one frame.
    const XCAN_MESSAGE& m = *r.message;
    const bool ext = (m.usFlags & XCAN_29BIT_ID) != 0;
    const bool remote = (m.usFlags & XCAN_REMOTE) != 0;
    chip.write(base + CTRL0, pair_write(0, MSGVAL | INTPND));
    chip.write(base + CTRL1, pair_write(0, RMTPND | TXRQST | CPUUPD | NEWDAT));
    const auto arb = encode_id(m.ulCanId, ext);
    for (uint8_t k = 0; k < 4; ++k) {
      chip.write(static_cast<uint8_t>(base + ARB0 + k), arb[k]);
    }
    // Decision: a remote message's usDataSize is its DLC. Its buffer is a receive object
    // (DIR = 0) for the remote frame; the answer it would catch is read only by the filter
    // channel (buffer 15), so the buffer goes invalid after the transmission.
    chip.write(base + CONFIG,
               static_cast<uint8_t>((m.usDataSize << kConfigDlcShift) | (remote ? 0 : CONFIG_DIR) |
                                    (ext ? CONFIG_XTD : 0)));
    for (uint8_t k = 0; k < 8; ++k) {
      chip.write(static_cast<uint8_t>(base + DATA0 + k), m.aucData[k]);
    }
    chip.write(base + CTRL0, pair_write(MSGVAL | TXIE, RXIE));
  } else if (b.owner != r.object) {
    b.owner = r.object;
    program_object(i, n, r.object);
  } else {
    loaded = false;  // cached: only its data change
    if (o.role == Role::active_send || o.role == Role::passive_send) {
      update_data(i, o);
    }
  }
  b.busy = true;
  b.sending = r;
  if (!loaded || load_ns_ == 0) {
    request_transmission(i, n);
    return;
  }
  // The load takes its time; the transmit request follows unless the buffer was taken from
  // the request meanwhile (a new plan, the interface's reset).
  const uint64_t token = next_load_++;
  b.load = token;
  loads_[token] = scheduler_.schedule_after(SimDuration(load_ns_), [this, i, n, token](SimTime) {
    loads_.erase(token);
    Buffer& x = ifaces_[i].buffers[n - 1];
    if (x.busy && x.load == token) {
      x.load = 0;
      request_transmission(i, n);
    }
  });
}

void XcanModule::request_transmission(unsigned i, uint8_t n) {
  Interface& f = ifaces_[i];
  const Request& r = f.buffers[n - 1].sending;
  const Role role = f.objects[static_cast<std::size_t>(r.object)].role;
  if (r.message || role == Role::active_send || role == Role::passive_send) {
    f.chip.write(message(n) + CTRL1, pair_write(TXRQST | NEWDAT, CPUUPD));
  } else {
    f.chip.write(message(n) + CTRL1, pair_write(TXRQST));  // a receive object's remote frame
  }
}

BufferView XcanModule::buffer(unsigned i, uint8_t n) const {
  const Interface& f = ifaces_[i];
  BufferView v;
  if (n == 15) {
    const std::vector<int> in15 = buffer15_objects(f);
    if (!in15.empty() || f.filter_channel != 0) {
      v.use = BufferView::Use::receive_only;
    }
    return v;
  }
  const Buffer& b = f.buffers[n - 1];
  v.busy = b.busy;
  if (b.owner < 0) {
    return v;
  }
  const Object& o = f.objects[static_cast<std::size_t>(b.owner)];
  if (o.role != Role::general) {
    v.id = o.id;
  }
  if (!b.permanent) {
    v.use = BufferView::Use::temporary;
  } else if (o.role == Role::general) {
    v.use = BufferView::Use::general;
  } else {
    v.use = f.shared ? BufferView::Use::exclusive : BufferView::Use::own;
  }
  return v;
}

}  // namespace canemu::model::sorcus
