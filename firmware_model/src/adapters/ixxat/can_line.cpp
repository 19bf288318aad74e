#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <tuple>

namespace canemu::model::ixxat {

namespace {

constexpr uint32_t kReportedStatus =
    CAN_STATUS_OVRRUN | CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF | CAN_STATUS_BUSCERR;
constexpr uint16_t kWarningLimit = 96;

CANMSG2 event_message(uint8_t type, uint32_t time, uint32_t id, uint8_t dlc) {
  CANMSG2 m{};
  m.dwTime = time;
  m.dwMsgId = id;
  m.uMsgInfo.Bits.type = type;
  m.uMsgInfo.Bits.dlc = dlc & 0x0FU;
  m.uMsgInfo.Bits.afc = CAN_ACCEPT_ALWAYS;
  return m;
}

CANMSG2 data_message(const Frame& frame, uint32_t time) {
  CANMSG2 m{};
  m.dwTime = time;
  m.dwMsgId = frame.id();
  m.uMsgInfo.Bits.type = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = frame.dlc() & 0x0FU;
  m.uMsgInfo.Bits.ext = frame.extended() ? 1 : 0;
  m.uMsgInfo.Bits.rtr = frame.remote() ? 1 : 0;
  m.uMsgInfo.Bits.edl = frame.fd() ? 1 : 0;
  m.uMsgInfo.Bits.fdr = frame.brs() ? 1 : 0;
  m.uMsgInfo.Bits.esi = frame.esi() ? 1 : 0;
  m.uMsgInfo.Bits.afc = CAN_ACCEPT_ALWAYS;
  const auto data = frame.data();
  std::memcpy(m.abData, data.data(), data.size());
  return m;
}

uint8_t error_code(const BusErrorEvent& e) {
  switch (e.type) {
    case CanErrorType::bit:
      // A bit error at the data bit rate of an FD frame (docs/vci.md): the fast data bit error.
      return e.data_phase ? CAN_ERROR_FDB : CAN_ERROR_BIT;
    case CanErrorType::stuff:
      return CAN_ERROR_STUFF;
    case CanErrorType::form:
      return CAN_ERROR_FORM;
    case CanErrorType::crc:
      return CAN_ERROR_CRC;
    case CanErrorType::ack:
      return CAN_ERROR_ACK;
  }
  return CAN_ERROR_OTHER;
}

}  // namespace

CanLine::CanLine(SimScheduler& scheduler, HostedNode& node, const Clocks& clocks, SimTime epoch)
    : scheduler_(scheduler),
      node_(node),
      clocks_(clocks),
      epoch_(epoch),
      filters_{IdFilter(false, kStdListCapacity, CAN_FILTER_INCL),
               IdFilter(true, CAN_FILTER_SIZE_EXT, CAN_FILTER_INCL)},
      detector_(scheduler, node, *this, [this] { detection_ended(); }),
      cyclic_(scheduler, clocks_, *this) {
  node_.claim(true);
  schedule_time_overrun();
}

CanLine::~CanLine() {
  for (EventId e : {overrun_event_, delay_event_}) {
    if (e != 0) {
      scheduler_.cancel(e);
    }
  }
  node_.stop();
  node_.claim(false);
}

// ---------------------------------------------------------------- status

uint32_t CanLine::ticks(SimTime t) const {
  return static_cast<uint32_t>(
      ns_to_ticks((t - epoch_).ns(), clocks_.tsc_divisor, clocks_.clock_hz));
}

uint32_t CanLine::status_flags() const {
  uint32_t s = 0;
  if (!loaded_.empty()) {
    s |= CAN_STATUS_TXPEND;
  }
  if (controller_overrun_) {
    s |= CAN_STATUS_OVRRUN;
  }
  if (error_state_ != ErrorState::active) {
    s |= CAN_STATUS_ERRLIM;
  }
  if (error_state_ == ErrorState::bus_off) {
    s |= CAN_STATUS_BUSOFF;
  }
  if (state_ != LineState::online || autobaud_detecting_) {
    s |= CAN_STATUS_ININIT;  // not online, or still looking for its rate (CAN_OPMODE_AUTOBAUD)
  }
  if (bus_coupling_error_) {
    s |= CAN_STATUS_BUSCERR;
  }
  return s;
}

void CanLine::set_bus_coupling_error(bool error) {
  bus_coupling_error_ = error;
  update_status(scheduler_.now());
}

CANLINESTATUS CanLine::line_status() const {
  CANLINESTATUS s{};
  if (state_ != LineState::not_initialized || configured_) {
    s.bOpMode = init_.op_mode;
    if (!autobaud_pending_) {
      s.bBtReg0 = settings_.btr0;
      s.bBtReg1 = settings_.btr1;
    }
  }
  s.bBusLoad = bus_load();
  s.dwStatus = status_flags();
  return s;
}

CANLINESTATUS2 CanLine::line_status2() const {
  CANLINESTATUS2 s{};
  if (state_ != LineState::not_initialized || configured_) {
    s.bOpMode = init_.op_mode;
    s.bExMode = init_.ex_mode;
    if (autobaud_pending_) {
      // No rate yet: the timing fields stay zero.
    } else if (init_.v2) {
      s.sBtpSdr = shown_.sdr;  // the timing taken (docs/vci.md, bit timing in bit/s form)
      s.sBtpFdr = shown_.fdr;
    } else if (!fd_controller()) {
      s.sBtpSdr = btp_of_btr(settings_.btr0, settings_.btr1);
    }
  }
  s.bBusLoad = bus_load();
  s.dwStatus = status_flags();
  return s;
}

uint8_t CanLine::bus_load() const {
  const double load = node_.bus().bus_load_percent(scheduler_.now());
  return static_cast<uint8_t>(std::clamp(std::lround(load), 0L, 100L));
}

ControllerState CanLine::controller_state() {
  FaultConfinement& fc = node_.controller().confinement();
  return {fc.state(), fc.tec(), fc.rec()};
}

// ---------------------------------------------------------------- control unit

bool CanLine::in_use() const {
  return control_open_ || !distributor_.empty() || scheduler_open_;
}

HRESULT CanLine::open_control() {
  if (control_open_) {
    return VCI_E_ACCESSDENIED;
  }
  control_open_ = true;
  return VCI_OK;
}

void CanLine::close_control() {
  control_open_ = false;
  release_if_unused();
}

void CanLine::release_if_unused() {
  if (in_use()) {
    return;
  }
  detector_.cancel();
  node_.stop();
  loaded_.clear();
  staged_.reset();
  state_ = LineState::not_initialized;
  configured_ = false;
  init_ = LineInit{};
  shown_ = LineTimings{};
  autobaud_pending_ = false;
  autobaud_table_.clear();
  controller_overrun_ = false;
  error_state_ = ErrorState::active;
  reported_status_ = bus_coupling_error_ ? CAN_STATUS_BUSCERR : 0;  // the transceiver's own
  reset_filters();
  cyclic_.clear();
}

void CanLine::reset_filters() {
  if (init_.v2) {
    filters_ = FilterPair{IdFilter(false, init_.sf_ids, init_.sf_mode, init_.sf_ids != 0),
                          IdFilter(true, init_.ef_ids, init_.ef_mode, init_.ef_ids != 0)};
  } else {
    filters_ = FilterPair{IdFilter(false, kStdListCapacity, CAN_FILTER_INCL),
                          IdFilter(true, CAN_FILTER_SIZE_EXT, CAN_FILTER_INCL)};
  }
}

HRESULT CanLine::init_line(const LineInit& init) {
  if (detector_.running() && !autobaud_detecting_) {
    return VCI_E_BUSY;  // DetectBaud runs
  }
  const auto settings = line_settings(init, fd_controller(), low_speed_);
  if (!settings) {
    return settings.error();
  }
  detector_.cancel();  // an online line still looking for its rate stops looking
  release_loaded(false);
  init_ = init;
  settings_ = *settings;
  shown_ = init.v2 ? shown_timings(init, fd_controller()) : LineTimings{};
  autobaud_pending_ = (init.op_mode & CAN_OPMODE_AUTOBAUD) != 0;
  autobaud_table_.clear();
  if (autobaud_pending_) {
    // The timing fields are ignored (and shown as zero until the rate is found).
    init_.btr0 = 0;
    init_.btr1 = 0;
    init_.sdr = CANBTP{};
    init_.fdr = CANBTP{};
    autobaud_table_ = autobaud_candidates(init, fd_controller());
  }
  configured_ = true;
  node_.configure(settings_, this, [this] { return next_tx(); });
  state_ = LineState::offline;
  controller_overrun_ = false;
  error_state_ = ErrorState::active;
  reset_filters();
  update_status(scheduler_.now());
  return VCI_OK;
}

HRESULT CanLine::reset_line() {
  detector_.cancel();
  release_loaded(false);
  if (configured_) {
    node_.configure(settings_, this, [this] { return next_tx(); });
  }
  state_ = LineState::not_initialized;
  controller_overrun_ = false;
  error_state_ = ErrorState::active;
  reset_filters();
  send_info(CAN_INFO_RESET, 0);
  update_status(scheduler_.now());
  return VCI_OK;
}

HRESULT CanLine::start_line() {
  if (state_ == LineState::online) {
    return VCI_OK;
  }
  if (detector_.running()) {
    return VCI_E_BUSY;
  }
  if (state_ == LineState::not_initialized) {
    return VCI_E_INVALID_STATE;
  }
  state_ = LineState::online;
  // The first frame after the start is not delayed (docs/vci.md, delayed transmission): no
  // frame has been handed to the controller since, not even one waiting for its delay.
  loaded_once_ = false;
  if (staged_) {
    staged_not_before_ = scheduler_.now();
  }
  send_info(CAN_INFO_START, ticks(scheduler_.now()));
  if (autobaud_pending_) {
    start_autobaud();
  } else {
    node_.go_online();
  }
  update_status(scheduler_.now());
  return VCI_OK;
}

void CanLine::start_autobaud() {
  std::vector<HostedNodeSettings> settings;
  for (const LineInit& c : autobaud_table_) {
    settings.push_back(*line_settings(c, fd_controller(), low_speed_));
  }
  autobaud_detecting_ = true;
  detector_.start_endless(std::move(settings));
}

HRESULT CanLine::stop_line() {
  if (state_ != LineState::online) {
    return VCI_OK;
  }
  detector_.cancel();  // still looking for its rate: it looks again from the next start
  // A frame in the controller that has not started is taken back (kept for the next start);
  // the controller's reset mode aborts its request, also one it held through bus-off.
  release_loaded(true);
  node_.go_offline();
  state_ = LineState::offline;
  send_info(CAN_INFO_STOP, 0);
  update_status(scheduler_.now());
  return VCI_OK;
}

void CanLine::send_info(uint8_t info, uint32_t time) {
  CANMSG2 m = event_message(CAN_MSGTYPE_INFO, time, CAN_MSGID_INFO, 1);
  m.abData[0] = info;
  distributor_.broadcast(m);
}

void CanLine::update_status(SimTime at) {
  const uint32_t now = status_flags() & kReportedStatus;
  if (now == reported_status_) {
    return;
  }
  reported_status_ = now;
  CANMSG2 m = event_message(CAN_MSGTYPE_STATUS, ticks(at), CAN_MSGID_STATUS, 1);
  m.abData[0] = static_cast<UINT8>(status_flags() & 0xFF);
  distributor_.broadcast(m);
}

// ---------------------------------------------------------------- filters

FilterResult CanLine::filter(std::optional<ChannelId> channel, const FilterOp& op) {
  FilterPair* pair = &filters_;
  bool busy = state_ == LineState::online;
  if (channel) {
    auto f = distributor_.filters(*channel);
    if (!f) {
      return {f.error(), 0};
    }
    std::tie(pair, busy) = *f;
  }
  if (op.select != CAN_FILTER_STD && op.select != CAN_FILTER_EXT) {
    return {VCI_E_INVALIDARG, 0};
  }
  IdFilter& f = pair->select(op.select == CAN_FILTER_EXT);
  if (op.kind == FilterOp::Kind::get_mode) {
    return {VCI_OK, f.mode()};
  }
  if (busy) {
    return {VCI_E_INVALID_STATE, 0};
  }
  switch (op.kind) {
    case FilterOp::Kind::set_mode: {
      const uint8_t previous = f.mode();
      return {f.set_mode(op.mode), previous};
    }
    case FilterOp::Kind::set_acceptance:
      f.set_acceptance(op.code, op.mask);
      return {VCI_OK, 0};
    case FilterOp::Kind::add_ids:
      return {f.add_ids(op.code, op.mask), 0};
    case FilterOp::Kind::remove_ids:
      return {f.remove_ids(op.code, op.mask), 0};
    case FilterOp::Kind::get_mode:
      break;
  }
  return {VCI_E_INVALIDARG, 0};
}

// ---------------------------------------------------------------- channels

tl::expected<ChannelId, HRESULT> CanLine::open_channel(bool exclusive, bool v2) {
  return distributor_.open(exclusive, v2);
}

void CanLine::close_channel(ChannelId id) {
  if (staged_ && staged_->channel == id) {
    staged_.reset();
  }
  distributor_.close(id);
  release_if_unused();
}

HRESULT CanLine::init_channel(ChannelId id, const ChannelSetup& setup, ChannelPort* port) {
  const HRESULT hr = distributor_.init(id, setup, port);
  if (hr == VCI_OK && staged_ && staged_->channel == id) {
    staged_.reset();  // it came from the FIFO that goes now
  }
  return hr;
}

HRESULT CanLine::activate(ChannelId id) {
  const HRESULT hr = distributor_.activate(id);
  if (hr == VCI_OK) {
    node_.kick();
  }
  return hr;
}

HRESULT CanLine::deactivate(ChannelId id) {
  const HRESULT hr = distributor_.deactivate(id);
  if (hr == VCI_OK && staged_ && staged_->channel == id) {
    // Taken from the FIFO but not yet handed to the controller (waiting for its delay): after
    // Deactivate the channel transmits nothing more (spec 3.8), so it is dropped and counted.
    count_dropped(*staged_);
    staged_.reset();
    if (delay_event_ != 0) {
      scheduler_.cancel(delay_event_);
      delay_event_ = 0;
    }
    node_.kick();  // another channel may send now
  }
  return hr;
}

std::optional<ChannelStatus> CanLine::channel_status(ChannelId id) const {
  return distributor_.status(id);
}

void CanLine::tx_ready() {
  node_.kick();
}

void CanLine::frame_received(SimTime at, const Frame& frame, bool own) {
  if (detector_.running()) {
    detector_.frame_received();
    if (!autobaud_detecting_) {
      return;
    }
    // CAN_OPMODE_AUTOBAUD: the frame that shows the rate was received whole with it, and is
    // delivered like every frame after it.
  }
  if (own || state_ != LineState::online) {
    return;
  }
  const bool ext = frame.extended();
  if ((init_.op_mode & (ext ? CAN_OPMODE_EXTENDED : CAN_OPMODE_STANDARD)) == 0) {
    return;
  }
  const uint8_t afc = filters_.accept(frame.id(), ext, frame.remote());
  if (afc == CAN_ACCEPT_REJECT) {
    return;  // invisible to every channel
  }
  CANMSG2 m = data_message(frame, ticks(at));
  m.uMsgInfo.Bits.afc = afc;
  distributor_.distribute(frame, m);
}

void CanLine::frame_transmitted(SimTime at, const Frame& frame) {
  if (loaded_.empty()) {
    return;
  }
  // Frames end in the order they were loaded (one transmit buffer, or the owner's queue of a
  // node on another daemon's bus).
  const std::optional<ChannelId> channel = loaded_.front().channel;
  const bool echoed = loaded_.front().msg.uMsgInfo.Bits.srr != 0;
  loaded_.erase(loaded_.begin());
  if (channel) {
    distributor_.count_sent(*channel);
  }
  if (!echoed) {
    return;  // invisible to the other channels
  }
  // Self reception: the firmware hands the frame to the distributor again.
  CANMSG2 echo = data_message(frame, ticks(at));
  echo.uMsgInfo.Bits.srr = 1;
  distributor_.echo(frame, echo, channel);
}

void CanLine::bus_error(const BusErrorEvent& event) {
  if (detector_.running()) {
    detector_.bus_error();
    return;
  }
  if ((init_.op_mode & CAN_OPMODE_ERRFRAME) == 0) {
    return;
  }
  uint32_t status = status_flags() & ~(CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF);
  if (event.tec >= kWarningLimit || event.rec >= kWarningLimit) {
    status |= CAN_STATUS_ERRLIM;
  }
  if (event.tec >= kBusOffLimit) {
    status |= CAN_STATUS_BUSOFF;
  }
  CANMSG2 m = event_message(CAN_MSGTYPE_ERROR, ticks(event.at), CAN_MSGID_ERROR, 2);
  m.abData[0] = error_code(event);
  m.abData[1] = static_cast<UINT8>(status & 0xFF);
  // Beyond the dlc, a canemu addition the manuals are silent on: the counters after the error
  // (REC, TEC; 255 stands for more), from which a program can tell the error-passive limit.
  m.abData[3] = static_cast<UINT8>(std::min<uint16_t>(event.rec, 255));
  m.abData[4] = static_cast<UINT8>(std::min<uint16_t>(event.tec, 255));
  distributor_.broadcast(m);
}

void CanLine::state_changed(SimTime at, ErrorState state, uint16_t, uint16_t) {
  if (detector_.running()) {
    return;
  }
  error_state_ = state;
  update_status(at);
}

void CanLine::overrun(SimTime at, const Frame&) {
  controller_overrun_ = true;
  update_status(at);
}

// ---------------------------------------------------------------- time stamps

void CanLine::schedule_time_overrun() {
  const uint128 count = static_cast<uint128>(time_overruns_ + 1) << 32;
  const SimTime at =
      epoch_ + SimDuration(ticks_to_ns(count, clocks_.tsc_divisor, clocks_.clock_hz));
  overrun_event_ = scheduler_.schedule_at(at, *this, kTimeOverrun);
}

void CanLine::on_event(SimTime now, uint64_t tag) {
  switch (tag) {
    case kTimeOverrun:
      ++time_overruns_;
      distributor_.broadcast(event_message(CAN_MSGTYPE_TIMEOVR, ticks(now), 1, 0));
      schedule_time_overrun();
      break;
    case kDelay:
      delay_event_ = 0;
      node_.kick();
      break;
    default:
      break;
  }
}

// ---------------------------------------------------------------- cyclic transmit list

HRESULT CanLine::open_scheduler() {
  if (scheduler_open_) {
    return VCI_E_ACCESSDENIED;
  }
  scheduler_open_ = true;
  cyclic_.suspend();  // the task is off after the list is opened
  return VCI_OK;
}

void CanLine::close_scheduler() {
  scheduler_open_ = false;
  release_if_unused();
}

}  // namespace canemu::model::ixxat
