// The SL-CANi's driver task SL64TASK: the data and send services, the interrupt and what it
// reports (service routines, function 14's service requests and the interrupt lock).
#include <algorithm>

#include "canemu/firmware_model/adapters/sorcus/slcan_module.hpp"

namespace canemu::model::sorcus {

using namespace i82527;

// --- data and sending ---

USHORT SlcanModule::set_data(SL064Handle handle, std::span<const uint8_t> data) {
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  if (phase_ != Phase::configured) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  const int k = object_of(handle);
  // Send objects only; Decision: more than 8 bytes is 2Ah as well.
  if (k < 0 || !(objects_[static_cast<std::size_t>(k)].flags & _SL064_SEND) || data.size() > 8) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  ManagedObject& m = mgr_.object(k);
  m.size = static_cast<uint8_t>(data.size());
  m.data.fill(0);
  std::copy(data.begin(), data.end(), m.data.begin());
  // It does not send; a buffer holding the object (an answer to a remote frame) gets the data.
  mgr_.update_data(k);
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::get_data(SL064Handle handle, std::array<uint8_t, 8>& data, uint8_t& size) {
  const uint8_t wanted = size;
  size = 0;
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  if (phase_ != Phase::configured) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  const int k = object_of(handle);
  if (k < 0) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  Object& o = objects_[static_cast<std::size_t>(k)];
  const ManagedObject& m = mgr_.object(k);
  size = std::min<uint8_t>(wanted, std::min<uint8_t>(m.size, 8));
  data.fill(0);
  std::copy_n(m.data.begin(), size, data.begin());
  // The warnings, the most telling first (Decision: one code holds one of them).
  if (o.lost) {
    o.lost = false;
    return done(SL064_DIAG_LOST);
  }
  if (m.buffer >= 1 && m.buffer <= 14 && !m.send) {
    // The frame is in the buffer, the interrupt has not handled it (the lock holds it back).
    if (pair_is_set(chip_.read(message(m.buffer) + CTRL1), NEWDAT)) {
      return done(SL064_DIAG_NOT_HANDLED);
    }
  }
  return done(wanted != m.size ? SL064_DIAG_SIZE_MISMATCH : SL064_DIAG_OK);
}

USHORT SlcanModule::send(SL064Handle handle, bool remote) {
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  // Decision: sending needs communication on (sl064_start_com): 2Dh before.
  if (phase_ != Phase::configured || !running_) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  const int k = object_of(handle);
  if (k < 0) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  const USHORT flags = objects_[static_cast<std::size_t>(k)].flags;
  // send_data: an active send object; send_data_request: an active receive object.
  if (!(flags & _SL064_ACTIVE) || ((flags & _SL064_SEND) != 0) == remote) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  const bool was_pending = mgr_.pending(k);
  switch (mgr_.request(SendRequest{k, remote, std::nullopt})) {
    case RequestResult::fifo_full:
      return done(SL064_DIAG_FIFO_FULL);
    case RequestResult::queued:
      // Decision: a request behind the object's own pending one is warning 3; one waiting for
      // a temporary buffer is warning 6.
      return done(was_pending ? SL064_DIAG_NOT_SENT : SL064_DIAG_QUEUED);
    case RequestResult::merged:
      return done(SL064_DIAG_NOT_SENT);
    case RequestResult::started:
      break;
  }
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::send_data(SL064Handle handle) {
  return send(handle, false);
}

USHORT SlcanModule::send_data_request(SL064Handle handle) {
  return send(handle, true);
}

USHORT SlcanModule::clear_msg(SL064Handle handle) {
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  if (phase_ != Phase::configured) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  const int k = object_of(handle);
  if (k < 0) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  // The repetition ends and the temporary buffer is free. Decision: nothing pending is no error.
  (void)mgr_.abort(k);
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::get_id(SL064Handle handle, ULONG& id, std::optional<ULONG> call_id) {
  if (phase_ != Phase::configured) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  if (handle == 0 && mask_set_) {
    // Decision (digest §7.17): handle 0 names the unconfigured message the mask's service
    // routine was called for: the routine's own call's (the library passes it back), outside a
    // routine the last one a call was made for.
    id = call_id.value_or(unconfigured_id_);
    return done(SL064_DIAG_OK);
  }
  const int k = object_of(handle);
  if (k < 0) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  id = mgr_.object(k).id;
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::get_msg_count(SL064Handle handle, ULONG& count) {
  if (phase_ != Phase::configured) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  const int k = object_of(handle);
  if (k < 0) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  count = objects_[static_cast<std::size_t>(k)].count;
  return done(SL064_DIAG_OK);
}

// --- service requests ---

USHORT SlcanModule::evaluate_srq(SL064Handle& handle) {
  handle = 0;
  if (srq_.empty()) {
    return 0;  // «…kein SRQ vom Treiberprogramm gesendet»
  }
  const Srq r = srq_.front();
  srq_.pop_front();
  handle = r.handle;
  if (r.handle == 0 && r.status == 0) {
    unconfigured_id_ = r.id;  // get_id(0) now names this request's frame
  }
  return r.status;
}

void SlcanModule::end_of_srq() {
  if (!int_mask_ || !locked_) {
    return;
  }
  locked_ = false;
  if (chip_.interrupt_line()) {
    on_interrupt(scheduler_.now());
  }
}

// --- the interrupt ---

void SlcanModule::on_interrupt(SimTime at) {
  if (isr_scheduled_) {
    return;
  }
  isr_scheduled_ = true;
  scheduler_.schedule_at(at, [this](SimTime) {
    isr_scheduled_ = false;
    mgr_.service();
  });
}

void SlcanModule::call(SlcanServiceCall c) {
  c.at = scheduler_.now();
  if (c.task == driver_task() && c.func == SL064_SRQ_SERVICE_FUNC) {
    // Function 14: the cause is stored, the PC gets a service request. With the lock enabled,
    // the controller's interrupt stays locked until sl064_end_of_srq.
    if (srq_.size() < kSrqDepth) {
      srq_.push_back(Srq{c.handle, static_cast<USHORT>(c.status), c.id});
    } else {
      ++srq_overflows_;
    }
    if (int_mask_) {
      locked_ = true;
    }
    sink_.service_request(c.at, SL064_SRQ_WORD(slot_));
    return;
  }
  if (routines_.contains({c.task, c.func})) {
    sink_.service(c);
  }
}

void SlcanModule::serve_status() {
  const uint8_t rising = serve_status_register(chip_, error_bits_, last_lec_);
  // «Ein Fehlerstand > 96 wird als 'Stark gestörter Bus' interpretiert und genau wie der
  // Übergang in die Betriebsart 'Bus-Off' mit einem Interrupt signalisiert»: status 1 at the
  // rise of WARN, 2 at the rise of BOFF (as on the X-CAN-2i: the 82527's limit of 96).
  if (err_task_ == 0 && err_func_ == 0) {
    return;
  }
  if (rising & STATUS_WARN) {
    call(SlcanServiceCall{
        {}, SlcanServiceCall::Kind::error, err_task_, err_func_, 0, SL064_STATUS_HEAVY});
  }
  if (rising & STATUS_BOFF) {
    call(SlcanServiceCall{
        {}, SlcanServiceCall::Kind::error, err_task_, err_func_, 0, SL064_STATUS_BUS_OFF});
  }
}

void SlcanModule::message_event(int object) {
  Object& o = objects_[static_cast<std::size_t>(object)];
  ++o.count;  // «wie viele Interrupts das Message-Objekt … ausgelöst hat»
  if (o.task != 0 || o.func != 0) {
    call(SlcanServiceCall{
        {}, SlcanServiceCall::Kind::message, o.task, o.func, handle_of(object), 0});
  }
}

void SlcanModule::sent(const SendRequest& r, bool /*answered*/) {
  if (r.remote || r.object < 0) {
    return;  // a remote frame: the answer's reception is the event
  }
  // _SL064_DISABLE_INT: no interrupt when it sends. An answer to a remote frame reports here,
  // after its data frame (digest §1.3, footnote 1), not at the remote frame.
  if (objects_[static_cast<std::size_t>(r.object)].flags & _SL064_DISABLE_INT) {
    return;
  }
  message_event(r.object);
}

void SlcanModule::received(int object, const Frame& frame, bool lost) {
  Object& o = objects_[static_cast<std::size_t>(object)];
  if (o.flags & _SL064_SEND) {
    return;
  }
  ManagedObject& m = mgr_.object(object);
  m.size = std::min<uint8_t>(frame.dlc(), 8);
  m.data.fill(0);
  std::copy_n(frame.data().begin(), std::min<std::size_t>(frame.data().size(), 8), m.data.begin());
  o.lost = o.lost || lost;
  message_event(object);
}

void SlcanModule::unconfigured(const Frame& frame) {
  if (!mask_set_ || (mask_task_ == 0 && mask_func_ == 0)) {
    ++discarded_;
    return;
  }
  if (!(mask_task_ == driver_task() && mask_func_ == SL064_SRQ_SERVICE_FUNC)) {
    unconfigured_id_ = frame.id();  // with function 14: when its request is evaluated
  }
  call(SlcanServiceCall{
      {}, SlcanServiceCall::Kind::message, mask_task_, mask_func_, 0, 0, frame.id()});
}

}  // namespace canemu::model::sorcus
