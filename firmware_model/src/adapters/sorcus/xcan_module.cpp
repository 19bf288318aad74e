// The X-CAN-2i MDD's channel services: opening and closing channels, and the services each
// channel kind answers. The driver side (chip, buffers, interrupt) is in xcan_driver.cpp.
#include <algorithm>
#include <cstring>

#include "canemu/firmware_model/adapters/sorcus/bit_params.hpp"
#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

namespace canemu::model::sorcus {

namespace {

constexpr USHORT kObjectFlags = _CP_SYNC_CALLBACK | XCAN_REMOTE | XCAN_NO_INT | XCAN_EXCL_BUFFER |
                                XCAN_NEW_ONLY | XCAN_29BIT_ID;

bool is_send(uint16_t device) {
  return device == DEVICE_BUS_OUT;
}

}  // namespace

XcanModule::XcanModule(SimScheduler& scheduler, XcanVariant variant, XcanSink& sink)
    : scheduler_(scheduler), variant_(variant), sink_(sink) {
  ifaces_[0].low_speed = variant == XcanVariant::f;
  ifaces_[1].low_speed = variant != XcanVariant::h;
  for (unsigned i = 0; i < XCAN_INTERFACES; ++i) {
    ifaces_[i].chip.on_interrupt = [this, i](SimTime at) {
      Interface& f = ifaces_[i];
      if (!f.isr_scheduled) {
        f.isr_scheduled = true;
        scheduler_.schedule_at(at, [this, i](SimTime) {
          ifaces_[i].isr_scheduled = false;
          service(i);
        });
      }
    };
  }
}

XcanModule::~XcanModule() {
  for (const Waiter& w : waiters_) {
    scheduler_.cancel(w.timeout);
  }
}

void XcanModule::connect(unsigned i, CanBus& bus) {
  ifaces_[i].bus = &bus;
  ifaces_[i].chip.connect(bus);
  init_chip(i);
}

bool XcanModule::low_speed(unsigned i) const {
  return ifaces_[i].low_speed;
}

bool XcanModule::set_line_error(unsigned i, bool error) {
  Interface& f = ifaces_[i];
  if (!f.low_speed) {
    return false;
  }
  const bool onset = error && !f.line_error;
  f.line_error = error;
  if (onset) {
    // Decision: the line fault is one of the four interrupt sources (§10.9.1), so it calls
    // the error callback at its onset; its end is visible only in INFO_DEVICE.
    error_callback(i);
  }
  return true;
}

XcanModule::Channel* XcanModule::find(ChannelHandle h) {
  auto it = channels_.find(h);
  return it == channels_.end() ? nullptr : &it->second;
}

ChannelHandle XcanModule::add_channel(Channel c) {
  const ChannelHandle h = next_handle_++;
  channels_.emplace(h, c);
  return h;
}

void XcanModule::emit(ChannelHandle h, const Channel& c, XcanCallback cb) {
  if (!c.callback) {
    return;
  }
  cb.at = scheduler_.now();
  cb.channel = h;
  cb.sync = (c.cps.usFlags & _CP_SYNC_CALLBACK) != 0;
  sink_.callback(cb);
}

bool XcanModule::extended_format(const Interface& f, const CPS_XCAN& cps) const {
  if (f.params.MsgFormat == 29) {
    return true;
  }
  if (f.params.MsgFormat == XCAN_MIXED_FORMAT) {
    // Decision: in mixed format (AN099, not provided) an object's CPS says 29 bits with
    // XCAN_29BIT_ID, the flag the general-ID channel's messages use.
    return (cps.usFlags & XCAN_29BIT_ID) != 0;
  }
  return false;
}

// --- opening ---

tl::expected<ChannelHandle, uint32_t> XcanModule::open_channel(const CPS_XCAN& cps, bool callback) {
  if (cps.usChannel >= XCAN_INTERFACES || ifaces_[cps.usChannel].bus == nullptr) {
    return tl::unexpected(uint32_t{ERR_XCAN_INVALID_CPS});
  }
  const unsigned i = cps.usChannel;
  Interface& f = ifaces_[i];
  if (cps.usDevice == DEVICE_CTRL) {
    if (cps.usIndexFirst == XCAN_BUS_CTRL_INDEX && cps.usIndexLast == XCAN_BUS_CTRL_INDEX) {
      if (cps.usFlags & ~_CP_SYNC_CALLBACK) {
        return tl::unexpected(uint32_t{ERR_XCAN_INVALID_CPS});
      }
      return add_channel(Channel{i, Kind::bus_control, cps, callback});
    }
    // The acceptance-filter device. «Zur Zeit muss usIndexFirst = usIndexLast = 0 gesetzt
    // werden.»
    if (cps.usIndexFirst != 0 || cps.usIndexLast != 0) {
      return tl::unexpected(uint32_t{ERR_XCAN_INDEX});
    }
    if (cps.usFlags & ~(_CP_SYNC_CALLBACK | XCAN_REMOTE | XCAN_29BIT_ID)) {
      return tl::unexpected(uint32_t{ERR_XCAN_INVALID_CPS});
    }
    if (f.filter_channel != 0) {
      // Decision: one filter channel per interface (buffer 15 has one mask), as SL-CANi allows
      // sl064_set_acceptance_mask once per S-Link.
      return tl::unexpected(uint32_t{ERR_XCAN_CHANNEL_BUSY});
    }
    const bool ext = extended_format(f, cps);
    if (cps.ulCanID != XCAN_AUTO_ID && cps.ulCanID > (ext ? XCAN_MAX_ID_29 : XCAN_MAX_ID_11)) {
      return tl::unexpected(uint32_t{ERR_XCAN_ID_RANGE});
    }
    const bool remote = (cps.usFlags & XCAN_REMOTE) != 0;
    const std::vector<int> in15 = buffer15_objects(f);
    if (!in15.empty() && cps.ulCanID != XCAN_AUTO_ID) {
      return tl::unexpected(uint32_t{ERR_XCAN_AUTO_ID_REQUIRED});
    }
    if (const uint32_t e = check_plan(f, std::nullopt, remote, true); e != ERR_OK) {
      return tl::unexpected(e);
    }
    const ChannelHandle h = add_channel(Channel{i, Kind::filter, cps, callback});
    f.filter_channel = h;
    f.filter_remote = remote;
    f.filter_id = cps.ulCanID;
    f.manual_mask.reset();
    program_buffer15(i);
    return h;
  }
  if (cps.usDevice != DEVICE_BUS_OUT && cps.usDevice != DEVICE_BUS_IN) {
    return tl::unexpected(uint32_t{ERR_XCAN_INVALID_CPS});
  }
  if (cps.ulCanID == XCAN_GENERAL_ID) {
    if (cps.usDevice != DEVICE_BUS_OUT || !(cps.usFlags & _CP_EXCLUSIVE) ||
        (cps.usFlags & ~(_CP_EXCLUSIVE | _CP_SYNC_CALLBACK | XCAN_NO_INT)) ||
        ((cps.usFlags & XCAN_NO_INT) && cps.usTimeout == 0)) {
      return tl::unexpected(uint32_t{ERR_XCAN_INVALID_CPS});
    }
    if (f.general_channel != 0) {
      return tl::unexpected(uint32_t{ERR_XCAN_CHANNEL_BUSY});
    }
    if (f.general_object < 0) {
      Object g;
      g.role = Role::general;
      g.cps = cps;
      g.excl = true;
      if (const uint32_t e = check_plan(f, g, f.filter_remote, f.filter_channel != 0);
          e != ERR_OK) {
        return tl::unexpected(e);
      }
      f.objects.push_back(g);
      f.general_object = static_cast<int>(f.objects.size() - 1);
      plan(i);
    }
    // The channel's own flags (NO_INT, timeout) count, not those of an earlier general channel.
    f.objects[static_cast<std::size_t>(f.general_object)].no_int = (cps.usFlags & XCAN_NO_INT) != 0;
    const ChannelHandle h = add_channel(Channel{i, Kind::general, cps, callback, f.general_object});
    f.general_channel = h;
    bus_on(i);
    return h;
  }
  return open_object(cps, callback);
}

uint32_t XcanModule::validate_object_cps(const Interface& f, const CPS_XCAN& cps, Role& role,
                                         bool& extended) const {
  if ((cps.usFlags & ~kObjectFlags) != 0) {
    return ERR_XCAN_INVALID_CPS;
  }
  if ((cps.usFlags & XCAN_29BIT_ID) && f.params.MsgFormat != XCAN_MIXED_FORMAT) {
    return ERR_XCAN_INVALID_CPS;
  }
  const bool remote = (cps.usFlags & XCAN_REMOTE) != 0;
  const bool no_int = (cps.usFlags & XCAN_NO_INT) != 0;
  if (is_send(cps.usDevice)) {
    if (cps.usFlags & XCAN_NEW_ONLY) {
      return ERR_XCAN_INVALID_CPS;
    }
    role = remote ? Role::passive_send : Role::active_send;
  } else {
    // «XCAN_REMOTE, XCAN_NO_INT: Müssen gesetzt sein» for an active receive object: one of the
    // two alone is no valid receive object.
    if (remote != no_int || (remote && (cps.usFlags & XCAN_NEW_ONLY))) {
      return ERR_XCAN_INVALID_CPS;
    }
    role = remote ? Role::active_receive : Role::passive_receive;
  }
  extended = extended_format(f, cps);
  if (cps.ulCanID > (extended ? XCAN_MAX_ID_29 : XCAN_MAX_ID_11)) {
    return ERR_XCAN_ID_RANGE;
  }
  return ERR_OK;
}

uint32_t XcanModule::check_plan(const Interface& f, std::optional<Object> added, bool filter_remote,
                                bool filter_open) const {
  std::size_t exclusive = 0;
  for (const Object& o : f.objects) {
    exclusive += o.excl ? 1 : 0;
  }
  if (added && added->excl && exclusive + 1 > 13) {
    // «Diese Eigenschaft darf nur maximal 13 Message-Objekten zugeteilt werden!»
    return ERR_XCAN_EXCL_LIMIT;
  }
  const std::size_t count = f.objects.size() + (added ? 1 : 0);
  if (count > kMaxObjects) {
    return ERR_XCAN_NO_MEMORY;
  }
  if (count <= 14 && !filter_open) {
    return ERR_OK;
  }
  // Buffer 15 takes one kind of frame in one format: its passive non-exclusive objects must all
  // be send objects (remote frames) or all receive objects (data frames), and agree with the
  // filter channel. Decision: the open that would break this fails with
  // ERR_XCAN_BUFFER15_MIXED (SL-CANi diag 2Ch), the same for the format in mixed mode.
  std::optional<bool> remote;
  std::optional<bool> extended;
  if (filter_open) {
    remote = filter_remote;
  }
  auto take = [&](const Object& o) {
    const bool passive = o.role == Role::passive_send || o.role == Role::passive_receive;
    if (!passive || o.excl || count <= 14) {
      return true;
    }
    const bool r = o.role == Role::passive_send;
    if ((remote && *remote != r) || (extended && *extended != o.extended)) {
      return false;
    }
    remote = r;
    extended = o.extended;
    return true;
  };
  for (const Object& o : f.objects) {
    if (!take(o)) {
      return ERR_XCAN_BUFFER15_MIXED;
    }
  }
  if (added && !take(*added)) {
    return ERR_XCAN_BUFFER15_MIXED;
  }
  return ERR_OK;
}

tl::expected<ChannelHandle, uint32_t> XcanModule::open_object(const CPS_XCAN& cps, bool callback) {
  const unsigned i = cps.usChannel;
  Interface& f = ifaces_[i];
  Role role{};
  bool extended = false;
  if (const uint32_t e = validate_object_cps(f, cps, role, extended); e != ERR_OK) {
    return tl::unexpected(e);
  }
  int index = find_object(f, cps.ulCanID, extended);
  if (index >= 0) {
    // «…dürfen sich die CPS-Parameter beim Öffnen eines Kanals zu einem bestehenden
    // Message-Objekt nicht von denen bei seiner Konfiguration unterscheiden.» Decision: the
    // device, the flags other than _CP_SYNC_CALLBACK (a property of the channel's callback)
    // and the timeout must match.
    const Object& o = f.objects[static_cast<std::size_t>(index)];
    if (o.cps.usDevice != cps.usDevice || o.cps.usTimeout != cps.usTimeout ||
        ((o.cps.usFlags ^ cps.usFlags) & ~_CP_SYNC_CALLBACK) != 0) {
      return tl::unexpected(uint32_t{ERR_XCAN_CPS_MISMATCH});
    }
  } else {
    Object o;
    o.id = cps.ulCanID;
    o.extended = extended;
    o.role = role;
    o.cps = cps;
    o.excl = (cps.usFlags & XCAN_EXCL_BUFFER) != 0;
    o.no_int = (cps.usFlags & XCAN_NO_INT) != 0;
    if (const uint32_t e = check_plan(f, o, f.filter_remote, f.filter_channel != 0); e != ERR_OK) {
      return tl::unexpected(e);
    }
    f.objects.push_back(o);
    index = static_cast<int>(f.objects.size() - 1);
    plan(i);
  }
  const ChannelHandle h = add_channel(Channel{i, Kind::object, cps, callback, index});
  bus_on(i);
  return h;
}

uint32_t XcanModule::close_channel(ChannelHandle h) {
  Channel* c = find(h);
  if (c == nullptr) {
    return ERR_XCAN_INVALID_HANDLE;
  }
  const unsigned i = c->iface;
  Interface& f = ifaces_[i];
  const Kind kind = c->kind;
  cancel_waiters(h);
  channels_.erase(h);
  if (kind == Kind::filter) {
    // Decision: closing the filter channel forgets the manual mask; buffer 15 goes back to
    // its automatic filter.
    f.filter_channel = 0;
    f.manual_mask.reset();
    f.filter_remote = false;
    f.filter_id = XCAN_AUTO_ID;
    program_buffer15(i);
  } else if (kind == Kind::general) {
    f.general_channel = 0;
  }
  const bool any = std::any_of(channels_.begin(), channels_.end(),
                               [i](const auto& e) { return e.second.iface == i; });
  if (!any) {
    // Decision: the manual does not say whether an object dies with its last channel. Objects
    // stay while the interface has channels (so its buffer plan never shrinks under a running
    // transmission); when its last channel closes, the interface returns to its initial state:
    // no objects, bus off, the bit timing kept.
    reset_interface(i);
  }
  return ERR_OK;
}

void XcanModule::reset_interface(unsigned i) {
  Interface& f = ifaces_[i];
  const XCAN_BITPARAMS params = f.params;
  const bool low = f.low_speed;
  const bool line = f.line_error;
  f.chip.hardware_reset();
  f.objects.clear();
  f.buffers = {};
  f.shared = false;
  f.fifo.clear();
  f.filter_channel = 0;
  f.manual_mask.reset();
  f.filter_id = XCAN_AUTO_ID;
  f.filter_remote = false;
  f.general_channel = 0;
  f.general_object = -1;
  f.controlled = false;
  f.stopped = false;
  f.error_bits = 0;
  f.last_lec = 0;
  f.params = params;
  f.low_speed = low;
  f.line_error = line;
  init_chip(i);
}

// --- services ---

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
    return ULONG{ifaces_[c->iface].objects[static_cast<std::size_t>(c->object)].count};
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
