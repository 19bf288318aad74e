// The IXXAT VCI firmware for one CAN controller of an adapter (VCI C++ guide 5.2): the
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
// The parts with a life of their own are classes of their own, which CanLine drives:
// Distributor (the channels, distribution to them and taking from their FIFOs), CyclicList,
// BitrateDetector, and line_settings()/capabilities() (line_init.hpp). CanLine keeps the
// control unit's state machine, its filters, the transmit path to the controller (staging,
// delays, what the controller holds) and the time stamps and event messages.
//
// Every decision where the manuals are silent is listed in docs/vci.md.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/firmware_model/adapters/ixxat/bitrate_detector.hpp"
#include "canemu/firmware_model/adapters/ixxat/clocks.hpp"
#include "canemu/firmware_model/adapters/ixxat/cyclic_list.hpp"
#include "canemu/firmware_model/adapters/ixxat/distributor.hpp"
#include "canemu/firmware_model/adapters/ixxat/filter.hpp"
#include "canemu/firmware_model/adapters/ixxat/line_init.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"
#include "vci/cantype.h"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

enum class LineState : uint8_t { not_initialized, offline, online };

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

class CanLine final : private ControllerEvents, private EventHandler, private CyclicList::Line {
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
  CANCAPABILITIES capabilities() const {
    return ixxat::capabilities(fd_controller(), low_speed_, clocks_);
  }
  CANCAPABILITIES2 capabilities2() const {
    return ixxat::capabilities2(fd_controller(), low_speed_, clocks_);
  }

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

  // --- CAN_OPMODE_AUTOBAUD ---
  // A line initialized with it listens from StartLine (listen-only, CAN_STATUS_ININIT, the
  // timing fields of its status zero) with each rate of autobaud_candidates() in turn, until a
  // frame decodes; from then on it runs with that rate, in its own modes. See docs/vci.md.
  bool autobaud_rate_known() const { return !autobaud_pending_; }

  // --- bit-rate detection (DetectBaud) ---
  // Listens (listen-only) with each entry's timing in turn until a frame decodes: an entry that
  // sees bus errors gives way at once, one that sees nothing for `per_entry` too. Only while
  // the line is not online; afterwards the line is not initialized. VCI_E_INVALID_STATE
  // online, VCI_E_BUSY while a detection runs, VCI_E_INVALIDARG for an empty table or an entry
  // the controller cannot run. Meanwhile init and start return VCI_E_BUSY; reset cancels it.
  HRESULT start_detection(const std::vector<LineInit>& entries, SimDuration per_entry);
  using Detection = BitrateDetector::Result;
  Detection detection() const { return detector_.result(); }

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
  // The list itself: cyclic_list.hpp.
  HRESULT scheduler_resume() { return cyclic_.resume(); }
  HRESULT scheduler_suspend() {
    cyclic_.suspend();
    return VCI_OK;
  }
  HRESULT scheduler_reset() {
    cyclic_.reset();
    return VCI_OK;
  }
  tl::expected<uint32_t, HRESULT> scheduler_add(const CANCYCLICTXMSG2& msg) {
    return cyclic_.add(msg);
  }
  HRESULT scheduler_remove(uint32_t index) { return cyclic_.remove(index); }
  HRESULT scheduler_start(uint32_t index, uint16_t count) { return cyclic_.start(index, count); }
  HRESULT scheduler_stop(uint32_t index) { return cyclic_.stop(index); }
  CANSCHEDULERSTATUS scheduler_status() const { return cyclic_.status(); }

  // Device ticks (time stamp counter) at `t`, wrapped to 32 bits.
  uint32_t ticks(SimTime t) const;

 private:
  // Where the frame in the controller came from.
  struct Loaded {
    CANMSG2 msg{};
    std::optional<ChannelId> channel;  // nothing: the cyclic list
  };
  // A message taken from a FIFO and the frame made of it then, under the line's modes then
  // (made again if they changed before it is loaded; nothing: to be made).
  struct Staged : Loaded {
    std::optional<TxFrame> frame;
    uint8_t op_mode = 0;
    uint8_t ex_mode = 0;
  };
  enum Tag : uint64_t { kTimeOverrun = 1, kDelay = 2 };

  bool in_use() const;
  void release_if_unused();
  void send_info(uint8_t info, uint32_t time);
  void update_status(SimTime at);
  uint8_t bus_load() const;
  // The frames the firmware took from a FIFO but did not finish: kept for the next start
  // (`keep`), or dropped and counted. A frame on the wire completes either way.
  void release_loaded(bool keep);
  void count_dropped(const Loaded& l);
  void reset_filters();

  // The hosted node's source: the next frame for the controller.
  std::optional<TxFrame> next_tx();
  // Puts `l` among the loaded frames and returns its frame: `frame`, or made now if empty
  // (nothing, counted as dropped, if it cannot be made).
  std::optional<TxFrame> load(const Loaded& l, std::optional<TxFrame>& frame);
  std::optional<TxFrame> to_frame(const CANMSG2& msg) const;

  // A detection ended: the line is not initialized (DetectBaud), or runs with the rate found
  // (CAN_OPMODE_AUTOBAUD).
  void detection_ended();
  // CAN_OPMODE_AUTOBAUD: the line was started and its rate is not known yet.
  void start_autobaud();
  bool autobaud_listening() const { return autobaud_detecting_; }
  void schedule_time_overrun();

  // --- CyclicList::Line ---
  bool online() const override { return state_ == LineState::online; }
  void frame_due() override { node_.kick(); }

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
  LineTimings shown_;        // v2: the timings the line status shows (shown_timings())
  HostedNodeSettings settings_;
  bool control_open_ = false;
  FilterPair filters_;
  bool controller_overrun_ = false;  // CAN_STATUS_OVRRUN
  bool low_speed_ = false;
  bool bus_coupling_error_ = false;  // CAN_STATUS_BUSCERR
  uint32_t reported_status_ = 0;     // status bits last sent in a STATUS message
  ErrorState error_state_ = ErrorState::active;

  Distributor distributor_;

  // The frames handed to the controller and not yet done, oldest first: one in an SJA1000's or
  // the FD controller's transmit buffer; up to the node's window on another daemon's bus. A
  // vector, as they are a few: it keeps its room (a deque allocated a block every few frames).
  std::vector<Loaded> loaded_;
  std::optional<Staged> staged_;  // taken from a FIFO, waiting for its delay or a restart
  SimTime staged_not_before_;
  SimTime last_load_;
  bool loaded_once_ = false;
  EventId delay_event_ = 0;

  BitrateDetector detector_;
  // CAN_OPMODE_AUTOBAUD (docs/vci.md): the rate is still to be found (from InitLine until the
  // detector decodes a frame), and the detector runs for it (only while online).
  bool autobaud_pending_ = false;
  bool autobaud_detecting_ = false;
  std::vector<LineInit> autobaud_table_;

  EventId overrun_event_ = 0;
  uint64_t time_overruns_ = 0;

  bool scheduler_open_ = false;
  CyclicList cyclic_;
  uint64_t cyclic_rejected_ = 0;  // list frames the line's modes did not allow
};

}  // namespace canemu::model::ixxat
