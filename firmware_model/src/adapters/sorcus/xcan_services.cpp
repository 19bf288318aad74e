// The X-CAN-2i MDD's channel services: block and ULONG reads and writes, control, info, clear
// error for each kind of channel, the bus-control device's bit timing, and the blocking
// services' requests with their timeouts.
#include <algorithm>
#include <cstring>

#include "canemu/firmware_model/adapters/sorcus/bit_params.hpp"
#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

namespace canemu::model::sorcus {

Reply XcanModule::write_block(ChannelHandle h, std::span<const uint8_t> data) {
  Channel* c = find(h);
  if (c == nullptr) {
    return {ERR_XCAN_INVALID_HANDLE};
  }
  const unsigned i = c->iface;
  Interface& f = ifaces_[i];
  switch (c->kind) {
    case Kind::bus_control:
      return {write_bitparams(i, data)};
    case Kind::filter:
      return {ERR_XCAN_WRONG_TYPE};
    case Kind::general: {
      if (data.size() != sizeof(XCAN_MESSAGE)) {
        return {ERR_XCAN_DATA_SIZE};
      }
      XCAN_MESSAGE m{};
      std::memcpy(&m, data.data(), sizeof m);
      const bool ext = (m.usFlags & XCAN_29BIT_ID) != 0;
      if (m.usDataSize > 8) {
        return {ERR_XCAN_DATA_SIZE};
      }
      if ((ext && f.params.MsgFormat == 11) || (!ext && f.params.MsgFormat == 29) ||
          m.ulCanId > (ext ? XCAN_MAX_ID_29 : XCAN_MAX_ID_11)) {
        return {ERR_XCAN_ID_RANGE};
      }
      if (const uint32_t e = request(i, Request{f.general_object, false, m}); e != ERR_OK) {
        return {e};
      }
      if (c->cps.usFlags & XCAN_NO_INT) {
        return {ERR_OK, wait(h, f.general_object, false, c->cps.usTimeout)};
      }
      return {ERR_OK};
    }
    case Kind::object:
      break;
  }
  Object& o = f.objects[static_cast<std::size_t>(c->object)];
  if (o.role != Role::active_send && o.role != Role::passive_send) {
    return {ERR_XCAN_WRONG_TYPE};
  }
  if (data.size() > 8) {
    return {ERR_XCAN_DATA_SIZE};
  }
  o.size = static_cast<uint8_t>(data.size());
  std::copy(data.begin(), data.end(), o.data.begin());
  if (o.role == Role::passive_send) {
    // «…stellt dem Sendeobjekt neue Daten zur Verfügung, ohne dass die Daten unmittelbar auf
    // den Bus versendet werden»: an answer from now on carries these data.
    update_data(i, o);
    return {ERR_OK};
  }
  if (const uint32_t e = request(i, Request{c->object, false, std::nullopt}); e != ERR_OK) {
    return {e};
  }
  if (o.no_int && o.cps.usTimeout > 0) {
    return {ERR_OK, wait(h, c->object, false, o.cps.usTimeout)};
  }
  return {ERR_OK};
}

Reply XcanModule::read_block(ChannelHandle h) {
  Channel* c = find(h);
  if (c == nullptr) {
    return {ERR_XCAN_INVALID_HANDLE};
  }
  const unsigned i = c->iface;
  Interface& f = ifaces_[i];
  switch (c->kind) {
    case Kind::bus_control: {
      Reply r;
      r.data.resize(sizeof(XCAN_BITPARAMS));
      std::memcpy(r.data.data(), &f.params, sizeof f.params);
      return r;
    }
    case Kind::filter:
    case Kind::general:
      return {ERR_XCAN_WRONG_TYPE};
    case Kind::object:
      break;
  }
  Object& o = f.objects[static_cast<std::size_t>(c->object)];
  if (c->sticky != ERR_OK) {
    return {c->sticky};
  }
  if (o.role == Role::active_receive && o.cps.usTimeout > 0) {
    // A read sends the remote frame and waits for the answer, at most usTimeout µs.
    if (const uint32_t e = request(i, Request{c->object, true, std::nullopt}); e != ERR_OK) {
      return {e};
    }
    return {ERR_OK, wait(h, c->object, true, o.cps.usTimeout)};
  }
  if (o.role == Role::active_receive) {
    // Decision: usTimeout 0 waits for nothing: the remote frame goes, the read returns the
    // data the object holds now.
    if (const uint32_t e = request(i, Request{c->object, true, std::nullopt}); e != ERR_OK) {
      return {e};
    }
  }
  if (o.role == Role::passive_receive && (o.cps.usFlags & XCAN_NEW_ONLY)) {
    if (!c->new_data) {
      c->sticky = ERR_DATA_NOT_READY;  // «Dieser muss mit max_clear_error zurückgesetzt werden»
      return {ERR_DATA_NOT_READY};
    }
  }
  c->new_data = false;
  Reply r;
  r.data.assign(o.data.begin(), o.data.begin() + o.size);
  return r;
}

uint32_t XcanModule::write_ulong(ChannelHandle h, ULONG value) {
  Channel* c = find(h);
  if (c == nullptr) {
    return ERR_XCAN_INVALID_HANDLE;
  }
  if (c->kind != Kind::filter) {
    return ERR_XCAN_WRONG_TYPE;
  }
  const unsigned i = c->iface;
  Interface& f = ifaces_[i];
  const std::vector<int> in15 = buffer15_objects(f);
  if (!in15.empty()) {
    // «…dass in der automatisch erzeugten Akzeptanzmaske niemals ein 0 gesetztes Bit über das
    // Akzeptanzfilter-Device auf 1 gesetzt werden darf»: a 1 where the automatic mask has 0.
    const bool ext = f.objects[static_cast<std::size_t>(in15.front())].extended;
    const AcceptanceFilter automatic = buffer15_filter(i);
    if ((value & id_width_mask(ext) & ~automatic.acc) != 0) {
      return ERR_XCAN_MASK_EXCLUDES;
    }
  }
  f.manual_mask = value;
  program_buffer15(i);
  return ERR_OK;
}

tl::expected<ULONG, uint32_t> XcanModule::read_ulong(ChannelHandle h) {
  Channel* c = find(h);
  if (c == nullptr) {
    return tl::unexpected(uint32_t{ERR_XCAN_INVALID_HANDLE});
  }
  if (c->kind != Kind::filter) {
    return tl::unexpected(uint32_t{ERR_XCAN_WRONG_TYPE});
  }
  const Interface& f = ifaces_[c->iface];
  if (f.manual_mask) {
    return *f.manual_mask;
  }
  // Decision: without a manual mask the read gives the automatic mask of buffer 15's
  // objects, or FFFFFFFFh (the «Initialisierungszustand») when there are none.
  if (!buffer15_objects(f).empty()) {
    return buffer15_filter(c->iface).acc;
  }
  return ULONG{0xFFFFFFFFu};
}

uint32_t XcanModule::control(ChannelHandle h, USHORT command) {
  Channel* c = find(h);
  if (c == nullptr) {
    return ERR_XCAN_INVALID_HANDLE;
  }
  const unsigned i = c->iface;
  Interface& f = ifaces_[i];
  if (command != CMD_START && command != CMD_STOP) {
    return ERR_XCAN_WRONG_TYPE;
  }
  if (c->kind == Kind::bus_control) {
    f.controlled = true;
    const uint8_t control = f.chip.read(i82527::CONTROL);
    if (command == CMD_STOP) {
      f.chip.write(i82527::CONTROL, control | i82527::CONTROL_INI);
      f.stopped = true;
      return ERR_OK;
    }
    // «Diese Betriebsart kann nur durch die Sonderdienste CMD_STOP und anschließend CMD_START
    // … verlassen werden»: CMD_START alone does not end bus-off.
    if ((f.error_bits & i82527::STATUS_BOFF) && !f.stopped) {
      return ERR_XCAN_NOT_READY;
    }
    f.stopped = false;
    // Clearing INI: after bus-off the 82527 waits 128 x 11 recessive bits, then both counters
    // are 0 («werden beide Fehlerzähler wieder zurückgesetzt»).
    f.chip.write(i82527::CONTROL, control & ~i82527::CONTROL_INI);
    return ERR_OK;
  }
  if (c->kind != Kind::object || command != CMD_START) {
    return ERR_XCAN_WRONG_TYPE;  // Decision: CMD_STOP is a bus-control command only
  }
  const Object& o = f.objects[static_cast<std::size_t>(c->object)];
  switch (o.role) {
    case Role::active_send:   // «die zuvor versendeten Daten nochmals senden»
    case Role::passive_send:  // «die gerade aktuellen Daten aktiv versenden»
      return request(i, Request{c->object, false, std::nullopt});
    case Role::active_receive:
      // The answer goes to the callback (XCAN_NO_INT concerns the read only, digest §7.10).
      c->start_pending = true;
      return request(i, Request{c->object, true, std::nullopt});
    case Role::passive_receive:  // the object becomes active and passive
      return request(i, Request{c->object, true, std::nullopt});
    case Role::general:
      break;
  }
  return ERR_XCAN_WRONG_TYPE;
}

tl::expected<ULONG, uint32_t> XcanModule::info(ChannelHandle h, USHORT what) {
  Channel* c = find(h);
  if (c == nullptr) {
    return tl::unexpected(uint32_t{ERR_XCAN_INVALID_HANDLE});
  }
  if (what == INFO_DEVICE && c->kind == Kind::bus_control) {
    return bus_state(c->iface);
  }
  if (what == INFO_XCAN_MSG_COUNT && (c->kind == Kind::object || c->kind == Kind::general)) {
    const Object& o = ifaces_[c->iface].objects[static_cast<std::size_t>(c->object)];
    // Send objects count «ab MDD Version 3.C»; receive objects always.
    const bool send = o.role == Role::active_send || o.role == Role::passive_send;
    if (!send || mdd_version_ >= kMdd3C) {
      return ULONG{o.count};
    }
  }
  return tl::unexpected(uint32_t{ERR_XCAN_WRONG_TYPE});
}

uint32_t XcanModule::clear_error(ChannelHandle h) {
  Channel* c = find(h);
  if (c == nullptr) {
    return ERR_XCAN_INVALID_HANDLE;
  }
  c->sticky = ERR_OK;
  return ERR_OK;
}

uint32_t XcanModule::write_bitparams(unsigned i, std::span<const uint8_t> data) {
  Interface& f = ifaces_[i];
  if (data.size() != sizeof(XCAN_BITPARAMS)) {
    return ERR_XCAN_DATA_SIZE;
  }
  XCAN_BITPARAMS p{};
  std::memcpy(&p, data.data(), sizeof p);
  const auto timing = decode_sorcus(kXCan2i, SorcusTiming{p.Tq, p.Tseg1, p.Tseg2, p.Tsjw, p.SpB});
  if (!timing || p.Rbus > 1 ||
      (p.MsgFormat != 11 && p.MsgFormat != 29 && p.MsgFormat != XCAN_MIXED_FORMAT)) {
    return ERR_XCAN_PARAM;
  }
  // «Low Speed 5 bis 125 kBit/s»: bit time at least 8 µs.
  const uint32_t bit_ns = uint32_t{p.Tq} * (1u + p.Tseg1 + p.Tseg2);
  if (f.low_speed && bit_ns < 8000) {
    return ERR_XCAN_PARAM;
  }
  // Decision: the identifier format cannot change under existing objects.
  if (p.MsgFormat != f.params.MsgFormat && !f.objects.empty()) {
    return ERR_XCAN_PARAM;
  }
  f.params = p;
  // Decision: new bit timing takes effect at once, also while the bus is on (the driver sets
  // INI around the write, as the 82527 requires CCE and a quiet controller).
  program_timing(i);
  return ERR_OK;
}

// --- waiting services ---

RequestId XcanModule::wait(ChannelHandle h, int object, bool read, USHORT timeout_us) {
  const RequestId id = next_request_++;
  Waiter w{id, h, object, read, 0};
  w.timeout = scheduler_.schedule_after(microseconds(timeout_us), [this, id](SimTime at) {
    auto it = std::find_if(waiters_.begin(), waiters_.end(),
                           [id](const Waiter& x) { return x.id == id; });
    if (it == waiters_.end()) {
      return;
    }
    const Waiter done = *it;
    waiters_.erase(it);
    // Decision: a request that timed out is not withdrawn; its frame still goes when it can
    // (the MDD has given up waiting, not sending).
    sink_.completed(XcanCompletion{at, done.id, done.channel, ERR_XCAN_TIMEOUT, {}});
  });
  waiters_.push_back(w);
  return id;
}

void XcanModule::complete_waiters(unsigned i, int object, bool read,
                                  const std::vector<uint8_t>& data) {
  std::vector<Waiter> done;
  for (auto it = waiters_.begin(); it != waiters_.end();) {
    const Channel* c = find(it->channel);
    if (c != nullptr && c->iface == i && it->object == object && it->read == read) {
      done.push_back(*it);
      scheduler_.cancel(it->timeout);
      it = waiters_.erase(it);
    } else {
      ++it;
    }
  }
  for (const Waiter& w : done) {
    sink_.completed(XcanCompletion{scheduler_.now(), w.id, w.channel, ERR_OK, data});
  }
}

void XcanModule::cancel_waiters(ChannelHandle h) {
  for (auto it = waiters_.begin(); it != waiters_.end();) {
    if (it->channel == h) {
      scheduler_.cancel(it->timeout);
      it = waiters_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace canemu::model::sorcus
