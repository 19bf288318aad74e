// How InitLine programs a VCI line's controller, and what the line reports it can do
// (VCI C++ guide 5.2.3, 8.3.6-8.3.7; decisions in docs/vci.md). Pure functions of the request,
// the controller (SJA1000 or the CAN FD controller), the bus coupling and the clocks.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/adapters/ixxat/clocks.hpp"
#include "canemu/firmware_model/adapters/ixxat/filter.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "vci/cantype.h"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

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

// The SJA1000 seen through CANBTP: the prescaler counts periods of half the 16 MHz oscillator.
inline constexpr BtpRange kSja1000BtpRange{
    8'000'000, {kBtModeRaw, 1, 1, 1, 1, 0}, {kBtModeRaw, 64, 16, 8, 4, 0}};

// The controller settings `init` asks for, on the CAN FD controller (`fd_controller`) or an
// SJA1000, wired to a low-speed bus or not. VCI_E_INVALIDARG for a mode the line does not have
// (low speed on a high-speed bus, FD modes on a classic controller, non-ISO frames, bit-rate
// detection with a fast data phase), an invalid filter mode or a timing the controller cannot
// run. v2 timings on an SJA1000 also give its BTR0/BTR1. With CAN_OPMODE_AUTOBAUD the timing
// fields are ignored: the settings are those of the first of autobaud_candidates().
tl::expected<HostedNodeSettings, HRESULT> line_settings(const LineInit& init, bool fd_controller,
                                                        bool low_speed);

// What CANLINESTATUS2 shows for a v2 `init` that line_settings() took: the timing the
// controller runs, in the form the request used. A bit/s CANBTP shows what convert_btp() made
// of it (its `shown` form: the same numbers as the request when the clock makes it exactly);
// a raw one is shown as given, and so is sBtpFdr without CAN_EXMODE_FASTDATA.
struct LineTimings {
  CANBTP sdr{};
  CANBTP fdr{};
};
LineTimings shown_timings(const LineInit& init, bool fd_controller);

// For a v2 `init` that line_settings() took: one line (describe_conversion()) for each bit/s
// CANBTP the controller could not take as it was (another rate, number of quanta, SJW or TDO).
std::vector<std::string> timing_conversions(const LineInit& init, bool fd_controller);

// Why line_settings() refuses the timing of a v2 `init` (the first phase it cannot run), or
// nothing when the timings are not what it refuses.
std::optional<std::string> timing_error(const LineInit& init, bool fd_controller);

// What CAN_OPMODE_AUTOBAUD tries, in order: `init` without AUTOBAUD, with the timing of
// 1000, 800, 500, 250, 125, 100, 50, 20 and 10 kbit/s (BTR0/BTR1 for a v1 init, CANBTP for v2).
std::vector<LineInit> autobaud_candidates(const LineInit& init, bool fd_controller);

// The raw CANBTP of SJA1000 bus timing registers (what CANLINESTATUS2 shows for a v1 init).
CANBTP btp_of_btr(uint8_t btr0, uint8_t btr1);

CANCAPABILITIES capabilities(bool fd_controller, bool low_speed, const Clocks& clocks);
CANCAPABILITIES2 capabilities2(bool fd_controller, bool low_speed, const Clocks& clocks);

}  // namespace canemu::model::ixxat
