// The SL-CANi's driver task SL64TASK: the configuration phase and its order, message objects
// and their rules, communication on and off. The data and send services, service routines and
// service requests are in slcan_services.cpp.
#include "canemu/firmware_model/adapters/sorcus/slcan_module.hpp"

namespace canemu::model::sorcus {

namespace {

constexpr USHORT kKnownFlags =
    _SL064_SEND | _SL064_ACTIVE | _SL064_PASSIVE | _SL064_EXCL_BUFFER | _SL064_DISABLE_INT;

}  // namespace

SlcanModule::SlcanModule(SimScheduler& scheduler, uint8_t slot, SlcanSink& sink)
    : scheduler_(scheduler),
      slot_(slot),
      sink_(sink),
      mgr_(chip_, events_, kFifoDepth, kMaxObjects) {
  events_.m = this;
  chip_.on_interrupt = [this](SimTime at) { on_interrupt(at); };
}

void SlcanModule::connect(CanBus& bus) {
  bus_ = &bus;
  chip_.connect(bus);
  mgr_.init_chip(false);  // the 10 MHz oscillator is the system clock: no DSC
}

void SlcanModule::reset() {
  chip_.hardware_reset();
  mgr_.reset();
  if (bus_ != nullptr) {
    mgr_.init_chip(false);
  }
  objects_.clear();
  handle_base_ = 0;
  phase_ = Phase::off;
  mask_set_ = false;
  running_ = false;
  settings_.reset();
  err_task_ = err_func_ = mask_task_ = mask_func_ = 0;
  diag_ = 0;
  led_ = false;
  error_bits_ = 0;
  last_lec_ = 0;
  int_mask_ = false;
  locked_ = false;
  srq_.clear();
}

bool SlcanModule::write_eeprom(unsigned word, uint16_t value) {
  if (!slcan_eeprom_writable(word)) {
    return false;
  }
  eeprom_[word] = value;
  return true;
}

USHORT SlcanModule::done(USHORT diagnosis) {
  diag_ = diagnosis;
  // «Der Rückgabewert nimmt den Wert … 42h (in PC-Programm) an, wenn das Treiberprogramm einen
  // Fehler signalisiert»; a warning is not signalled through the return value.
  return diagnosis >= SL064_DIAG_FIRST_ERROR ? USHORT{SL064_E_DRIVER} : USHORT{0};
}

std::optional<USHORT> SlcanModule::fault_diagnosis() const {
  switch (fault_) {
    case SlcanFault::none:
      return std::nullopt;
    case SlcanFault::no_response:
      return SL064_DIAG_NO_RESPONSE;
    case SlcanFault::reset:
      return SL064_DIAG_RESET_FAILED;
    case SlcanFault::async_init:
      return SL064_DIAG_ASYNC_INIT;
    case SlcanFault::sync_init:
      return SL064_DIAG_SYNC_INIT;
    case SlcanFault::no_m6p0500:
      return SL064_DIAG_NO_M6P0500;
    case SlcanFault::m6p0500_error:
      return SL064_DIAG_M6P0500_ERROR;
    case SlcanFault::scc_frequency:
      return SL064_DIAG_SCC_FREQUENCY;
  }
  return std::nullopt;
}

int SlcanModule::object_of(SL064Handle handle) const {
  const int k = static_cast<int>(handle) - static_cast<int>(handle_base_) - 1;
  return handle == 0 || k < 0 || k >= static_cast<int>(objects_.size()) ? -1 : k;
}

bool SlcanModule::installed(USHORT task, USHORT func) const {
  return (task == driver_task() && func == SL064_SRQ_SERVICE_FUNC) ||
         routines_.contains({task, func});
}

// --- the configuration phase ---

USHORT SlcanModule::bib_startup() {
  // The library's start: it finds this slot's SL64TASK. Decision: a second call changes
  // nothing.
  if (const auto d = fault_diagnosis(); d && fault_ != SlcanFault::reset) {
    return done(*d);
  }
  if (phase_ == Phase::off) {
    phase_ = Phase::started;
  }
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::config_module(USHORT err_task, USHORT err_func) {
  if (const auto d = fault_diagnosis()) {
    return done(*d);
  }
  // «sl064_config_module … darf pro SL-CANi nur einmal aufgerufen werden» and needs
  // sl064_bib_startup before it.
  if (phase_ != Phase::started) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  // Decision (digest §7.19): the EEPROM is read here, so a change takes effect at the next
  // configuration (after the S-Link's reset: the session's end or a canemud restart).
  const auto s = slcan_settings(eeprom_);
  if (!s) {
    return done(s.error().diagnosis);
  }
  settings_ = *s;
  mgr_.program_timing(s->timing);
  err_task_ = err_task;
  err_func_ = err_func;
  phase_ = Phase::configured;
  // Decision: an error routine (0, 0) is none; one not installed gives warning 2.
  const bool routine = err_task == 0 && err_func == 0 ? true : installed(err_task, err_func);
  return done(routine ? SL064_DIAG_OK : SL064_DIAG_NO_ROUTINE);
}

USHORT SlcanModule::config_msg_object(const SL064MsgType& config, SL064Handle& handle) {
  handle = 0;  // «…bei einem Fehler auf 0 gesetzt»
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  // Objects come after sl064_config_module and before sl064_set_acceptance_mask and
  // sl064_start_com. Decision: also after sl064_stop_com (communication off), not while it runs.
  if (phase_ != Phase::configured || mask_set_ || running_) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  USHORT flags = config.control_flags;
  const bool send = (flags & _SL064_SEND) != 0;
  // Decision: a flag outside the five, a send object without ACTIVE or PASSIVE, a receive object
  // without either, _SL064_DISABLE_INT on a receive object and an identifier beyond the range
  // of the EEPROM's format are "an object of the wrong type": 2Ah.
  if ((flags & ~kKnownFlags) != 0 || ((flags & _SL064_DISABLE_INT) && !send)) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  if (flags & _SL064_DISABLE_INT) {
    flags |= _SL064_ACTIVE | _SL064_PASSIVE;  // «…sind immer aktiv und passiv»
  }
  if ((flags & (_SL064_ACTIVE | _SL064_PASSIVE)) == 0) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  const bool extended = settings_->extended;
  if (config.id > (extended ? SL064_MAX_ID_29 : SL064_MAX_ID_11)) {
    return done(SL064_DIAG_WRONG_HANDLE);
  }
  if (mgr_.find(config.id, extended) >= 0) {
    return done(SL064_DIAG_DUPLICATE_ID);
  }
  ManagedObject m;
  m.id = config.id;
  m.extended = extended;
  m.send = send;
  m.active = (flags & _SL064_ACTIVE) != 0;
  m.passive = (flags & _SL064_PASSIVE) != 0;
  m.excl = (flags & _SL064_EXCL_BUFFER) != 0;
  m.preemptible = (flags & _SL064_DISABLE_INT) && !m.excl;
  switch (mgr_.check(&m, mgr_.manual())) {
    case PlanError::none:
      break;
    case PlanError::excl_limit:
      return done(SL064_DIAG_EXCL_LIMIT);
    case PlanError::no_memory:
      return done(SL064_DIAG_NO_MEMORY);
    case PlanError::buffer15_mixed:
      return done(SL064_DIAG_BUFFER15_MIXED);
  }
  objects_.push_back(Object{flags, config.serv_task, config.serv_func, 0, false});
  const int k = mgr_.add(m);  // the payload starts as 0 bytes of 0
  handle = handle_of(k);
  const bool routine = (config.serv_task == 0 && config.serv_func == 0) ||
                       installed(config.serv_task, config.serv_func);
  return done(routine ? SL064_DIAG_OK : SL064_DIAG_NO_ROUTINE);
}

USHORT SlcanModule::clear_configuration() {
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  if (phase_ != Phase::configured) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  // «Anschließend können neue Message-Objekte konfiguriert werden, ohne daß
  // sl064_config_module erneut aufgerufen werden muß»; communication stops until
  // sl064_start_com. Decision: the acceptance mask is part of the configuration and goes too
  // (it may be set once more); handles of the old objects stay invalid (2Ah).
  mgr_.reset();
  mgr_.init_chip(false);  // every buffer invalid, off the bus
  mgr_.program_timing(settings_->timing);
  handle_base_ = static_cast<USHORT>(handle_base_ + objects_.size());
  objects_.clear();
  mask_set_ = false;
  mask_task_ = mask_func_ = 0;
  running_ = false;
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::start_com() {
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  // Decision: a second start_com while communication runs is out of order too (2Dh); after
  // bus-off the way out is sl064_stop_com, then sl064_start_com.
  if (phase_ != Phase::configured || running_) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  running_ = true;
  // INI cleared: after bus-off the 82527 waits 128 x 11 recessive bits, then both counters
  // are 0.
  mgr_.set_bus_on(true);
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::stop_com() {
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  if (phase_ != Phase::configured) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  // Decision: pending requests stay and go when communication starts again.
  running_ = false;
  mgr_.set_bus_on(false);
  return done(SL064_DIAG_OK);
}

USHORT SlcanModule::get_diagnosis() {
  const USHORT d = diag_;
  diag_ = 0;  // «Die Diagnosemeldung wird vom Treiberprogramm nach dem Lesen = 0 gesetzt.»
  return d;
}

USHORT SlcanModule::set_acceptance_mask(ULONG& mask, USHORT usage, USHORT serv_task,
                                        USHORT serv_func) {
  if (fault_ == SlcanFault::no_response) {
    return done(SL064_DIAG_NO_RESPONSE);
  }
  // «Die Funktion darf pro S-Link nur einmal ausgeführt werden!», after the objects and before
  // sl064_start_com.
  if (phase_ != Phase::configured || mask_set_ || running_) {
    return done(SL064_DIAG_CALL_ORDER);
  }
  if (usage > 1) {
    return done(SL064_DIAG_WRONG_HANDLE);  // Decision: usage other than 0 and 1 is 2Ah
  }
  const bool extended = settings_->extended;
  const uint32_t width = id_width_mask(extended);
  ManualFilter manual;
  manual.open = true;
  manual.remote = usage == 1;
  manual.extended = extended;
  manual.mask = mask & width;
  // Decision (digest §7.17): the mask compares with the automatic ID mask of buffer 15's
  // objects, or with 0 when there are none.
  const std::vector<int> in15 = mgr_.buffer15_objects();
  if (!in15.empty()) {
    // A 1 where the automatic mask has 0, or the other kind of frame, would lock configured
    // messages out: unchanged, 29h.
    const AcceptanceFilter automatic = mgr_.buffer15_filter();
    const bool remote = mgr_.object(in15.front()).send;
    if ((*manual.mask & ~automatic.acc) != 0 || remote != manual.remote) {
      return done(SL064_DIAG_MASK_EXCLUDES);
    }
  } else if (mgr_.check(nullptr, manual) != PlanError::none) {
    return done(SL064_DIAG_MASK_EXCLUDES);
  }
  mgr_.manual() = manual;
  mgr_.program_buffer15();
  mask_set_ = true;
  mask_task_ = serv_task;
  mask_func_ = serv_func;
  mask = *manual.mask;  // the mask in force
  const bool routine = (serv_task == 0 && serv_func == 0) || installed(serv_task, serv_func);
  return done(routine ? SL064_DIAG_OK : SL064_DIAG_NO_ROUTINE);
}

}  // namespace canemu::model::sorcus
