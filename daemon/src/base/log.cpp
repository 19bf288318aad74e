#include "canemu/daemon/base/log.hpp"

#include <cstdio>

namespace canemu::daemon::log {

namespace {

// Process-wide, touched from the event loop's thread only (see log.hpp).
Level g_max_level = Level::debug;
std::vector<std::string>* g_capture = nullptr;

}  // namespace

std::string_view prefix(Level level) {
  switch (level) {
    case Level::error:
      return "<3>";
    case Level::warning:
      return "<4>";
    case Level::notice:
      return "<5>";
    case Level::info:
      return "<6>";
    case Level::debug:
      return "<7>";
  }
  return "<6>";
}

std::string stamp(const At& at) {
  // Whole seconds and nanoseconds as integers: exact at any simulated time.
  const int64_t ns = at.time.ns();
  return fmt::format("{}: t={}.{:09} s: ", at.topic, ns / 1'000'000'000, ns % 1'000'000'000);
}

std::string format_line(Level level, std::string_view message) {
  std::string line;
  line.reserve(message.size() + 16);
  line += prefix(level);
  line += "canemud: ";
  line += message;
  return line;
}

void write(Level level, std::string_view message) {
  if (static_cast<uint8_t>(level) > static_cast<uint8_t>(g_max_level)) {
    return;
  }
  std::string line = format_line(level, message);
  if (g_capture != nullptr) {
    g_capture->push_back(std::move(line));
    return;
  }
  line += '\n';
  std::fwrite(line.data(), 1, line.size(), stderr);  // stderr is unbuffered: one write
}

void write(Level level, const At& at, std::string_view message) {
  write(level, stamp(at) + std::string(message));
}

void set_max_level(Level level) {
  g_max_level = level;
}

Capture::Capture() {
  g_capture = &lines_;
}

Capture::~Capture() {
  g_capture = nullptr;
}

}  // namespace canemu::daemon::log
