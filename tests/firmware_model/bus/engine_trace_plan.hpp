// The plan of a bus scenario of the engine trace (engine_trace.hpp): its buses, nodes and every
// action, drawn from the scenario's seed alone before anything runs, so that what a scenario does
// does not depend on what the engine does.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "canemu/firmware_model/bus/can_controller.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "engine_trace.hpp"

namespace canemu::model::testing::engine_trace {

// Classic rates on a 16 MHz clock: 83 1/3, 125, 250, 500, 666 2/3 kbit/s and 1 Mbit/s.
extern const std::array<BitTiming, 6> kClassic;
// CAN FD on an 80 MHz clock: nominal 500 kbit/s and 1 Mbit/s (with their classic twins in
// kClassic, for classic-only nodes), data 2, 4, 5 and 8 Mbit/s.
extern const std::array<BitTiming, 2> kFdNominal;
extern const std::array<std::size_t, 2> kFdNominalTwin;
extern const std::array<BitTiming, 4> kFdData;

std::string timing_text(const BitTiming& t);

struct NodeSetup {
  NodeTiming timing;
  bool fd_capable = false;
  BusOffRecovery recovery = BusOffRecovery::automatic;
  int64_t restart_delay_ns = -1;  // on_restart: the host restarts this long after bus-off
  uint16_t rec_limit = 0xFFFF;
  uint8_t warning_limit = kDefaultWarningLimit;
  bool responder = false;  // answers remote frames whose identifier is its own mod 3
};

enum class Op : uint8_t {
  send,
  connect,
  oscillator,
  run,
  listen,
  self_test,
  retime,
  fd,
  counters,
  restart,
  attach,
  withdraw,
  add_rule,
  disable_rule,
  remove_rule,
  hold,
  suppress_acks,
  at_arbitration,  // a node-level fault applied at the next look for transmitters
};

struct Action {
  int64_t at = 0;
  Op op = Op::send;
  uint32_t node = 0;
  bool on = false;  // connect, run, listen, self_test, fd: the new setting; counters: tell the bus
  int64_t a = 0;    // oscillator: ppm; counters: TEC; hold: start; rules: id; retime: timing
  int64_t b = 0;    // counters: REC; hold, suppress_acks: duration (ns)
  uint8_t variant = 0;            // at_arbitration: 0 connect, 1 oscillator, 2 counters
  std::vector<uint32_t> nodes{};  // send: who sends (several: at the same instant)
  std::vector<TxFrame> frames{};  // send: each one's frames, in order (a burst when one node)
  std::optional<FaultRule> rule{};
};

struct Plan {
  bool fd_bus = false;
  std::size_t rate = 0;  // classic: into kClassic; CAN FD: into kFdNominal
  std::size_t data_rate = 0;
  int64_t bit_ns = 0;
  int64_t duration_ns = 0;
  std::size_t initial = 0;  // nodes attached at the start; the rest attach later, in order
  std::vector<NodeSetup> nodes;
  std::vector<std::pair<uint32_t, bool>> id_pool;
  std::vector<Action> actions;
};

// The plan of a scenario, drawn from `rng`.
Plan make_plan(Rng& rng);

}  // namespace canemu::model::testing::engine_trace
