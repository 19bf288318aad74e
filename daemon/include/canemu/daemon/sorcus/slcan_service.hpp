// The SL-CANi requests of the control protocol (ipc::SlcanRequest), answered: each client's
// slots of configured "sorcus-sl-cani" devices, taken at sl064_bib_startup (every configured
// slot no other client holds) and given back, with the S-Link reset to its state after
// power-up, when the client goes away.
//
// Service routine calls and service requests go to the client holding the slot; they wait in
// its session outbox, which the server sends after the events that made them (and before a
// time step's reply).
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <set>
#include <span>
#include <tuple>
#include <vector>

#include "canemu/daemon/world/simulation.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

struct SlcanSession {
  std::set<unsigned> slots;                                     // held
  std::set<std::tuple<unsigned, uint16_t, uint16_t>> routines;  // (slot, task, func) installed
  std::deque<std::vector<uint8_t>> outbox;
};

class SlcanService {
 public:
  using Send = std::function<void(const void* data, std::size_t size, std::span<const int> fds)>;
  explicit SlcanService(Simulation& sim) : sim_(sim) {}
  ~SlcanService();
  SlcanService(const SlcanService&) = delete;
  SlcanService& operator=(const SlcanService&) = delete;

  void handle(SlcanSession& session, const ipc::SlcanRequest& m, const Send& send);
  // The session's slots given back (the client went away).
  void close_all(SlcanSession& session);

 private:
  void hook(const std::shared_ptr<SlcanDevice>& device);
  void startup(SlcanSession& session, ipc::SlcanReply& r);
  // One sl064_* call on `module`; false for an unknown op.
  bool call(SlcanDevice& device, SlcanSession& session, const ipc::SlcanRequest& m,
            ipc::SlcanReply& r, std::string& error);

  Simulation& sim_;
  std::set<std::shared_ptr<SlcanDevice>> hooked_;
  std::array<SlcanSession*, 6> owner_{};  // per slot
};

}  // namespace canemu::daemon
