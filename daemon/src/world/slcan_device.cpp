#include "canemu/daemon/world/slcan_device.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

#include <fmt/format.h>

#include "canemu/ipc/text_file.hpp"

namespace canemu::daemon {

using model::sorcus::EepromWords;
using model::sorcus::kEepromWords;

Result<EepromWords> load_eeprom_file(const std::string& path) {
  if (::access(path.c_str(), F_OK) != 0 && errno == ENOENT) {
    return model::sorcus::slcan_eeprom_defaults();
  }
  // 64 words of four digits, with comments: a few KiB at most.
  auto file = ipc::read_text_file(path, 64 * 1024);
  if (!file) {
    return fail(Errc::io, file.error());
  }
  std::istringstream in(*file);
  EepromWords words{};
  std::size_t n = 0;
  std::string text;
  for (unsigned line = 1; std::getline(in, text); ++line) {
    if (text.empty() || text[0] == '#') {
      continue;
    }
    unsigned value = 0;
    char extra = 0;
    if (text.size() != 4 || std::sscanf(text.c_str(), "%4x%c", &value, &extra) != 1) {
      return fail(Errc::bad_argument,
                  fmt::format("{}:{}: \"{}\" is not an EEPROM word (4 hex digits, one per line)",
                              path, line, text));
    }
    if (n == kEepromWords) {
      return fail(Errc::bad_argument,
                  fmt::format("{}:{}: more than {} EEPROM words", path, line, kEepromWords));
    }
    words[n++] = static_cast<uint16_t>(value);
  }
  if (n != kEepromWords) {
    return fail(Errc::bad_argument,
                fmt::format("{}: {} EEPROM words, but the SL-CANi has {}", path, n, kEepromWords));
  }
  return words;
}

Result<> save_eeprom_file(const std::string& path, const EepromWords& words) {
  std::string text = "# canemu SL-CANi EEPROM: words 0..63, one per line (hex)\n";
  for (uint16_t w : words) {
    text += fmt::format("{:04X}\n", w);
  }
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    return fail(Errc::io, fmt::format("open {}: {}", tmp, std::strerror(errno)));
  }
  const auto n = ::write(fd, text.data(), text.size());
  const bool ok = n == static_cast<ssize_t>(text.size()) && ::fsync(fd) == 0;
  const int err = errno;
  ::close(fd);
  if (!ok) {
    ::unlink(tmp.c_str());
    return fail(Errc::io, fmt::format("write {}: {}", tmp, std::strerror(err)));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return fail(Errc::io, fmt::format("rename {} to {}: {}", tmp, path, std::strerror(e)));
  }
  return {};
}

Result<> SlcanDevice::load() {
  if (state_file_.empty()) {
    return {};
  }
  auto words = load_eeprom_file(state_file_);
  if (!words) {
    return tl::unexpected(std::move(words.error()));
  }
  module_.load_eeprom(*words);
  return {};
}

Result<> SlcanDevice::write_eeprom(unsigned word, uint16_t value) {
  if (word >= kEepromWords) {
    return fail(Errc::bad_argument, fmt::format("word {} does not exist (0..63)", word));
  }
  if (!model::sorcus::slcan_eeprom_writable(word)) {
    return fail(Errc::bad_argument,
                fmt::format("word {} is read-only (writable: 13..19 and 32..63)", word));
  }
  EepromWords next = module_.eeprom();
  next[word] = value;
  if (!state_file_.empty()) {
    if (auto saved = save_eeprom_file(state_file_, next); !saved) {
      return saved;
    }
  }
  (void)module_.write_eeprom(word, value);
  return {};
}

}  // namespace canemu::daemon
