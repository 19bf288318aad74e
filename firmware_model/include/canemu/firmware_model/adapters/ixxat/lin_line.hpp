// The LIN side of an IXXAT adapter's firmware (VCI C++ guide 5.3, 7.7, 8.4; decisions in
// docs/lin.md): the control unit's InitLine / ResetLine / StartLine / StopLine / WriteMessage
// and line status on a LIN controller (chips/lin), and the message monitors that receive
// LINMSGs: data frames, errors with LIN_OPMODE_ERRORS, info messages at start, stop and reset,
// time stamp overruns.
//
// bPid carries the 6-bit identifier both ways (0..63; the guide asks for "an ID in the range 0
// to 63" and names the field a protected identifier: canemu keeps the parity bits on the wire
// only). A wake-up pulse from another node reaches the monitors as LIN_MSGTYPE_WAKEUP.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/firmware_model/adapters/ixxat/clocks.hpp"
#include "canemu/firmware_model/chips/lin/lin_controller.hpp"
#include "vci/lintype.h"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

// A monitor's receive FIFO as the firmware sees it.
class LinMonitorPort {
 public:
  virtual ~LinMonitorPort() = default;
  // Free places left.
  virtual std::size_t room() const = 0;
  virtual void put(const LINMSG& msg) = 0;
};

using MonitorId = uint32_t;

// What the controller did while online, for status displays.
struct LinLineStats {
  uint64_t frames_sent = 0;      // frames it sent the header or the response of
  uint64_t frames_received = 0;  // frames of other nodes
  uint64_t errors = 0;           // errors it saw (reported or not)
};

struct LinMonitorState {
  bool initialized = false;
  bool activated = false;
  bool rx_overrun = false;  // sticky until the monitor is initialized again
  uint64_t received = 0;
  uint64_t lost = 0;
};

class LinLine final : private lin::LinController::Listener, private EventHandler {
 public:
  // Features of the emulated controller (LINCAPABILITIES.dwFeatures).
  static constexpr uint32_t kFeatures = LIN_FEATURE_MASTER | LIN_FEATURE_AUTORATE |
                                        LIN_FEATURE_ERRFRAME | LIN_FEATURE_BUSLOAD |
                                        LIN_FEATURE_SLEEP | LIN_FEATURE_WAKEUP;

  // Time stamps count from `epoch` (the adapter's power-on) with `clocks`' time stamp counter.
  LinLine(SimScheduler& scheduler, lin::LinBus& bus, const Clocks& clocks, SimTime epoch);
  ~LinLine();
  LinLine(const LinLine&) = delete;
  LinLine& operator=(const LinLine&) = delete;

  // --- the control unit ---
  // One application at a time: VCI_E_ACCESSDENIED while another holds it. When the last
  // control unit or monitor closes, the controller is reset (a started controller keeps
  // running while monitors are open).
  HRESULT open_control();
  void close_control();
  HRESULT init_line(const LININITLINE& init);
  HRESULT reset_line();
  HRESULT start_line();
  HRESULT stop_line();
  HRESULT write_message(bool send, const LINMSG& msg);
  LINLINESTATUS line_status() const;
  LINCAPABILITIES capabilities() const;
  bool online() const { return controller_.online(); }

  // --- message monitors ---
  // VCI_E_ACCESSDENIED next to an exclusive monitor, or for an exclusive one next to others.
  tl::expected<MonitorId, HRESULT> open_monitor(bool exclusive);
  void close_monitor(MonitorId id);
  bool has_monitors() const { return !monitors_.empty(); }
  // The monitor's FIFO is `port` (not owned); overrun cleared. Only while inactive.
  HRESULT init_monitor(MonitorId id, LinMonitorPort* port);
  HRESULT activate(MonitorId id);
  HRESULT deactivate(MonitorId id);
  std::optional<LinMonitorState> monitor_state(MonitorId id) const;

  lin::LinController& controller() { return controller_; }
  const lin::LinController& controller() const { return controller_; }
  uint32_t ticks(SimTime t) const;
  SimTime epoch() const { return epoch_; }
  const LinLineStats& stats() const { return stats_; }

 private:
  struct Monitor {
    MonitorId id = 0;
    bool initialized = false;
    bool active = false;
    LinMonitorPort* port = nullptr;
    LinMonitorState state;
  };
  enum Tag : uint64_t { kTimeOverrun = 1 };

  void on_lin(const lin::Event& e, bool own_response) override;
  void on_event(SimTime now, uint64_t tag) override;
  void broadcast(LINMSG msg);
  void info(uint8_t what);
  LINMSG event_message(uint8_t type, uint32_t time, uint8_t data0, uint8_t data1) const;
  uint8_t status_byte() const;
  Monitor* find(MonitorId id);
  const Monitor* find(MonitorId id) const;
  void schedule_time_overrun();
  void release_if_unused();

  SimScheduler& scheduler_;
  lin::LinController controller_;
  Clocks clocks_;
  SimTime epoch_;
  bool initialized_ = false;
  uint8_t op_mode_ = LIN_OPMODE_SLAVE;
  uint16_t bitrate_ = LIN_BITRATE_UNDEF;
  std::vector<Monitor> monitors_;
  MonitorId next_monitor_ = 1;
  bool exclusive_ = false;
  bool control_open_ = false;
  uint64_t time_overruns_ = 0;
  std::optional<EventId> overrun_event_;
  LinLineStats stats_;
};

}  // namespace canemu::model::ixxat
