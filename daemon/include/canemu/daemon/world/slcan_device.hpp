// A configured SORCUS SL-CANi: the S-Link's model (driver task, 82527, EEPROM) on its bus, the
// EEPROM's state file, and the sink that takes its service routine calls and service requests
// to whoever holds its slot (SlcanService).
//
// The state file keeps the 64 EEPROM words across canemud restarts: a comment line, then one
// word per line in hex (4 digits), word 0 first. It is written whole to "PATH.tmp", flushed and
// renamed over PATH, so a crash leaves the old contents or the new ones, never a mix.
#pragma once

#include <functional>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/firmware_model/adapters/sorcus/slcan_module.hpp"

namespace canemu::daemon {

// The EEPROM words in `path`; the factory contents when it does not exist. An error names the
// file, the line and what is wrong.
Result<model::sorcus::EepromWords> load_eeprom_file(const std::string& path);
// Writes `words` to `path` atomically (temp file, fsync, rename); the error names the call.
Result<> save_eeprom_file(const std::string& path, const model::sorcus::EepromWords& words);

class SlcanDevice final : public model::sorcus::SlcanSink {
 public:
  // `state_file` "": not persisted.
  SlcanDevice(std::string name, model::SimScheduler& scheduler, uint8_t slot,
              std::string state_file)
      : name_(std::move(name)),
        state_file_(std::move(state_file)),
        module_(scheduler, slot, *this) {}
  SlcanDevice(const SlcanDevice&) = delete;
  SlcanDevice& operator=(const SlcanDevice&) = delete;
  ~SlcanDevice() = default;

  const std::string& name() const { return name_; }
  const std::string& state_file() const { return state_file_; }
  model::sorcus::SlcanModule& module() { return module_; }

  // Reads the state file into the EEPROM (at start-up).
  Result<> load();
  // A program's EEPROM write: refused for a read-only word ("word N is read-only"), persisted
  // before it counts (a failed save leaves the EEPROM as it was).
  Result<> write_eeprom(unsigned word, uint16_t value);

  std::function<void(const model::sorcus::SlcanServiceCall&)> on_service;
  std::function<void(model::SimTime, USHORT)> on_request;

  void service(const model::sorcus::SlcanServiceCall& c) override {
    if (on_service) {
      on_service(c);
    }
  }
  void service_request(model::SimTime at, USHORT word) override {
    if (on_request) {
      on_request(at, word);
    }
  }

 private:
  std::string name_;
  std::string state_file_;
  model::sorcus::SlcanModule module_;  // after the functions: it may call them once built
};

}  // namespace canemu::daemon
