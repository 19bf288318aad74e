// Bit-rate detection (ICanControl::DetectBaud, VCI C++ guide 7.6.3; decisions in
// docs/vci.md): the controller listens, listen-only, with each candidate timing in turn until a
// frame decodes. An entry that sees a bus error gives way at once (its timing does not decode
// the traffic), one that sees nothing for the time given too. Then the controller is off the
// bus, its node configured with the last entry tried.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

class BitrateDetector final : private EventHandler {
 public:
  struct Result {
    HRESULT hr = VCI_E_INVALID_STATE;  // VCI_E_PENDING while it runs, then VCI_OK,
                                       // VCI_E_TIMEOUT or VCI_E_ABORT (cancelled)
    uint32_t index = 0;                // VCI_OK: the entry that decoded a frame
  };

  // The node's events go to `events` while the detector listens (its owner, which passes
  // frames and bus errors on to frame_received() and bus_error()). `finished` is called at the
  // end of every detection, whichever way it ended. `node` must outlive the detector.
  BitrateDetector(SimScheduler& scheduler, HostedNode& node, ControllerEvents& events,
                  std::function<void()> finished);
  ~BitrateDetector();
  BitrateDetector(const BitrateDetector&) = delete;
  BitrateDetector& operator=(const BitrateDetector&) = delete;

  // Listens with `entries[0]` from now (each entry made listen-only), `per_entry` at most each.
  // The caller checks that there is an entry, that `per_entry` is positive and that no
  // detection runs.
  void start(std::vector<HostedNodeSettings> entries, SimDuration per_entry);
  // CAN_OPMODE_AUTOBAUD: as start(), but an entry listens as long as the bus is silent (only a
  // bus error moves it on), and after the last entry the first comes again: it ends only with
  // a frame decoded, or cancel().
  void start_endless(std::vector<HostedNodeSettings> entries);
  bool running() const { return running_.has_value(); }
  // Ends a running detection with VCI_E_ABORT.
  void cancel();
  Result result() const { return result_; }

  // What the node reported while running: a frame decoded with the current entry (which
  // ends the detection), or a bus error (the next entry is tried).
  void frame_received();
  void bus_error();

 private:
  struct Running {
    std::vector<HostedNodeSettings> entries;
    SimDuration per_entry;  // zero: endless (no time limit, wraps around)
    std::size_t current = 0;
    bool moving_on = false;  // the next entry (or the end) is scheduled
    bool found = false;      // the current entry received a frame
  };

  void on_event(SimTime now, uint64_t tag) override;
  void try_entry(std::size_t i);
  void next_entry();
  void finish(HRESULT hr, uint32_t index);

  SimScheduler& scheduler_;
  HostedNode& node_;
  ControllerEvents& events_;
  std::function<void()> finished_;
  std::optional<Running> running_;
  Result result_;
  EventId event_ = 0;
};

}  // namespace canemu::model::ixxat
