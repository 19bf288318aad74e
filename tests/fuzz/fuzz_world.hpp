// What the daemon's fuzz targets share: a configuration parsed once, a fresh simulation of it
// for each input (nothing one input did can hide or cause another's crash), and one client's
// session of a control dispatcher on it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string_view>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/control/control_dispatcher.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::fuzzing {

// `text` parsed as a configuration; a text that does not parse is the target's bug: abort.
inline daemon::Config parse_or_abort(std::string_view text) {
  auto parsed = daemon::parse_config(text, "fuzz.toml");
  if (!parsed) {
    std::abort();
  }
  return std::move(*parsed);
}

inline std::unique_ptr<daemon::Simulation> fresh_simulation(const daemon::Config& config) {
  auto sim = daemon::Simulation::build(config);
  if (!sim) {
    std::abort();
  }
  return std::move(*sim);
}

// The loop of a dispatcher with one client, as the server would count it, that keeps the
// doorbell of the last channel opened.
struct OneClientLoop final : daemon::LoopServices {
  daemon::Doorbell* bell = nullptr;
  uint16_t client_count() override { return 1; }
  void watch(daemon::Doorbell& d) override { bell = &d; }
  void unwatch(daemon::Doorbell&) override { bell = nullptr; }
};

// A fresh simulation of `config` in stepped time and one client's session of a control
// dispatcher on it; `end()` closes what the session opened.
struct OneClient {
  std::unique_ptr<daemon::Simulation> sim;
  OneClientLoop loop;
  daemon::ControlDispatcher dispatcher;
  daemon::Session session;
  explicit OneClient(const daemon::Config& config)
      : sim(fresh_simulation(config)),
        dispatcher(*sim, daemon::TimeSetting{daemon::TimeMode::stepped, 1.0}, loop) {}
  void handle(const void* packet, std::size_t size, const daemon::ControlDispatcher::Send& send) {
    dispatcher.handle(session, static_cast<const uint8_t*>(packet), size, send);
  }
  void end() { dispatcher.end_session(session); }
};

}  // namespace canemu::fuzzing
