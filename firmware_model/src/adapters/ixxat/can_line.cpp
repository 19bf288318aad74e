#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model::ixxat {

namespace {

constexpr int64_t kNsPerSecond = 1'000'000'000;
// 128-bit intermediate products: tick counts times clock rates overflow 64 bits.
__extension__ typedef unsigned __int128 Wide;
constexpr uint32_t kReportedStatus =
    CAN_STATUS_OVRRUN | CAN_STATUS_ERRLIM | CAN_STATUS_BUSOFF | CAN_STATUS_BUSCERR;
constexpr uint16_t kWarningLimit = 96;
constexpr uint8_t kKnownOpModes =
    CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME | CAN_OPMODE_LISTONLY;

// The SJA1000 seen through CANBTP: the prescaler counts periods of half the 16 MHz oscillator.
constexpr BtpRange kSja1000Range{
    8'000'000, {kBtModeRaw, 1, 1, 1, 1, 0}, {kBtModeRaw, 64, 16, 8, 4, 0}};

// Nanoseconds from a clock's zero to its tick `count` (a clock of `clock_hz` divided by
// `divisor`), rounded up: the first instant at which the counter shows `count`.
int64_t ticks_to_ns(Wide count, uint32_t divisor, uint32_t clock_hz) {
  const Wide num = count * divisor * kNsPerSecond;
  return static_cast<int64_t>((num + clock_hz - 1) / clock_hz);
}

uint64_t ns_to_ticks(int64_t ns, uint32_t divisor, uint32_t clock_hz) {
  if (ns <= 0) {
    return 0;
  }
  const Wide num = static_cast<Wide>(ns) * clock_hz;
  return static_cast<uint64_t>(num / (static_cast<Wide>(divisor) * kNsPerSecond));
}

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

uint8_t error_code(CanErrorType t) {
  switch (t) {
    case CanErrorType::bit:
      return CAN_ERROR_BIT;
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

Btp to_btp(const CANBTP& b) {
  return Btp{b.dwMode, b.dwBPS, b.wTS1, b.wTS2, b.wSJW, b.wTDO};
}

// The raw CANBTP of SJA1000 bus timing registers.
// The raw CANBTP of an SJA1000 timing: the prescaler counts the chip's 8 MHz CAN clock (half the
// oscillator), so BRP + 1.
CANBTP btp_of_btr(uint8_t btr0, uint8_t btr1) {
  const BitTiming t = sja1000::timing_from_btr(btr0, btr1);
  CANBTP b{};
  b.dwMode = CAN_BTMODE_RAW | (t.samples == 3 ? CAN_BTMODE_TSM : 0);
  b.dwBPS = t.prescaler / 2;
  b.wTS1 = static_cast<UINT16>(t.tseg1);
  b.wTS2 = static_cast<UINT16>(t.tseg2);
  b.wSJW = static_cast<UINT16>(t.sjw);
  return b;
}

uint32_t payload_length(const CANMSG2& m) {
  const auto& b = m.uMsgInfo.Bits;
  return static_cast<uint32_t>(dlc_to_length(static_cast<uint8_t>(b.dlc), b.edl || b.fdr));
}

}  // namespace

CanLine::CanLine(SimScheduler& scheduler, HostedNode& node, const Clocks& clocks, SimTime epoch)
    : scheduler_(scheduler),
      node_(node),
      clocks_(clocks),
      epoch_(epoch),
      filters_{IdFilter(false, kStdListCapacity, CAN_FILTER_INCL),
               IdFilter(true, CAN_FILTER_SIZE_EXT, CAN_FILTER_INCL)} {
  node_.claim(true);
  schedule_time_overrun();
}

CanLine::~CanLine() {
  for (EventId e : {overrun_event_, delay_event_, cyclic_event_, detect_event_}) {
    if (e != 0) {
      scheduler_.cancel(e);
    }
  }
  node_.stop();
  node_.claim(false);
}

// ---------------------------------------------------------------- capabilities and status

namespace {
uint32_t features(bool fd) {
  uint32_t f = CAN_FEATURE_STDANDEXT | CAN_FEATURE_RMTFRAME | CAN_FEATURE_ERRFRAME |
               CAN_FEATURE_BUSLOAD | CAN_FEATURE_IDFILTER | CAN_FEATURE_LISTONLY |
               CAN_FEATURE_SCHEDULER | CAN_FEATURE_DELAYEDTX | CAN_FEATURE_SINGLESHOT |
               CAN_FEATURE_HIGHPRIOR;
  if (fd) {
    f |= CAN_FEATURE_EXTDATA | CAN_FEATURE_FASTDATA | CAN_FEATURE_ISOFRAME;
  }
  return f;
}

CANBTP to_canbtp(const Btp& b) {
  CANBTP c{};
  c.dwMode = b.mode;
  c.dwBPS = b.bps;
  c.wTS1 = b.ts1;
  c.wTS2 = b.ts2;
  c.wSJW = b.sjw;
  c.wTDO = b.tdo;
  return c;
}
}  // namespace

CANCAPABILITIES CanLine::capabilities() const {
  CANCAPABILITIES c{};
  c.wCtrlType = fd_controller() ? CAN_CTRL_IFICFD : CAN_CTRL_SJA1000;
  c.wBusCoupling = low_speed_ ? CAN_BUSC_LOWSPEED : CAN_BUSC_HIGHSPEED;
  c.dwFeatures = features(fd_controller());
  c.dwClockFreq = clocks_.clock_hz;
  c.dwTscDivisor = clocks_.tsc_divisor;
  c.dwCmsDivisor = clocks_.cms_divisor;
  c.dwCmsMaxTicks = clocks_.cms_max_ticks;
  c.dwDtxDivisor = clocks_.dtx_divisor;
  c.dwDtxMaxTicks = clocks_.dtx_max_ticks;
  return c;
}

CANCAPABILITIES2 CanLine::capabilities2() const {
  CANCAPABILITIES2 c{};
  const bool fd = fd_controller();
  c.wCtrlType = fd ? CAN_CTRL_IFICFD : CAN_CTRL_SJA1000;
  c.wBusCoupling = low_speed_ ? CAN_BUSC_LOWSPEED : CAN_BUSC_HIGHSPEED;
  c.dwFeatures = features(fd);
  const BtpRange& nominal = fd ? kFdNominalRange : kSja1000Range;
  c.dwCanClkFreq = nominal.clock_hz;
  c.sSdrRangeMin = to_canbtp(nominal.min);
  c.sSdrRangeMax = to_canbtp(nominal.max);
  if (fd) {
    c.sFdrRangeMin = to_canbtp(kFdDataRange.min);
    c.sFdrRangeMax = to_canbtp(kFdDataRange.max);
  }
  c.dwTscClkFreq = clocks_.clock_hz;
  c.dwTscDivisor = clocks_.tsc_divisor;
  c.dwCmsClkFreq = clocks_.clock_hz;
  c.dwCmsDivisor = clocks_.cms_divisor;
  c.dwCmsMaxTicks = clocks_.cms_max_ticks;
  c.dwDtxClkFreq = clocks_.clock_hz;
  c.dwDtxDivisor = clocks_.dtx_divisor;
  c.dwDtxMaxTicks = clocks_.dtx_max_ticks;
  return c;
}

uint32_t CanLine::ticks(SimTime t) const {
  return static_cast<uint32_t>(
      ns_to_ticks((t - epoch_).ns(), clocks_.tsc_divisor, clocks_.clock_hz));
}

uint32_t CanLine::status_flags() const {
  uint32_t s = 0;
  if (loaded_) {
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
  if (state_ != LineState::online) {
    s |= CAN_STATUS_ININIT;
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
    s.bBtReg0 = settings_.btr0;
    s.bBtReg1 = settings_.btr1;
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
    if (init_.v2) {
      s.sBtpSdr = init_.sdr;
      s.sBtpFdr = init_.fdr;
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
  return control_open_ || !channels_.empty() || scheduler_open_;
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
  if (detecting_) {
    finish_detection(VCI_E_ABORT, 0);
  }
  node_.stop();
  loaded_.reset();
  staged_.reset();
  cyclic_pending_.reset();
  state_ = LineState::not_initialized;
  configured_ = false;
  init_ = LineInit{};
  controller_overrun_ = false;
  error_state_ = ErrorState::active;
  reported_status_ = bus_coupling_error_ ? CAN_STATUS_BUSCERR : 0;  // the transceiver's own
  reset_filters();
  stop_task();
  for (CyclicEntry& e : cyclic_) {
    e = CyclicEntry{};
  }
}

HostedNodeSettings CanLine::settings_for(const LineInit& init, HRESULT& hr) const {
  HostedNodeSettings s;
  hr = VCI_E_INVALIDARG;
  const uint8_t known_op = kKnownOpModes | (low_speed_ ? CAN_OPMODE_LOWSPEED : 0);
  if ((init.op_mode & ~known_op) != 0) {
    return s;  // hardware bit-rate detection is not emulated; low speed needs a low-speed bus
  }
  const bool fd = fd_controller();
  s.listen_only = (init.op_mode & CAN_OPMODE_LISTONLY) != 0;
  if (!init.v2) {
    s.btr0 = init.btr0;
    s.btr1 = init.btr1;
    if (fd) {
      auto t = sja1000::decode_btr(init.btr0, init.btr1);
      if (!t) {
        return s;
      }
      s.nominal = *t;
      s.data = *t;
    }
    s.fd = false;
    hr = VCI_OK;
    return s;
  }
  if (!valid_filter_mode(init.sf_mode) || !valid_filter_mode(init.ef_mode)) {
    return s;
  }
  const uint8_t known_ex = fd ? (CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA) : 0;
  if ((init.ex_mode & ~known_ex) != 0) {
    return s;  // FD modes on a classic controller; non-ISO frames are not emulated
  }
  const BtpRange& range = fd ? kFdNominalRange : kSja1000Range;
  auto nominal = decode_btp(to_btp(init.sdr), range, Phase::nominal);
  if (!nominal) {
    return s;
  }
  s.nominal = *nominal;
  s.data = *nominal;
  if (!fd) {
    auto raw = to_raw(to_btp(init.sdr), range, Phase::nominal);
    if (!raw) {
      return s;
    }
    s.btr0 = static_cast<uint8_t>(((raw->sjw - 1) << 6) | (raw->bps - 1));
    s.btr1 = static_cast<uint8_t>(((raw->mode & kBtModeTsm) != 0 ? 0x80 : 0) |
                                  ((raw->ts2 - 1) << 4) | (raw->ts1 - 1));
  }
  if ((init.ex_mode & CAN_EXMODE_FASTDATA) != 0) {
    auto data = decode_btp(to_btp(init.fdr), kFdDataRange, Phase::data);
    if (!data) {
      return s;
    }
    s.data = *data;
  }
  s.fd = (init.ex_mode & (CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA)) != 0;
  hr = VCI_OK;
  return s;
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

void CanLine::release_loaded(bool keep) {
  if (staged_ && !keep) {
    count_dropped(*staged_);
    staged_.reset();
  }
  if (loaded_ && !node_.frame_on_wire()) {
    if (keep && !staged_) {
      staged_ = loaded_;
      staged_not_before_ = scheduler_.now();
    } else {
      count_dropped(*loaded_);
    }
    loaded_.reset();
  }
  // A frame on the wire completes; its outcome reaches frame_transmitted() or
  // transmission_dropped() with loaded_ still set.
}

void CanLine::count_dropped(const Loaded& l) {
  if (l.channel) {
    if (Channel* c = find(*l.channel)) {
      ++c->counters.dropped;
    }
  }
}

HRESULT CanLine::init_line(const LineInit& init) {
  if (detecting_) {
    return VCI_E_BUSY;
  }
  HRESULT hr = VCI_OK;
  const HostedNodeSettings settings = settings_for(init, hr);
  if (hr != VCI_OK) {
    return hr;
  }
  release_loaded(false);
  init_ = init;
  settings_ = settings;
  configured_ = true;
  node_.configure(settings, this, [this] { return next_tx(); });
  state_ = LineState::offline;
  controller_overrun_ = false;
  error_state_ = ErrorState::active;
  reset_filters();
  update_status(scheduler_.now());
  return VCI_OK;
}

HRESULT CanLine::reset_line() {
  if (detecting_) {
    finish_detection(VCI_E_ABORT, 0);
  }
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
  if (detecting_) {
    return VCI_E_BUSY;
  }
  if (state_ == LineState::not_initialized) {
    return VCI_E_INVALID_STATE;
  }
  if (state_ == LineState::online) {
    return VCI_OK;
  }
  state_ = LineState::online;
  // The first frame after the start is not delayed (docs/vci.md, delayed transmission): no
  // frame has been handed to the controller since, not even one waiting for its delay.
  loaded_once_ = false;
  if (staged_) {
    staged_not_before_ = scheduler_.now();
  }
  send_info(CAN_INFO_START, ticks(scheduler_.now()));
  node_.go_online();
  update_status(scheduler_.now());
  return VCI_OK;
}

HRESULT CanLine::stop_line() {
  if (state_ != LineState::online) {
    return VCI_OK;
  }
  const bool loaded_not_started = loaded_ && !node_.frame_on_wire();
  release_loaded(true);
  node_.go_offline();
  if (loaded_not_started && staged_ && !loaded_ && node_.controller().pending_tx() != nullptr) {
    // The controller kept its request through reset mode (the SJA1000 in bus-off holds it and
    // sends it after recovery): the frame is still in the controller, it must not be loaded a
    // second time.
    loaded_ = staged_;
    staged_.reset();
  }
  state_ = LineState::offline;
  send_info(CAN_INFO_STOP, 0);
  update_status(scheduler_.now());
  return VCI_OK;
}

void CanLine::send_info(uint8_t info, uint32_t time) {
  CANMSG2 m = event_message(CAN_MSGTYPE_INFO, time, CAN_MSGID_INFO, 1);
  m.abData[0] = info;
  broadcast(m);
}

void CanLine::update_status(SimTime at) {
  const uint32_t now = status_flags() & kReportedStatus;
  if (now == reported_status_) {
    return;
  }
  reported_status_ = now;
  CANMSG2 m = event_message(CAN_MSGTYPE_STATUS, ticks(at), CAN_MSGID_STATUS, 1);
  m.abData[0] = static_cast<UINT8>(status_flags() & 0xFF);
  broadcast(m);
}

// ---------------------------------------------------------------- filters

FilterResult CanLine::filter(std::optional<ChannelId> channel, const FilterOp& op) {
  FilterPair* pair = &filters_;
  bool busy = state_ == LineState::online;
  if (channel) {
    Channel* c = find(*channel);
    if (c == nullptr) {
      return {VCI_E_INVALID_HANDLE, 0};
    }
    if (!c->v2) {
      return {VCI_E_NOT_IMPLEMENTED, 0};
    }
    if (!c->filters) {
      return {VCI_E_NOT_INITIALIZED, 0};
    }
    pair = &*c->filters;
    busy = c->active;
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

CanLine::Channel* CanLine::find(ChannelId id) {
  for (Channel& c : channels_) {
    if (c.id == id) {
      return &c;
    }
  }
  return nullptr;
}

const CanLine::Channel* CanLine::find(ChannelId id) const {
  return const_cast<CanLine*>(this)->find(id);
}

tl::expected<ChannelId, HRESULT> CanLine::open_channel(bool exclusive, bool v2) {
  if (exclusive_ || (exclusive && !channels_.empty())) {
    return tl::unexpected(VCI_E_ACCESSDENIED);
  }
  Channel c;
  c.id = next_channel_id_++;
  c.v2 = v2;
  channels_.push_back(std::move(c));
  exclusive_ = exclusive;
  return channels_.back().id;
}

void CanLine::close_channel(ChannelId id) {
  if (staged_ && staged_->channel == id) {
    staged_.reset();
  }
  std::erase_if(channels_, [id](const Channel& c) { return c.id == id; });
  if (channels_.empty()) {
    exclusive_ = false;
  }
  release_if_unused();
}

HRESULT CanLine::init_channel(ChannelId id, const ChannelSetup& setup, ChannelPort* port) {
  Channel* c = find(id);
  if (c == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  if (c->active) {
    return VCI_E_INVALID_STATE;
  }
  if (c->v2) {
    const uint8_t mode = setup.filter_mode & static_cast<uint8_t>(~CAN_FILTER_SRRA);
    if (!valid_filter_mode(mode)) {
      return VCI_E_INVALIDARG;
    }
    c->srra = (setup.filter_mode & CAN_FILTER_SRRA) != 0;
    c->filters.emplace(FilterPair{IdFilter(false, kStdListCapacity, mode),
                                  IdFilter(true, setup.ext_list_size, mode)});
  }
  if (staged_ && staged_->channel == id) {
    staged_.reset();  // it came from the FIFO that goes now
  }
  c->port = port;
  c->initialized = true;
  c->overrun = false;
  c->lost_pending = false;
  c->counters = ChannelCounters{};
  return VCI_OK;
}

HRESULT CanLine::activate(ChannelId id) {
  Channel* c = find(id);
  if (c == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  if (!c->initialized) {
    return VCI_E_NOT_INITIALIZED;
  }
  c->active = true;
  node_.kick();
  return VCI_OK;
}

HRESULT CanLine::deactivate(ChannelId id) {
  Channel* c = find(id);
  if (c == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  c->active = false;
  if (staged_ && staged_->channel == id) {
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
  return VCI_OK;
}

std::optional<ChannelStatus> CanLine::channel_status(ChannelId id) const {
  const Channel* c = find(id);
  if (c == nullptr) {
    return std::nullopt;
  }
  return ChannelStatus{c->initialized, c->active, c->overrun, c->counters};
}

void CanLine::tx_ready() {
  node_.kick();
}

void CanLine::deliver(Channel& c, CANMSG2 msg) {
  if (!c.active || c.port == nullptr) {
    return;
  }
  if (!c.v2 && msg.uMsgInfo.Bits.type == CAN_MSGTYPE_DATA && payload_length(msg) > 8) {
    ++c.counters.not_shown;  // a CANMSG has no room for it
    return;
  }
  if (c.lost_pending) {
    msg.uMsgInfo.Bits.ovr = 1;
  }
  if (c.port->put(msg)) {
    ++c.counters.received;
    c.lost_pending = false;
  } else {
    ++c.counters.lost;
    c.overrun = true;
    c.lost_pending = true;
  }
}

void CanLine::broadcast(const CANMSG2& msg) {
  for (Channel& c : channels_) {
    deliver(c, msg);
  }
}

// ---------------------------------------------------------------- transmission

std::optional<TxFrame> CanLine::to_frame(const CANMSG2& msg) const {
  const auto& b = msg.uMsgInfo.Bits;
  if (b.type != CAN_MSGTYPE_DATA) {
    return std::nullopt;
  }
  const bool ext = b.ext != 0;
  if ((init_.op_mode & (ext ? CAN_OPMODE_EXTENDED : CAN_OPMODE_STANDARD)) == 0) {
    return std::nullopt;
  }
  // fdr alone asks for an FD frame with a fast data phase (the guide's own example).
  const bool fd = b.edl != 0 || b.fdr != 0;
  if ((b.edl != 0 && (init_.ex_mode & CAN_EXMODE_EXTDATA) == 0) ||
      (b.fdr != 0 && (init_.ex_mode & CAN_EXMODE_FASTDATA) == 0)) {
    return std::nullopt;
  }
  FrameSpec spec;
  spec.id = msg.dwMsgId;
  spec.extended = ext;
  spec.remote = b.rtr != 0 && !fd;
  spec.fd = fd;
  spec.brs = b.fdr != 0;
  spec.dlc = static_cast<uint8_t>(b.dlc);
  if (!spec.remote) {
    spec.data = std::span<const uint8_t>(msg.abData, dlc_to_length(*spec.dlc, fd));
  }
  auto frame = Frame::create(spec);
  if (!frame) {
    return std::nullopt;
  }
  return TxFrame{*frame, b.ssm != 0, false};
}

std::optional<CanLine::Loaded> CanLine::take_from(Channel& c, bool hpm_only) {
  if (!c.active || c.port == nullptr) {
    return std::nullopt;
  }
  while (std::optional<CANMSG2> m = c.port->peek()) {
    if (!to_frame(*m)) {
      c.port->pop();
      ++c.counters.rejected;  // not a frame this line can send: dropped, counted
      continue;
    }
    if (hpm_only && m->uMsgInfo.Bits.hpm == 0) {
      return std::nullopt;
    }
    c.port->pop();
    return Loaded{*m, c.id};
  }
  return std::nullopt;
}

std::optional<CanLine::Loaded> CanLine::pick_from_channels() {
  const std::size_t n = channels_.size();
  for (bool hpm_only : {true, false}) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = (rr_next_ + k) % n;
      if (auto l = take_from(channels_[i], hpm_only)) {
        rr_next_ = (i + 1) % n;
        return l;
      }
    }
  }
  return std::nullopt;
}

std::optional<TxFrame> CanLine::load(Loaded l) {
  std::optional<TxFrame> tx = to_frame(l.msg);
  if (!tx) {
    count_dropped(l);  // the line's modes changed since the message was taken
    return std::nullopt;
  }
  loaded_ = std::move(l);
  last_load_ = scheduler_.now();
  loaded_once_ = true;
  return tx;
}

std::optional<TxFrame> CanLine::next_tx() {
  if (state_ != LineState::online) {
    return std::nullopt;
  }
  const SimTime now = scheduler_.now();
  if (cyclic_pending_) {
    Loaded l = *cyclic_pending_;
    cyclic_pending_.reset();
    if (auto tx = load(std::move(l))) {
      return tx;
    }
    ++cyclic_rejected_;
  }
  if (!staged_) {
    staged_ = pick_from_channels();
    if (!staged_) {
      return std::nullopt;
    }
    staged_not_before_ = now;
    const uint32_t delay = std::min(staged_->msg.dwTime, clocks_.dtx_max_ticks);
    if (delay > 0 && loaded_once_) {
      staged_not_before_ =
          last_load_ + SimDuration(ticks_to_ns(delay, clocks_.dtx_divisor, clocks_.clock_hz));
    }
  }
  if (now < staged_not_before_) {
    if (delay_event_ != 0) {
      scheduler_.cancel(delay_event_);
    }
    delay_event_ = scheduler_.schedule_at(staged_not_before_, *this, kDelay);
    return std::nullopt;
  }
  Loaded l = *staged_;
  staged_.reset();
  return load(std::move(l));
}

void CanLine::frame_received(SimTime at, const Frame& frame, bool own) {
  if (detecting_) {
    detecting_->found = true;  // this timing decodes the traffic
    next_detection_entry();
    return;
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
  for (Channel& c : channels_) {
    if (!c.active) {
      continue;
    }
    CANMSG2 copy = m;
    if (passes_channel_filter(c, frame, copy)) {
      deliver(c, copy);
    }
  }
}

bool CanLine::passes_channel_filter(const Channel& c, const Frame& frame, CANMSG2& msg) const {
  if (!c.filters) {
    return true;  // v1 channels have no filter of their own
  }
  const uint8_t a = c.filters->accept(frame.id(), frame.extended(), frame.remote());
  if (a == CAN_ACCEPT_REJECT) {
    return false;
  }
  if (c.filters->select(frame.extended()).mode() != CAN_FILTER_PASS) {
    msg.uMsgInfo.Bits.afc = a;  // the last stage that filters sets it
  }
  return true;
}

void CanLine::frame_transmitted(SimTime at, const Frame& frame) {
  if (!loaded_) {
    return;
  }
  const Loaded done = *loaded_;
  loaded_.reset();
  if (done.channel) {
    if (Channel* c = find(*done.channel)) {
      ++c->counters.sent;
    }
  }
  if (done.msg.uMsgInfo.Bits.srr == 0) {
    return;  // invisible to the other channels
  }
  // Self reception: the firmware hands the frame to the distributor again.
  CANMSG2 echo = data_message(frame, ticks(at));
  echo.uMsgInfo.Bits.srr = 1;
  for (Channel& c : channels_) {
    if (!c.active) {
      continue;
    }
    if (!c.v2 || (done.channel && c.id == *done.channel)) {
      deliver(c, echo);
      continue;
    }
    if (!c.srra) {
      continue;
    }
    // Another channel's frame: as if it came from another controller, through the channel's
    // filter, srr cleared. The cyclic list's frames are no channel's but the line's own: they
    // keep srr, so that a program can tell them from the bus's traffic.
    CANMSG2 copy = echo;
    copy.uMsgInfo.Bits.srr = done.channel ? 0 : 1;
    if (passes_channel_filter(c, frame, copy)) {
      deliver(c, copy);
    }
  }
}

void CanLine::transmission_dropped(SimTime, const Frame&) {
  if (loaded_) {
    count_dropped(*loaded_);
    loaded_.reset();
  }
}

void CanLine::bus_error(const BusErrorEvent& event) {
  if (detecting_) {
    next_detection_entry();  // this timing does not decode the traffic
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
  m.abData[0] = error_code(event.type);
  m.abData[1] = static_cast<UINT8>(status & 0xFF);
  // Beyond the dlc, a canemu addition the manuals are silent on: the counters after the error
  // (REC, TEC; 255 stands for more), from which a program can tell the error-passive limit.
  m.abData[3] = static_cast<UINT8>(std::min<uint16_t>(event.rec, 255));
  m.abData[4] = static_cast<UINT8>(std::min<uint16_t>(event.tec, 255));
  broadcast(m);
}

void CanLine::state_changed(SimTime at, ErrorState state, uint16_t, uint16_t) {
  if (detecting_) {
    return;
  }
  error_state_ = state;
  update_status(at);
}

void CanLine::overrun(SimTime at, const Frame&) {
  controller_overrun_ = true;
  update_status(at);
}

// ---------------------------------------------------------------- bit-rate detection

HRESULT CanLine::start_detection(const std::vector<LineInit>& entries, SimDuration per_entry) {
  if (detecting_) {
    return VCI_E_BUSY;
  }
  if (state_ == LineState::online) {
    return VCI_E_INVALID_STATE;
  }
  if (entries.empty() || per_entry.ns() <= 0) {
    return VCI_E_INVALIDARG;
  }
  Detecting d;
  d.per_entry = per_entry;
  for (const LineInit& e : entries) {
    HRESULT hr = VCI_OK;
    HostedNodeSettings s = settings_for(e, hr);
    if (hr != VCI_OK) {
      return hr;
    }
    s.listen_only = true;  // the detector never disturbs the traffic it listens to
    d.settings.push_back(s);
  }
  release_loaded(false);
  detecting_ = std::move(d);
  detection_ = Detection{VCI_E_PENDING, 0};
  state_ = LineState::not_initialized;
  configured_ = false;
  try_detection_entry(0);
  return VCI_OK;
}

void CanLine::try_detection_entry(std::size_t i) {
  if (i >= detecting_->settings.size()) {
    finish_detection(VCI_E_TIMEOUT, 0);
    return;
  }
  detecting_->current = i;
  detecting_->moving_on = false;
  node_.configure(detecting_->settings[i], this, [] { return std::optional<TxFrame>(); });
  node_.go_online();
  if (detect_event_ != 0) {
    scheduler_.cancel(detect_event_);
  }
  detect_event_ =
      scheduler_.schedule_at(scheduler_.now() + detecting_->per_entry, *this, kDetectNext);
}

void CanLine::next_detection_entry() {
  if (detecting_->moving_on) {
    return;
  }
  // Not from inside the bus's callbacks: the next entry (or the end) comes in an event of its
  // own, at this instant.
  detecting_->moving_on = true;
  if (detect_event_ != 0) {
    scheduler_.cancel(detect_event_);
  }
  detect_event_ = scheduler_.schedule_at(scheduler_.now(), *this, kDetectNext);
}

void CanLine::finish_detection(HRESULT hr, uint32_t index) {
  if (detect_event_ != 0) {
    scheduler_.cancel(detect_event_);
    detect_event_ = 0;
  }
  detecting_.reset();
  detection_ = Detection{hr, index};
  node_.go_offline();
  state_ = LineState::not_initialized;
  configured_ = false;
  error_state_ = ErrorState::active;
}

// ---------------------------------------------------------------- time stamps

void CanLine::schedule_time_overrun() {
  const Wide count = static_cast<Wide>(time_overruns_ + 1) << 32;
  const SimTime at =
      epoch_ + SimDuration(ticks_to_ns(count, clocks_.tsc_divisor, clocks_.clock_hz));
  overrun_event_ = scheduler_.schedule_at(at, *this, kTimeOverrun);
}

void CanLine::on_event(SimTime now, uint64_t tag) {
  switch (tag) {
    case kTimeOverrun:
      ++time_overruns_;
      broadcast(event_message(CAN_MSGTYPE_TIMEOVR, ticks(now), 1, 0));
      schedule_time_overrun();
      break;
    case kDelay:
      delay_event_ = 0;
      node_.kick();
      break;
    case kCyclicTick:
      cyclic_event_ = 0;
      cyclic_tick();
      break;
    case kDetectNext:
      detect_event_ = 0;
      if (detecting_ && detecting_->found) {
        finish_detection(VCI_OK, static_cast<uint32_t>(detecting_->current));
      } else if (detecting_) {
        try_detection_entry(detecting_->current + 1);
      }
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
  stop_task();  // the task is off after the list is opened
  return VCI_OK;
}

void CanLine::close_scheduler() {
  scheduler_open_ = false;
  release_if_unused();
}

void CanLine::stop_task() {
  task_running_ = false;
  if (cyclic_event_ != 0) {
    scheduler_.cancel(cyclic_event_);
    cyclic_event_ = 0;
  }
}

HRESULT CanLine::scheduler_resume() {
  if (task_running_) {
    return VCI_OK;
  }
  task_running_ = true;
  task_epoch_ = scheduler_.now();
  last_tick_ = 0;
  for (CyclicEntry& e : cyclic_) {
    if (e.started) {
      e.due = e.msg.wCycleTime;
    }
  }
  schedule_cyclic();
  return VCI_OK;
}

HRESULT CanLine::scheduler_suspend() {
  stop_task();
  return VCI_OK;
}

HRESULT CanLine::scheduler_reset() {
  stop_task();
  for (CyclicEntry& e : cyclic_) {
    e = CyclicEntry{};
  }
  return VCI_OK;
}

tl::expected<uint32_t, HRESULT> CanLine::scheduler_add(const CANCYCLICTXMSG2& msg) {
  if (msg.wCycleTime == 0 || msg.wCycleTime > clocks_.cms_max_ticks ||
      msg.uMsgInfo.Bits.type != CAN_MSGTYPE_DATA) {
    return tl::unexpected(VCI_E_INVALIDARG);
  }
  const bool fd = msg.uMsgInfo.Bits.edl != 0 || msg.uMsgInfo.Bits.fdr != 0;
  const uint32_t length =
      msg.uMsgInfo.Bits.rtr != 0 && !fd
          ? 0
          : static_cast<uint32_t>(dlc_to_length(static_cast<uint8_t>(msg.uMsgInfo.Bits.dlc), fd));
  const uint32_t max_id = msg.uMsgInfo.Bits.ext != 0 ? kMaxExtendedId : kMaxStandardId;
  if (msg.dwMsgId > max_id) {
    return tl::unexpected(VCI_E_INVALIDARG);
  }
  switch (msg.bIncrMode) {
    case CAN_CTXMSG_INC_NO:
    case CAN_CTXMSG_INC_ID:
      break;
    case CAN_CTXMSG_INC_8:
      if (msg.bByteIndex >= length) {
        return tl::unexpected(VCI_E_INVALIDARG);
      }
      break;
    case CAN_CTXMSG_INC_16:
      if (msg.bByteIndex + 1U >= length) {
        return tl::unexpected(VCI_E_INVALIDARG);
      }
      break;
    default:
      return tl::unexpected(VCI_E_INVALIDARG);
  }
  for (uint32_t i = 0; i < cyclic_.size(); ++i) {
    if (cyclic_[i].status == CAN_CTXMSG_STAT_EMPTY) {
      cyclic_[i] = CyclicEntry{};
      cyclic_[i].status = CAN_CTXMSG_STAT_DONE;
      cyclic_[i].msg = msg;
      cyclic_[i].order = ++cyclic_order_;
      return i;
    }
  }
  return tl::unexpected(VCI_E_OUTOFMEMORY);
}

HRESULT CanLine::scheduler_remove(uint32_t index) {
  if (index >= cyclic_.size() || cyclic_[index].status == CAN_CTXMSG_STAT_EMPTY) {
    return VCI_E_INVALID_INDEX;
  }
  cyclic_[index] = CyclicEntry{};
  schedule_cyclic();
  return VCI_OK;
}

HRESULT CanLine::scheduler_start(uint32_t index, uint16_t count) {
  if (index >= cyclic_.size() || cyclic_[index].status == CAN_CTXMSG_STAT_EMPTY) {
    return VCI_E_INVALID_INDEX;
  }
  CyclicEntry& e = cyclic_[index];
  e.started = true;
  e.status = CAN_CTXMSG_STAT_BUSY;
  e.endless = count == 0;
  e.remaining = count;
  if (task_running_) {
    e.due = cyclic_tick_now() + e.msg.wCycleTime;
    schedule_cyclic();
  }
  return VCI_OK;
}

HRESULT CanLine::scheduler_stop(uint32_t index) {
  if (index >= cyclic_.size() || cyclic_[index].status == CAN_CTXMSG_STAT_EMPTY) {
    return VCI_E_INVALID_INDEX;
  }
  cyclic_[index].started = false;
  cyclic_[index].status = CAN_CTXMSG_STAT_DONE;
  schedule_cyclic();
  return VCI_OK;
}

CANSCHEDULERSTATUS CanLine::scheduler_status() const {
  CANSCHEDULERSTATUS s{};
  s.bTaskStat = task_running_ ? CAN_CTXTSK_STAT_RUNNING : CAN_CTXTSK_STAT_STOPPED;
  for (std::size_t i = 0; i < cyclic_.size(); ++i) {
    s.abMsgStat[i] = cyclic_[i].status;
  }
  return s;
}

uint64_t CanLine::cyclic_tick_now() const {
  return ns_to_ticks((scheduler_.now() - task_epoch_).ns(), clocks_.cms_divisor, clocks_.clock_hz);
}

SimTime CanLine::cyclic_tick_time(uint64_t tick) const {
  return task_epoch_ + SimDuration(ticks_to_ns(tick, clocks_.cms_divisor, clocks_.clock_hz));
}

void CanLine::schedule_cyclic() {
  if (cyclic_event_ != 0) {
    scheduler_.cancel(cyclic_event_);
    cyclic_event_ = 0;
  }
  if (!task_running_) {
    return;
  }
  std::optional<uint64_t> next;
  for (const CyclicEntry& e : cyclic_) {
    if (e.started && (!next || e.due < *next)) {
      next = e.due;
    }
  }
  if (!next) {
    return;
  }
  next_tick_ = std::max(*next, last_tick_ + 1);
  cyclic_event_ = scheduler_.schedule_at(cyclic_tick_time(next_tick_), *this, kCyclicTick);
}

namespace {
void increment(CANCYCLICTXMSG2& m) {
  switch (m.bIncrMode) {
    case CAN_CTXMSG_INC_ID: {
      const uint32_t wrap = m.uMsgInfo.Bits.ext != 0 ? (kMaxExtendedId + 1) : (kMaxStandardId + 1);
      m.dwMsgId = (m.dwMsgId + 1) % wrap;
      break;
    }
    case CAN_CTXMSG_INC_8:
      ++m.abData[m.bByteIndex];
      break;
    case CAN_CTXMSG_INC_16: {
      const uint16_t v =
          static_cast<uint16_t>(m.abData[m.bByteIndex] | (m.abData[m.bByteIndex + 1] << 8)) + 1;
      m.abData[m.bByteIndex] = static_cast<UINT8>(v & 0xFF);
      m.abData[m.bByteIndex + 1] = static_cast<UINT8>(v >> 8);
      break;
    }
    default:
      break;
  }
}
}  // namespace

void CanLine::cyclic_tick() {
  const uint64_t tick = next_tick_;
  last_tick_ = tick;
  if (state_ != LineState::online) {
    // The list keeps its rhythm but sends nothing while the line is not online.
    for (CyclicEntry& e : cyclic_) {
      while (e.started && e.due <= tick) {
        e.due += e.msg.wCycleTime;
      }
    }
  } else if (!cyclic_pending_) {
    // One frame per tick: the entry due longest, the older one on a tie. The others wait for
    // the next free tick; their rhythm stays.
    CyclicEntry* pick = nullptr;
    for (CyclicEntry& e : cyclic_) {
      if (e.started && e.due <= tick &&
          (pick == nullptr || e.due < pick->due || (e.due == pick->due && e.order < pick->order))) {
        pick = &e;
      }
    }
    if (pick != nullptr) {
      CANMSG2 m{};
      m.dwMsgId = pick->msg.dwMsgId;
      m.uMsgInfo = pick->msg.uMsgInfo;
      std::memcpy(m.abData, pick->msg.abData, sizeof(m.abData));
      cyclic_pending_ = Loaded{m, std::nullopt};
      increment(pick->msg);
      pick->due += pick->msg.wCycleTime;
      if (!pick->endless && --pick->remaining == 0) {
        pick->started = false;
        pick->status = CAN_CTXMSG_STAT_DONE;
      }
      node_.kick();
    }
  }
  schedule_cyclic();
}

}  // namespace canemu::model::ixxat
