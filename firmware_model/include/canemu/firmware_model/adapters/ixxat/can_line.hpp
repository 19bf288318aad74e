// The IXXAT VCI firmware for one CAN controller of an adapter (spec/vci-cpp-digest.md 3): the
// control unit (not initialized / offline / online, InitLine, ResetLine, StartLine, StopLine
// with their INFO messages, line status), the message filters of the control unit and of v2
// channels, the channels with the distributor between them, self reception, delayed, single
// shot and high-priority transmission, time stamps from the device clock with TIMEOVR
// messages, ERROR and STATUS messages, and the cyclic transmit list.
//
// The controller is a hosted node (an SJA1000 on classic adapters, the CAN FD controller on FD
// adapters) that this firmware drives as the vendor firmware drives the chip. Channel FIFOs are
// ChannelPorts: shared-memory rings in canemud, vectors in tests. The daemon enforces who may
// call what (the exclusive control unit and cyclic list); this class enforces the rules between
// calls (states, exclusive channels, filter changes only offline or inactive).
//
// Every decision where the manuals are silent is listed in docs/vci.md.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/firmware_model/adapters/ixxat/filter.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"
#include "vci/cantype.h"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

// The time bases of an emulated adapter, as its capabilities report them.
struct Clocks {
  uint32_t clock_hz = 1'000'000;  // dwClockFreq; also the v2 time stamp, list and delay clocks
  uint32_t tsc_divisor = 1;       // time stamps count microseconds
  uint32_t cms_divisor = 1000;    // the cyclic list's tick: 1 ms
  uint32_t cms_max_ticks = 0xFFFF;
  uint32_t dtx_divisor = 1;  // transmit delays count microseconds
  uint32_t dtx_max_ticks = 0xFFFF;
};

// A channel's FIFOs as the firmware sees them.
class ChannelPort {
 public:
  virtual ~ChannelPort() = default;
  // Stores a message in the receive FIFO; false when it is full (the message is then lost).
  virtual bool put(const CANMSG2& msg) = 0;
  // The message at the head of the transmit FIFO, left in place; nothing when it is empty or
  // the channel has no transmit FIFO.
  virtual std::optional<CANMSG2> peek() = 0;
  virtual void pop() = 0;
};

enum class LineState : uint8_t { not_initialized, offline, online };

// CANINITLINE (v2 false) or CANINITLINE2 (v2 true).
struct LineInit {
  bool v2 = false;
  uint8_t op_mode = CAN_OPMODE_STANDARD;
  uint8_t ex_mode = CAN_EXMODE_DISABLED;
  uint8_t sf_mode = CAN_FILTER_INCL;  // v2: default and reset mode of the 11-bit filter
  uint8_t ef_mode = CAN_FILTER_INCL;
  uint32_t sf_ids = kStdListCapacity;  // v2: 0 means no 11-bit filtering at all
  uint32_t ef_ids = CAN_FILTER_SIZE_EXT;
  uint8_t btr0 = 0;  // v1
  uint8_t btr1 = 0;
  CANBTP sdr{};  // v2
  CANBTP fdr{};
};

using ChannelId = uint32_t;

struct ChannelSetup {
  uint32_t ext_list_size = 0;             // v2: 29-bit ID list size (0: no list)
  uint8_t filter_mode = CAN_FILTER_PASS;  // v2: both filters' mode, optionally | CAN_FILTER_SRRA
};

struct ChannelCounters {
  uint64_t received = 0;   // messages stored in the receive FIFO
  uint64_t lost = 0;       // messages the receive FIFO had no room for
  uint64_t sent = 0;       // frames of this channel that went out
  uint64_t rejected = 0;   // transmit FIFO entries that were not frames the line can send
  uint64_t dropped = 0;    // single-shot frames given up
  uint64_t not_shown = 0;  // v1 channels: CAN FD frames with more than 8 bytes
};

struct ChannelStatus {
  bool initialized = false;
  bool activated = false;
  bool rx_overrun = false;  // sticky until the channel is initialized again
  ChannelCounters counters;
};

// A filter call on the control unit or a v2 channel.
struct FilterOp {
  enum class Kind : uint8_t { get_mode, set_mode, set_acceptance, add_ids, remove_ids };
  Kind kind = Kind::get_mode;
  uint8_t select = CAN_FILTER_STD;
  uint8_t mode = 0;  // set_mode
  uint32_t code = 0;
  uint32_t mask = 0;
};
struct FilterResult {
  HRESULT hr = VCI_OK;
  uint8_t mode = 0;  // get_mode: the mode; set_mode: the previous mode
};

// The canemu extension's view of the controller.
struct ControllerState {
  ErrorState state = ErrorState::active;
  uint16_t tec = 0;
  uint16_t rec = 0;
};

class CanLine final : private ControllerEvents, private EventHandler {
 public:
  // `node` must be stopped and stay with this line until it is destroyed. Time stamps count
  // from `epoch` (the adapter's power-on).
  CanLine(SimScheduler& scheduler, HostedNode& node, const Clocks& clocks, SimTime epoch);
  ~CanLine();
  CanLine(const CanLine&) = delete;
  CanLine& operator=(const CanLine&) = delete;

  bool fd_controller() const { return node_.fd_capable(); }
  // The adapter's power-on: its time stamps count from here.
  SimTime epoch() const { return epoch_; }
  const Clocks& clocks() const { return clocks_; }
  // The bus coupling: a low-speed, fault-tolerant transceiver (ISO 11898-3) instead of the
  // high-speed one. Set once, before use, from the bus the adapter is wired to.
  void set_low_speed(bool low_speed) { low_speed_ = low_speed; }
  bool low_speed() const { return low_speed_; }
  // The transceiver reports a wire fault (its error output): CAN_STATUS_BUSCERR while it lasts,
  // with a STATUS message when it changes. Reset and InitLine do not clear it.
  void set_bus_coupling_error(bool error);
  CANCAPABILITIES capabilities() const;
  CANCAPABILITIES2 capabilities2() const;

  // --- control unit ---
  // The control unit, the channels and the cyclic list keep the line in use; when the last of
  // them goes, the line is reset to not initialized (no INFO, nobody is left to see it).
  HRESULT open_control();
  void close_control();
  bool control_open() const { return control_open_; }
  HRESULT init_line(const LineInit& init);
  HRESULT reset_line();
  HRESULT start_line();
  HRESULT stop_line();
  LineState state() const { return state_; }
  CANLINESTATUS line_status() const;
  CANLINESTATUS2 line_status2() const;
  uint32_t status_flags() const;
  ControllerState controller_state();

  // --- bit-rate detection (DetectBaud) ---
  // Listens (listen-only) with each entry's timing in turn until a frame decodes: an entry that
  // sees bus errors gives way at once, one that sees nothing for `per_entry` too. Only while
  // the line is not online; afterwards the line is not initialized. VCI_E_INVALID_STATE
  // online, VCI_E_BUSY while a detection runs, VCI_E_INVALIDARG for an empty table or an entry
  // the controller cannot run. Meanwhile init and start return VCI_E_BUSY; reset cancels it.
  HRESULT start_detection(const std::vector<LineInit>& entries, SimDuration per_entry);
  struct Detection {
    HRESULT hr = VCI_E_INVALID_STATE;  // VCI_E_PENDING while it runs, then VCI_OK or
                                       // VCI_E_TIMEOUT (VCI_E_ABORT when cancelled)
    uint32_t index = 0;                // VCI_OK: the entry that decoded a frame
  };
  Detection detection() const { return detection_; }

  // --- channels ---
  tl::expected<ChannelId, HRESULT> open_channel(bool exclusive, bool v2);
  void close_channel(ChannelId id);
  // The channel's FIFOs are `port` (not owned; valid until the channel is closed or
  // initialized again). Only while inactive.
  HRESULT init_channel(ChannelId id, const ChannelSetup& setup, ChannelPort* port);
  HRESULT activate(ChannelId id);
  HRESULT deactivate(ChannelId id);
  std::optional<ChannelStatus> channel_status(ChannelId id) const;
  // The channel's transmit FIFO got messages: the line takes one if the controller is free.
  void tx_ready();
  // On the control unit (channel empty) or a v2 channel.
  FilterResult filter(std::optional<ChannelId> channel, const FilterOp& op);

  // --- cyclic transmit list ---
  HRESULT open_scheduler();
  void close_scheduler();
  bool scheduler_open() const { return scheduler_open_; }
  HRESULT scheduler_resume();
  HRESULT scheduler_suspend();
  HRESULT scheduler_reset();
  tl::expected<uint32_t, HRESULT> scheduler_add(const CANCYCLICTXMSG2& msg);
  HRESULT scheduler_remove(uint32_t index);
  HRESULT scheduler_start(uint32_t index, uint16_t count);
  HRESULT scheduler_stop(uint32_t index);
  CANSCHEDULERSTATUS scheduler_status() const;

  // Device ticks (time stamp counter) at `t`, wrapped to 32 bits.
  uint32_t ticks(SimTime t) const;

 private:
  struct Channel {
    ChannelId id = 0;
    bool v2 = false;
    bool open = false;
    bool initialized = false;
    bool active = false;
    bool srra = false;
    bool overrun = false;       // fRxOverrun
    bool lost_pending = false;  // the next stored message gets ovr
    ChannelPort* port = nullptr;
    std::optional<FilterPair> filters;  // v2
    ChannelCounters counters;
  };
  struct CyclicEntry {
    uint8_t status = CAN_CTXMSG_STAT_EMPTY;
    bool started = false;
    CANCYCLICTXMSG2 msg{};
    uint32_t remaining = 0;  // repetitions left; 0 with `endless`
    bool endless = false;
    uint64_t due = 0;  // tick of the next transmission (while the task runs)
    uint64_t order = 0;
  };
  // Where the frame in the controller came from.
  struct Loaded {
    CANMSG2 msg{};
    std::optional<ChannelId> channel;  // nothing: the cyclic list
  };
  enum Tag : uint64_t { kTimeOverrun = 1, kCyclicTick = 2, kDelay = 3, kDetectNext = 4 };

  bool in_use() const;
  void release_if_unused();
  Channel* find(ChannelId id);
  const Channel* find(ChannelId id) const;
  void deliver(Channel& c, CANMSG2 msg);
  // A v2 channel's own filter on a data frame: false when it blocks; sets afc unless the
  // filter passes everything.
  bool passes_channel_filter(const Channel& c, const Frame& frame, CANMSG2& msg) const;
  void broadcast(const CANMSG2& msg);  // to every active channel
  void send_info(uint8_t info, uint32_t time);
  void update_status(SimTime at);
  uint8_t bus_load() const;
  // The frames the firmware took from a FIFO but did not finish: kept for the next start
  // (`keep`), or dropped and counted. A frame on the wire completes either way.
  void release_loaded(bool keep);
  void count_dropped(const Loaded& l);
  void reset_filters();
  HostedNodeSettings settings_for(const LineInit& init, HRESULT& hr) const;

  // The hosted node's source: the next frame for the controller.
  std::optional<TxFrame> next_tx();
  std::optional<Loaded> pick_from_channels();
  std::optional<Loaded> take_from(Channel& c, bool hpm_only);
  std::optional<TxFrame> load(Loaded l);
  std::optional<TxFrame> to_frame(const CANMSG2& msg) const;

  void try_detection_entry(std::size_t i);
  void next_detection_entry();
  void finish_detection(HRESULT hr, uint32_t index);

  void schedule_time_overrun();
  void stop_task();
  uint64_t cyclic_tick_now() const;
  SimTime cyclic_tick_time(uint64_t tick) const;
  void schedule_cyclic();
  void cyclic_tick();

  void on_event(SimTime now, uint64_t tag) override;
  void frame_received(SimTime at, const Frame& frame, bool own) override;
  void frame_transmitted(SimTime at, const Frame& frame) override;
  void transmission_dropped(SimTime at, const Frame& frame) override;
  void bus_error(const BusErrorEvent& event) override;
  void state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) override;
  void overrun(SimTime at, const Frame& lost) override;

  SimScheduler& scheduler_;
  HostedNode& node_;
  Clocks clocks_;
  SimTime epoch_;

  LineState state_ = LineState::not_initialized;
  LineInit init_{};
  bool configured_ = false;  // init_line() succeeded since the line was last released
  HostedNodeSettings settings_;
  bool control_open_ = false;
  FilterPair filters_;
  bool controller_overrun_ = false;  // CAN_STATUS_OVRRUN
  bool low_speed_ = false;
  bool bus_coupling_error_ = false;  // CAN_STATUS_BUSCERR
  uint32_t reported_status_ = 0;     // status bits last sent in a STATUS message
  ErrorState error_state_ = ErrorState::active;

  std::vector<Channel> channels_;
  ChannelId next_channel_id_ = 1;
  bool exclusive_ = false;
  std::size_t rr_next_ = 0;  // the distributor's next channel

  std::optional<Loaded> loaded_;  // the frame in the controller's transmit buffer
  std::optional<Loaded> staged_;  // taken from a FIFO, waiting for its delay or a restart
  SimTime staged_not_before_;
  SimTime last_load_;
  bool loaded_once_ = false;
  EventId delay_event_ = 0;

  struct Detecting {
    std::vector<HostedNodeSettings> settings;
    SimDuration per_entry;
    std::size_t current = 0;
    bool moving_on = false;  // the next entry (or the end) is scheduled
    bool found = false;      // the current entry received a frame
  };
  std::optional<Detecting> detecting_;
  Detection detection_;
  EventId detect_event_ = 0;

  EventId overrun_event_ = 0;
  uint64_t time_overruns_ = 0;

  bool scheduler_open_ = false;
  bool task_running_ = false;
  SimTime task_epoch_;
  std::array<CyclicEntry, CAN_MAX_CTX_MSGS> cyclic_{};
  uint64_t cyclic_order_ = 0;
  std::optional<Loaded> cyclic_pending_;  // the list's frame waiting for the controller
  uint64_t cyclic_rejected_ = 0;          // list frames the line's modes did not allow
  EventId cyclic_event_ = 0;
  uint64_t last_tick_ = 0;  // ticks since the task's start
  uint64_t next_tick_ = 0;
};

}  // namespace canemu::model::ixxat
