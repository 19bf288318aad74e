// A configured SORCUS X-CAN-2i: the module firmware model on the buses of its two interfaces,
// and the sink that takes its callbacks and the ends of its blocking services to whoever serves
// its channels (XcanService).
#pragma once

#include <functional>
#include <string>

#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

namespace canemu::daemon {

class XcanDevice final : public model::sorcus::XcanSink {
 public:
  XcanDevice(std::string name, model::SimScheduler& scheduler, model::sorcus::XcanVariant variant)
      : name_(std::move(name)), module_(scheduler, variant, *this) {}
  XcanDevice(const XcanDevice&) = delete;
  XcanDevice& operator=(const XcanDevice&) = delete;
  ~XcanDevice() = default;

  const std::string& name() const { return name_; }
  model::sorcus::XcanModule& module() { return module_; }

  // Set by the service that answers the device's channels; nothing happens without them.
  std::function<void(const model::sorcus::XcanCallback&)> on_callback;
  std::function<void(const model::sorcus::XcanCompletion&)> on_completed;

  void callback(const model::sorcus::XcanCallback& c) override {
    if (on_callback) {
      on_callback(c);
    }
  }
  void completed(const model::sorcus::XcanCompletion& c) override {
    if (on_completed) {
      on_completed(c);
    }
  }

 private:
  std::string name_;
  model::sorcus::XcanModule module_;  // after the functions: it may call them once built
};

}  // namespace canemu::daemon
