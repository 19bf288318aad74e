// The X-CAN-2i MDD's side of the interrupt service (the buffer manager serves the buffers): the
// 82527's status changes (the error callback) and what the buffers report: callbacks and
// completions.
#include <algorithm>

#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

namespace canemu::model::sorcus {

using namespace i82527;

void XcanModule::serve_status(unsigned i) {
  Interface& f = ifaces_[i];
  // The high word of the state word is the last error code: the 82527's codes are the manual's.
  const uint8_t rising = serve_status_register(f.chip, f.error_bits, f.last_lec);
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

void XcanModule::Events::sent(const SendRequest& r, bool /*answered*/) {
  module->finished(iface, r);
}

void XcanModule::Events::received(int object, const Frame& frame, bool /*lost*/) {
  module->received(iface, object, frame);
}

void XcanModule::finished(unsigned i, const SendRequest& r) {
  Object& o = ifaces_[i].objects[static_cast<std::size_t>(r.object)];
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
  ManagedObject& m = f.mgr->object(object);
  m.size = frame.dlc() > 8 ? 8 : frame.dlc();
  std::fill(m.data.begin(), m.data.end(), uint8_t{0});
  std::copy_n(frame.data().begin(), m.size, m.data.begin());
  ++o.count;
  const std::vector<uint8_t> data(m.data.begin(), m.data.begin() + m.size);
  for (auto& [h, c] : channels_) {
    if (c.iface != i || c.object != object) {
      continue;
    }
    c.new_data = true;
    if (o.role == Role::passive_receive || c.start_pending) {
      c.start_pending = false;
      XcanCallback cb;
      cb.arg = CallbackArg::data;
      cb.size = m.size;
      cb.data = m.data;
      emit(h, c, cb);
    }
  }
  complete_waiters(i, object, true, data);
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
