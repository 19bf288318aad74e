// The X-CAN-2i MDD's channels: the module, opening and closing channels, the dynamic object
// model and its checks. The services are in xcan_services.cpp, the driver side in
// xcan_driver.cpp and xcan_interrupt.cpp.
#include <algorithm>

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
    Interface& f = ifaces_[i];
    f.events.module = this;
    f.events.iface = i;
    f.mgr.emplace(f.chip, f.events, kFifoDepth, kMaxObjects);
    f.chip.on_interrupt = [this, i](SimTime at) {
      Interface& g = ifaces_[i];
      if (!g.isr_scheduled) {
        g.isr_scheduled = true;
        scheduler_.schedule_at(at, [this, i](SimTime) {
          ifaces_[i].isr_scheduled = false;
          ifaces_[i].mgr->service();
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

void XcanModule::set_buffer_load_time(int64_t ns) {
  for (Interface& f : ifaces_) {
    f.mgr->set_load_time(scheduler_, ns);
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
    if (!f.mgr->buffer15_objects().empty() && cps.ulCanID != XCAN_AUTO_ID) {
      return tl::unexpected(uint32_t{ERR_XCAN_AUTO_ID_REQUIRED});
    }
    ManualFilter manual;
    manual.open = true;
    manual.remote = (cps.usFlags & XCAN_REMOTE) != 0;
    manual.extended = ext;
    if (cps.ulCanID != XCAN_AUTO_ID) {
      manual.id = cps.ulCanID;
    }
    if (const uint32_t e = check_plan(f, nullptr, manual); e != ERR_OK) {
      return tl::unexpected(e);
    }
    const ChannelHandle h = add_channel(Channel{i, Kind::filter, cps, callback});
    f.filter_channel = h;
    f.mgr->manual() = manual;
    f.mgr->program_buffer15();
    return h;
  }
  if (cps.usDevice != DEVICE_BUS_OUT && cps.usDevice != DEVICE_BUS_IN) {
    return tl::unexpected(uint32_t{ERR_XCAN_INVALID_CPS});
  }
  if (cps.ulCanID == XCAN_GENERAL_ID) {
    // «dieser Kanaltyp ist ab MDD Version 3.C implementiert»: before, no such channel.
    if (mdd_version_ < kMdd3C || cps.usDevice != DEVICE_BUS_OUT || !(cps.usFlags & _CP_EXCLUSIVE) ||
        (cps.usFlags & ~(_CP_EXCLUSIVE | _CP_SYNC_CALLBACK | XCAN_NO_INT)) ||
        ((cps.usFlags & XCAN_NO_INT) && cps.usTimeout == 0)) {
      return tl::unexpected(uint32_t{ERR_XCAN_INVALID_CPS});
    }
    if (f.general_channel != 0) {
      return tl::unexpected(uint32_t{ERR_XCAN_CHANNEL_BUSY});
    }
    if (f.general_object < 0) {
      ManagedObject m;
      m.send = true;
      m.general = true;
      m.excl = true;
      if (const uint32_t e = check_plan(f, &m, f.mgr->manual()); e != ERR_OK) {
        return tl::unexpected(e);
      }
      f.general_object = add_object(i, m, Object{Role::general, cps, false, 0});
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
  // «Das Flag steht erst ab MDD Version 3.C zur Verfügung.»
  if ((cps.usFlags & XCAN_NEW_ONLY) && mdd_version_ < kMdd3C) {
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

uint32_t XcanModule::check_plan(const Interface& f, const ManagedObject* added,
                                const ManualFilter& manual) const {
  // Decision: an open that would mix passive send and passive receive objects in buffer 15
  // (or both formats, in mixed mode) fails with ERR_XCAN_BUFFER15_MIXED (SL-CANi diag 2Ch).
  switch (f.mgr->check(added, manual)) {
    case PlanError::none:
      return ERR_OK;
    case PlanError::excl_limit:
      return ERR_XCAN_EXCL_LIMIT;
    case PlanError::no_memory:
      return ERR_XCAN_NO_MEMORY;
    case PlanError::buffer15_mixed:
      return ERR_XCAN_BUFFER15_MIXED;
  }
  return ERR_XCAN_PARAM;
}

int XcanModule::add_object(unsigned i, const ManagedObject& m, const Object& o) {
  Interface& f = ifaces_[i];
  f.objects.push_back(o);
  return f.mgr->add(m);
}

tl::expected<ChannelHandle, uint32_t> XcanModule::open_object(const CPS_XCAN& cps, bool callback) {
  const unsigned i = cps.usChannel;
  Interface& f = ifaces_[i];
  Role role{};
  bool extended = false;
  if (const uint32_t e = validate_object_cps(f, cps, role, extended); e != ERR_OK) {
    return tl::unexpected(e);
  }
  int index = f.mgr->find(cps.ulCanID, extended);
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
    ManagedObject m;
    m.id = cps.ulCanID;
    m.extended = extended;
    m.send = role == Role::active_send || role == Role::passive_send;
    m.active = role == Role::active_send || role == Role::active_receive;
    m.passive = !m.active;
    m.excl = (cps.usFlags & XCAN_EXCL_BUFFER) != 0;
    if (const uint32_t e = check_plan(f, &m, f.mgr->manual()); e != ERR_OK) {
      return tl::unexpected(e);
    }
    index = add_object(i, m, Object{role, cps, (cps.usFlags & XCAN_NO_INT) != 0, 0});
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
    f.mgr->manual() = ManualFilter{};
    f.mgr->program_buffer15();
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
  f.mgr->reset();
  f.filter_channel = 0;
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

}  // namespace canemu::model::sorcus
