#include "canemu/firmware_model/adapters/ixxat/lin_line.hpp"

#include <algorithm>

namespace canemu::model::ixxat {

namespace {

using lin::ErrorKind;

uint8_t vci_error(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::bit:
      return LIN_ERROR_BIT;
    case ErrorKind::checksum:
      return LIN_ERROR_CHKSUM;
    case ErrorKind::parity:
      return LIN_ERROR_PARITY;
    case ErrorKind::no_response:
      return LIN_ERROR_SLNORE;
    case ErrorKind::sync:
      return LIN_ERROR_SYNC;
    case ErrorKind::inactive:
      return LIN_ERROR_NOBUS;
    case ErrorKind::other:
      break;
  }
  return LIN_ERROR_OTHER;
}

constexpr uint8_t kNoPid = 0xFF;

lin::Response response_of(const LINMSG& msg) {
  lin::Response r;
  r.size = msg.uMsgInfo.Bytes.bDlen;
  std::copy(msg.abData, msg.abData + r.size, r.data.begin());
  r.checksum = msg.uMsgInfo.Bits.ecs ? lin::Checksum::enhanced : lin::Checksum::classic;
  return r;
}

}  // namespace

LinLine::LinLine(SimScheduler& scheduler, lin::LinBus& bus, const Clocks& clocks, SimTime epoch)
    : scheduler_(scheduler), controller_(bus), clocks_(clocks), epoch_(epoch) {
  controller_.set_listener(this);
  schedule_time_overrun();
}

LinLine::~LinLine() {
  if (overrun_event_) {
    scheduler_.cancel(*overrun_event_);
  }
}

uint32_t LinLine::ticks(SimTime t) const {
  return static_cast<uint32_t>(
      ns_to_ticks((t - epoch_).ns(), clocks_.tsc_divisor, clocks_.clock_hz));
}

// ---------------------------------------------------------------- the control unit

HRESULT LinLine::open_control() {
  if (control_open_) {
    return VCI_E_ACCESSDENIED;
  }
  control_open_ = true;
  return VCI_OK;
}

void LinLine::close_control() {
  control_open_ = false;
  release_if_unused();
}

void LinLine::release_if_unused() {
  if (!control_open_ && monitors_.empty()) {
    reset_line();  // nobody hears the info message
  }
}

HRESULT LinLine::init_line(const LININITLINE& init) {
  if ((init.bOpMode & ~(LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS)) != 0 || init.bReserved != 0) {
    return VCI_E_INVALIDARG;
  }
  const bool master = (init.bOpMode & LIN_OPMODE_MASTER) != 0;
  if (init.wBitrate == LIN_BITRATE_AUTO) {
    if (master) {
      return VCI_E_INVALIDARG;  // a commander sets the rate: detection is a responder's
    }
  } else if (init.wBitrate < LIN_BITRATE_MIN || init.wBitrate > LIN_BITRATE_MAX) {
    return VCI_E_INVALIDARG;
  }
  reset_line();  // «InitLine internally performs ResetLine first»
  op_mode_ = init.bOpMode;
  bitrate_ = init.wBitrate;
  controller_.configure(master ? lin::LinController::Mode::master : lin::LinController::Mode::slave,
                        init.wBitrate);
  initialized_ = true;
  return VCI_OK;
}

HRESULT LinLine::reset_line() {
  const bool was = initialized_ || controller_.online();
  controller_.reset();
  initialized_ = false;
  op_mode_ = LIN_OPMODE_SLAVE;
  bitrate_ = LIN_BITRATE_UNDEF;
  if (was) {
    info(LIN_INFO_RESET);
  }
  return VCI_OK;
}

HRESULT LinLine::start_line() {
  if (!initialized_) {
    return VCI_E_INVALID_STATE;
  }
  if (!controller_.online()) {
    controller_.start();
    LINMSG m = event_message(LIN_MSGTYPE_INFO, ticks(scheduler_.now()), LIN_INFO_START, 0);
    broadcast(m);
  }
  return VCI_OK;
}

HRESULT LinLine::stop_line() {
  if (controller_.online()) {
    controller_.stop();
    info(LIN_INFO_STOP);
  }
  return VCI_OK;
}

HRESULT LinLine::write_message(bool send, const LINMSG& msg) {
  const auto& b = msg.uMsgInfo.Bytes;
  const uint8_t type = b.bType;
  if (!send) {
    // The response table: a DATA message with an identifier and 1..8 bytes.
    if (type != LIN_MSGTYPE_DATA || b.bPid > lin::kMaxId || b.bDlen == 0 ||
        b.bDlen > lin::kMaxData) {
      return VCI_E_INVALIDARG;
    }
    controller_.set_response(b.bPid, response_of(msg));
    return VCI_OK;
  }
  using Result = lin::LinController::SendResult;
  Result r = Result::ok;
  switch (type) {
    case LIN_MSGTYPE_DATA:
      if (b.bPid > lin::kMaxId || b.bDlen > lin::kMaxData ||
          (!msg.uMsgInfo.Bits.ido && b.bDlen == 0)) {
        return VCI_E_INVALIDARG;
      }
      r = msg.uMsgInfo.Bits.ido ? controller_.send_header(b.bPid)
                                : controller_.send_frame(b.bPid, response_of(msg));
      break;
    case LIN_MSGTYPE_SLEEP:
      r = controller_.send_sleep();
      break;
    case LIN_MSGTYPE_WAKEUP:
      r = controller_.send_wakeup();
      break;
    default:
      return VCI_E_INVALIDARG;
  }
  switch (r) {
    case Result::ok:
      return VCI_OK;
    case Result::busy:
      return VCI_E_TXQUEUE_FULL;
    case Result::offline:
      return VCI_E_INVALID_STATE;
    case Result::not_master:
      return VCI_E_INVALIDARG;
  }
  return VCI_E_UNEXPECTED;
}

uint8_t LinLine::status_byte() const {
  return controller_.online() ? 0 : LIN_STATUS_ININIT;
}

LINLINESTATUS LinLine::line_status() const {
  LINLINESTATUS s{};
  s.bOpMode = op_mode_;
  s.wBitrate =
      bitrate_ == LIN_BITRATE_AUTO ? static_cast<uint16_t>(controller_.bitrate()) : bitrate_;
  s.dwStatus = status_byte();
  return s;
}

LINCAPABILITIES LinLine::capabilities() const {
  LINCAPABILITIES c{};
  c.dwFeatures = kFeatures;
  c.dwClockFreq = clocks_.clock_hz;
  c.dwTscDivisor = clocks_.tsc_divisor;
  return c;
}

// ---------------------------------------------------------------- monitors

tl::expected<MonitorId, HRESULT> LinLine::open_monitor(bool exclusive) {
  if (exclusive_ || (exclusive && !monitors_.empty())) {
    return tl::unexpected(VCI_E_ACCESSDENIED);
  }
  exclusive_ = exclusive;
  monitors_.push_back(Monitor{next_monitor_, false, false, nullptr, {}});
  return next_monitor_++;
}

void LinLine::close_monitor(MonitorId id) {
  std::erase_if(monitors_, [id](const Monitor& m) { return m.id == id; });
  if (monitors_.empty()) {
    exclusive_ = false;
  }
  release_if_unused();
}

LinLine::Monitor* LinLine::find(MonitorId id) {
  auto it = std::find_if(monitors_.begin(), monitors_.end(),
                         [id](const Monitor& m) { return m.id == id; });
  return it == monitors_.end() ? nullptr : &*it;
}

const LinLine::Monitor* LinLine::find(MonitorId id) const {
  return const_cast<LinLine*>(this)->find(id);
}

HRESULT LinLine::init_monitor(MonitorId id, LinMonitorPort* port) {
  Monitor* m = find(id);
  if (m == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  if (m->active) {
    return VCI_E_INVALID_STATE;
  }
  m->port = port;
  m->initialized = true;
  m->state = LinMonitorState{};
  m->state.initialized = true;
  return VCI_OK;
}

HRESULT LinLine::activate(MonitorId id) {
  Monitor* m = find(id);
  if (m == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  if (!m->initialized) {
    return VCI_E_NOT_INITIALIZED;
  }
  m->active = true;
  m->state.activated = true;
  return VCI_OK;
}

HRESULT LinLine::deactivate(MonitorId id) {
  Monitor* m = find(id);
  if (m == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  m->active = false;
  m->state.activated = false;
  return VCI_OK;
}

std::optional<LinMonitorState> LinLine::monitor_state(MonitorId id) const {
  const Monitor* m = find(id);
  if (m == nullptr) {
    return std::nullopt;
  }
  return m->state;
}

// ---------------------------------------------------------------- messages

LINMSG LinLine::event_message(uint8_t type, uint32_t time, uint8_t data0, uint8_t data1) const {
  LINMSG m{};
  m.dwTime = time;
  m.uMsgInfo.Bytes.bPid = kNoPid;
  m.uMsgInfo.Bytes.bType = type;
  m.abData[0] = data0;
  m.abData[1] = data1;
  return m;
}

void LinLine::info(uint8_t what) {
  broadcast(event_message(LIN_MSGTYPE_INFO, 0, what, 0));  // stop and reset: time 0
}

void LinLine::broadcast(LINMSG msg) {
  for (Monitor& m : monitors_) {
    if (!m.active || m.port == nullptr) {
      continue;
    }
    const std::size_t room = m.port->room();
    if (room == 0) {
      ++m.state.lost;
      m.state.rx_overrun = true;
      continue;
    }
    LINMSG copy = msg;
    // ovr: the FIFO is full with this message.
    copy.uMsgInfo.Bits.ovr = room == 1 ? 1 : 0;
    m.port->put(copy);
    ++m.state.received;
  }
}

void LinLine::on_lin(const lin::Event& e, bool own_response) {
  const uint32_t time = ticks(e.at);
  switch (e.kind) {
    case lin::Event::Kind::frame: {
      ++(own_response || e.sender == controller_.node() ? stats_.frames_sent
                                                        : stats_.frames_received);
      LINMSG m{};
      m.dwTime = time;
      m.uMsgInfo.Bytes.bPid = e.id;
      m.uMsgInfo.Bytes.bType = LIN_MSGTYPE_DATA;
      m.uMsgInfo.Bytes.bDlen = e.response.size;
      m.uMsgInfo.Bits.ecs = e.response.checksum == lin::Checksum::enhanced ? 1 : 0;
      m.uMsgInfo.Bits.sor = own_response ? 1 : 0;
      std::copy(e.response.data.begin(), e.response.data.begin() + e.response.size, m.abData);
      broadcast(m);
      return;
    }
    case lin::Event::Kind::error:
      ++stats_.errors;
      if (op_mode_ & LIN_OPMODE_ERRORS) {
        broadcast(event_message(LIN_MSGTYPE_ERROR, time, vci_error(e.error), status_byte()));
      }
      return;
    case lin::Event::Kind::wakeup:
      broadcast(event_message(LIN_MSGTYPE_WAKEUP, time, 0, 0));
      return;
    case lin::Event::Kind::sleep:
      return;  // the go-to-sleep command came as the data frame 3Ch
  }
}

void LinLine::schedule_time_overrun() {
  const uint128 count = static_cast<uint128>(time_overruns_ + 1) << 32;
  const SimTime at =
      epoch_ + SimDuration(ticks_to_ns(count, clocks_.tsc_divisor, clocks_.clock_hz));
  overrun_event_ = scheduler_.schedule_at(at, *this, kTimeOverrun);
}

void LinLine::on_event(SimTime now, uint64_t tag) {
  if (tag != kTimeOverrun) {
    return;
  }
  ++time_overruns_;
  if (controller_.online()) {
    LINMSG m = event_message(LIN_MSGTYPE_TMOVR, ticks(now), 0, 0);
    m.uMsgInfo.Bytes.bDlen = 1;  // one overrun since the last message
    broadcast(m);
  }
  schedule_time_overrun();
}

}  // namespace canemu::model::ixxat
