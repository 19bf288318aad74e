// The cyclic transmit list of a VCI controller (ICanScheduler, VCI C++ guide 5.2.5, 7.6.7-7.6.8;
// decisions in docs/vci.md): 16 entries, each sent every wCycleTime ticks of the list's clock
// (Clocks::cms_divisor) while the task runs, endlessly or a given number of times, with
// auto-increment of the identifier or of an 8- or 16-bit data field after each frame.
//
// One frame per tick: of the entries due, the one due longest goes, the older on a tie; the
// others wait for the next free tick and keep their rhythm. The list hands its frame to the
// line, which gives it to the controller before any channel's; while the frame waits there, no
// tick picks another. While the line is not online the list keeps its rhythm and sends nothing.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include <tl/expected.hpp>

#include "canemu/firmware_model/adapters/ixxat/clocks.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"
#include "vci/cantype.h"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

class CyclicList final : private EventHandler {
 public:
  // What the list sees of its line.
  class Line {
   public:
    // Frames go out only while the line is online.
    virtual bool online() const = 0;
    // take() has a frame for the controller.
    virtual void frame_due() = 0;

   protected:
    ~Line() = default;
  };

  // The task is stopped and every entry empty. `line` must outlive the list.
  CyclicList(SimScheduler& scheduler, const Clocks& clocks, Line& line);
  ~CyclicList();
  CyclicList(const CyclicList&) = delete;
  CyclicList& operator=(const CyclicList&) = delete;

  // --- ICanScheduler ---
  // Starts the task: every started entry is due one cycle from now. VCI_OK when it runs.
  HRESULT resume();
  // Stops the task; the entries keep their state.
  void suspend();
  // Stops the task and empties every entry.
  void reset();
  // The first empty entry gets `msg` (added, not started). VCI_E_INVALIDARG for a cycle of 0
  // or above cms_max_ticks, a message that is not data, an identifier out of range, an unknown
  // increment mode or one whose byte(s) lie outside the data; VCI_E_OUTOFMEMORY when full or
  // when the entries' shares of the ticks, 1/wCycleTime each, would add up to more than 1.
  tl::expected<uint32_t, HRESULT> add(const CANCYCLICTXMSG2& msg);
  // VCI_E_INVALID_INDEX for an index out of range or an empty entry.
  HRESULT remove(uint32_t index);
  // Sends the entry `count` times (0: endlessly), the first one cycle from now if the task runs.
  HRESULT start(uint32_t index, uint16_t count);
  HRESULT stop(uint32_t index);
  CANSCHEDULERSTATUS status() const;
  bool running() const { return running_; }

  // The frame a tick picked, not yet taken by the line (only `dwMsgId`, `uMsgInfo` and
  // `abData` are set); the line takes it once.
  std::optional<CANMSG2> take();
  // Back to power-on: the task stopped, every entry empty, no frame waiting.
  void clear();

 private:
  struct Entry {
    uint8_t status = CAN_CTXMSG_STAT_EMPTY;
    bool started = false;
    CANCYCLICTXMSG2 msg{};
    uint32_t remaining = 0;  // repetitions left; 0 with `endless`
    bool endless = false;
    uint64_t due = 0;  // tick of the next transmission (while the task runs)
    uint64_t order = 0;
  };

  void on_event(SimTime now, uint64_t tag) override;
  bool valid(uint32_t index) const;
  uint64_t tick_now() const;
  SimTime tick_time(uint64_t tick) const;
  // The event for the next tick at which a started entry is due.
  void schedule();
  void tick();

  SimScheduler& scheduler_;
  const Clocks& clocks_;
  Line& line_;
  bool running_ = false;
  SimTime epoch_;  // the task's start: ticks count from here
  std::array<Entry, CAN_MAX_CTX_MSGS> entries_{};
  uint64_t order_ = 0;
  std::optional<CANMSG2> pending_;
  EventId event_ = 0;
  uint64_t last_tick_ = 0;  // ticks since the task's start
  uint64_t next_tick_ = 0;
};

}  // namespace canemu::model::ixxat
