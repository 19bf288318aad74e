// canemud's one logging facade. A line is "<N>canemud: MESSAGE" on stderr, N the sd-daemon(3)
// priority prefix (3 error .. 7 debug) that journald takes as the line's syslog priority under
// systemd; on a terminal the prefix shows as it is. A line about something that happened at a
// simulated instant carries that instant after its topic:
//
//   log::info(log::At{"fault", SimTime::from_ns(96'000)}, "scenario \"{}\" cleared", "noisy");
//   -> "<6>canemud: fault: t=0.000096000 s: scenario \"noisy\" cleared"
//
// Per-frame events are counted and traced, never logged (the model logs nothing; the daemon
// decides what is worth a line).
//
// Thread: canemud logs from its event loop's thread only. The sink and the level are
// process-wide state, so that every part of the daemon logs alike without a logger handed
// through every constructor; tests replace the sink with a log::Capture.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "canemu/firmware_model/sim/sim_time.hpp"

namespace canemu::daemon::log {

// The syslog priorities canemud uses, with their values (sd-daemon prefixes).
enum class Level : uint8_t { error = 3, warning = 4, notice = 5, info = 6, debug = 7 };

// "<3>" for Level::error, and so on.
std::string_view prefix(Level level);

// The topic and simulated instant of a line: "TOPIC: t=SECONDS s: " with nine decimals (ns).
struct At {
  std::string_view topic;
  model::SimTime time;
};
std::string stamp(const At& at);

// The whole line for `message`, without the newline: "<N>canemud: MESSAGE".
std::string format_line(Level level, std::string_view message);

// Writes `message` at `level` (one write of the whole line), unless the level is filtered.
void write(Level level, std::string_view message);
void write(Level level, const At& at, std::string_view message);

// Lines less important than `level` are dropped from now on (default: none are).
// canemud --check-config keeps warnings and errors only.
void set_max_level(Level level);

template <class... Args>
void error(fmt::format_string<Args...> f, Args&&... args) {
  write(Level::error, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void warning(fmt::format_string<Args...> f, Args&&... args) {
  write(Level::warning, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void notice(fmt::format_string<Args...> f, Args&&... args) {
  write(Level::notice, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void info(fmt::format_string<Args...> f, Args&&... args) {
  write(Level::info, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void info(const At& at, fmt::format_string<Args...> f, Args&&... args) {
  write(Level::info, at, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void debug(fmt::format_string<Args...> f, Args&&... args) {
  write(Level::debug, fmt::format(f, std::forward<Args>(args)...));
}

// For tests: while it lives, lines go into lines() (whole, without the newline) instead of
// stderr. Captures do not nest.
class Capture {
 public:
  Capture();
  ~Capture();
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;
  const std::vector<std::string>& lines() const { return lines_; }

 private:
  std::vector<std::string> lines_;
};

}  // namespace canemu::daemon::log
