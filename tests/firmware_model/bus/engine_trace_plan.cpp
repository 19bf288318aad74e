// The plan of a bus scenario of the engine trace (engine_trace_plan.hpp).
#include "engine_trace_plan.hpp"

#include <algorithm>

namespace canemu::model::testing::engine_trace {
namespace {

BitTiming classic(uint32_t prescaler, uint32_t tseg1, uint32_t tseg2, uint32_t sjw) {
  return BitTiming{16'000'000, prescaler, tseg1, tseg2, sjw, 1};
}
BitTiming fd80(uint32_t prescaler, uint32_t tseg1, uint32_t tseg2) {
  return BitTiming{80'000'000, prescaler, tseg1, tseg2, tseg2, 1};
}

void fill_payload(Rng& rng, uint8_t* data, std::size_t length) {
  static constexpr std::array<uint8_t, 6> kRuns{0x00, 0xFF, 0x0F, 0xF0, 0x55, 0x80};
  const bool runs = rng.chance(30);
  for (std::size_t i = 0; i < length; ++i) {
    data[i] = runs ? kRuns[rng.below(kRuns.size())] : static_cast<uint8_t>(rng.next());
  }
}

TxFrame plan_frame(Rng& rng, const Plan& plan, const NodeSetup& node,
                   std::optional<std::pair<uint32_t, bool>> id = std::nullopt) {
  FrameSpec spec;
  spec.fd = plan.fd_bus && node.fd_capable && rng.chance(70);
  if (!id) {
    id = rng.chance(80) ? plan.id_pool[rng.below(plan.id_pool.size())]
                        : std::make_pair(static_cast<uint32_t>(rng.below(0x800)), false);
  }
  spec.id = id->first;
  spec.extended = id->second;
  if (spec.fd) {
    spec.brs = node.timing.has_data_phase && rng.chance(60);
    spec.esi = rng.chance(10);
  } else {
    spec.remote = rng.chance(12);
  }
  const auto dlc = static_cast<uint8_t>(spec.fd && rng.chance(25) ? rng.between(9, 15)
                                        : rng.chance(5)           ? rng.between(9, 15)
                                                                  : rng.between(0, 8));
  spec.dlc = dlc;
  std::array<uint8_t, kMaxFdLength> data{};
  const std::size_t length = spec.remote ? 0 : dlc_to_length(dlc, spec.fd);
  fill_payload(rng, data.data(), length);
  spec.data = std::span<const uint8_t>(data.data(), length);
  return TxFrame{*Frame::create(spec), rng.chance(12), rng.chance(10)};
}

FaultRule plan_rule(Rng& rng, const Plan& plan, int64_t at) {
  FaultRule r;
  const uint64_t kind = rng.below(7);
  if (kind < 5) {
    r.fault.error = static_cast<CanErrorType>(kind);
    if (rng.chance(50)) {
      r.fault.bit = static_cast<uint16_t>(rng.below(300));
    }
  } else if (kind == 5) {
    r.fault.suppress_ack = true;
  } else {
    r.bit_error_rate = static_cast<double>(rng.between(5, 200)) / 10000.0;
  }
  if (rng.chance(40)) {
    r.match.transmitter = static_cast<NodeId>(rng.below(plan.nodes.size()));
  }
  if (rng.chance(30)) {
    const auto& [id, ext] = plan.id_pool[rng.below(plan.id_pool.size())];
    r.match.id = id;
    r.match.mask = ext ? kMaxExtendedId : kMaxStandardId;
  } else if (rng.chance(10)) {
    r.match.id = static_cast<uint32_t>(rng.below(0x800));
    r.match.mask = static_cast<uint32_t>(rng.below(0x800));
  }
  if (rng.chance(10)) {
    r.match.extended = rng.chance(50);
  }
  if (rng.chance(10)) {
    r.match.remote = rng.chance(50);
  }
  if (rng.chance(30)) {
    r.skip = rng.below(4);
  }
  // Most rules hit a few frames; one that hits every frame it matches makes a scenario a run of
  // error frames (and drives its senders bus-off), so those are rarer or hit by chance.
  if (rng.chance(80)) {
    r.count = rng.between(1, 12);
    if (rng.chance(30)) {
      r.probability = static_cast<double>(rng.between(10, 90)) / 100.0;
    }
  } else if (!r.match.transmitter || rng.chance(50)) {
    r.probability = static_cast<double>(rng.between(5, 40)) / 100.0;
  }
  if (rng.chance(30)) {
    r.from = SimTime::from_ns(at + rng.between(0, plan.duration_ns / 2));
    if (rng.chance(70)) {
      r.until = r.from + SimDuration(rng.between(100, 5000) * plan.bit_ns);
    }
  }
  r.seed = rng.next();
  return r;
}

}  // namespace

const std::array<BitTiming, 6> kClassic{classic(12, 12, 3, 1), classic(8, 13, 2, 1),
                                        classic(4, 13, 2, 1),  classic(2, 13, 2, 1),
                                        classic(1, 17, 6, 2),  classic(1, 11, 4, 1)};
const std::array<BitTiming, 2> kFdNominal{fd80(2, 63, 16), fd80(1, 63, 16)};
const std::array<std::size_t, 2> kFdNominalTwin{3, 5};
const std::array<BitTiming, 4> kFdData{fd80(2, 15, 4), fd80(1, 15, 4), fd80(1, 11, 4),
                                       fd80(1, 7, 2)};

std::string timing_text(const BitTiming& t) {
  std::string s;
  appendf(s, "%lluHz/%u/%u+%u+%u", static_cast<unsigned long long>(t.clock_hz), t.prescaler,
          t.tseg1, t.tseg2, t.sjw);
  return s;
}

Plan make_plan(Rng& rng) {
  Plan p;
  p.fd_bus = rng.chance(45);
  p.rate = p.fd_bus ? rng.below(kFdNominal.size()) : rng.below(kClassic.size());
  p.data_rate = rng.below(kFdData.size());
  const BitTiming& bus_nominal = p.fd_bus ? kFdNominal[p.rate] : kClassic[p.rate];
  p.bit_ns = bus_nominal.bits_duration(1).ns();
  p.duration_ns = rng.between(2000, 20000) * p.bit_ns;
  const std::size_t n = static_cast<std::size_t>(rng.between(2, 8));
  const std::size_t late =
      n >= 3 && rng.chance(30) ? rng.between(1, std::min<int64_t>(2, n - 2)) : 0;
  p.initial = n - late;
  for (std::size_t i = 0; i < n; ++i) {
    NodeSetup s;
    s.fd_capable = p.fd_bus;
    if (s.fd_capable) {
      s.timing.nominal = kFdNominal[p.rate];
      s.timing.has_data_phase = true;
      s.timing.data = kFdData[rng.chance(3) ? rng.below(kFdData.size()) : p.data_rate];
    } else {
      s.timing.nominal = kClassic[p.rate];
    }
    if (rng.chance(20)) {
      s.timing.oscillator_ppm = static_cast<int32_t>(rng.between(-1500, 1500));
    }
    s.recovery = rng.chance(50) ? BusOffRecovery::automatic : BusOffRecovery::on_restart;
    if (s.recovery == BusOffRecovery::on_restart && rng.chance(75)) {
      s.restart_delay_ns = rng.between(0, 2000) * p.bit_ns;
    }
    s.rec_limit = rng.chance(50) ? 255 : 0xFFFF;
    static constexpr std::array<uint8_t, 6> kWarning{1, 50, 127, 128, 200, 255};
    s.warning_limit = rng.chance(80) ? kDefaultWarningLimit : kWarning[rng.below(kWarning.size())];
    s.responder = rng.chance(30);
    p.nodes.push_back(s);
  }
  // On a CAN FD bus: a classic-only node (a form error in every FD frame while it is
  // error-active), or one without a data phase (it cannot follow bit-rate switches).
  if (p.fd_bus && rng.chance(25)) {
    NodeSetup& s = p.nodes[rng.below(n)];
    s.fd_capable = false;
    s.timing.has_data_phase = false;
    s.timing.nominal = kClassic[kFdNominalTwin[p.rate]];
  }
  if (p.fd_bus && rng.chance(10)) {
    p.nodes[rng.below(n)].timing.has_data_phase = false;
  }
  // A node at another bit rate, or with an oscillator too far off to decode the others: it
  // destroys the traffic while it is error-active.
  if (rng.chance(15)) {
    NodeSetup& s = p.nodes[rng.below(n)];
    const BitTiming other = kClassic[rng.below(kClassic.size())];
    s.timing.nominal = other == s.timing.nominal ? kClassic[(rng.below(5) + 1) % 6] : other;
  }
  if (rng.chance(8)) {
    p.nodes[rng.below(n)].timing.oscillator_ppm =
        static_cast<int32_t>(rng.between(3000, 20000)) * (rng.chance(50) ? 1 : -1);
  }
  const std::size_t pool = static_cast<std::size_t>(rng.between(2, 8));
  for (std::size_t i = 0; i < pool; ++i) {
    const bool ext = rng.chance(30);
    const uint32_t id = static_cast<uint32_t>(
        rng.chance(50) ? rng.below(0x20) : rng.next() & (ext ? kMaxExtendedId : kMaxStandardId));
    p.id_pool.emplace_back(id, ext);
  }

  const int64_t dur = p.duration_ns;
  const int64_t bit = p.bit_ns;
  auto at = [&](int64_t from = 0) { return from + rng.between(0, dur - from - 1); };
  auto node = [&] { return static_cast<uint32_t>(rng.below(n)); };
  auto add = [&](Action a) { p.actions.push_back(std::move(a)); };
  auto pair = [&](Op op, uint32_t who, int64_t t, int64_t back_after, bool first) {
    add(Action{.at = t, .op = op, .node = who, .on = first});
    add(Action{.at = t + back_after, .op = op, .node = who, .on = !first});
  };

  // Late nodes, in order.
  std::vector<int64_t> attach_at;
  for (std::size_t i = 0; i < late; ++i) {
    attach_at.push_back(rng.between(dur / 10, dur * 8 / 10));
  }
  std::sort(attach_at.begin(), attach_at.end());
  for (std::size_t i = 0; i < late; ++i) {
    add(Action{.at = attach_at[i], .op = Op::attach, .node = static_cast<uint32_t>(p.initial + i)});
  }

  // Traffic: bursts from each node, and frames from several nodes at the same instant
  // (arbitration; the same identifier with other data: a collision; the same frame: sent
  // together).
  for (uint32_t i = 0; i < n; ++i) {
    const int64_t sends = rng.between(2, 24);
    for (int64_t k = 0; k < sends; ++k) {
      Action a{.at = rng.between(0, dur * 9 / 10), .op = Op::send, .node = i};
      a.nodes.push_back(i);
      const int64_t burst = rng.between(1, 5);
      for (int64_t b = 0; b < burst; ++b) {
        a.frames.push_back(plan_frame(rng, p, p.nodes[i]));
      }
      add(std::move(a));
    }
  }
  for (int64_t g = rng.between(0, 3); g > 0; --g) {
    Action a{.at = at(), .op = Op::send};
    const uint64_t how = rng.below(3);
    const TxFrame shared = plan_frame(rng, p, p.nodes[0]);
    for (uint32_t i = 0; i < n; ++i) {
      if (a.nodes.size() < 2 || rng.chance(60)) {
        a.nodes.push_back(i);
        if (how == 0) {
          a.frames.push_back(TxFrame{shared.frame, false, false});
        } else if (how == 1) {
          a.frames.push_back(plan_frame(
              rng, p, p.nodes[0], std::make_pair(shared.frame.id(), shared.frame.extended())));
        } else {
          a.frames.push_back(plan_frame(rng, p, p.nodes[i]));
        }
      }
    }
    add(std::move(a));
  }

  // Fault rules, from the start and while running; some disabled or removed later.
  std::size_t rules = 0;
  for (int64_t r = rng.chance(60) ? rng.between(1, 4) : 0; r > 0; --r) {
    add(Action{.at = 0,
               .op = Op::add_rule,
               .a = static_cast<int64_t>(rules++),
               .rule = plan_rule(rng, p, 0)});
  }
  for (int64_t r = rng.chance(40) ? rng.between(1, 2) : 0; r > 0; --r) {
    const int64_t t = at();
    add(Action{.at = t,
               .op = Op::add_rule,
               .a = static_cast<int64_t>(rules++),
               .rule = plan_rule(rng, p, t)});
  }
  if (rules > 0 && rng.chance(25)) {
    add(Action{.at = at(),
               .op = rng.chance(50) ? Op::disable_rule : Op::remove_rule,
               .a = static_cast<int64_t>(rng.below(rules))});
  }

  // The bus.
  if (rng.chance(30)) {
    for (int64_t h = rng.between(1, 2); h > 0; --h) {
      const int64_t bits = rng.chance(60)   ? rng.between(1, 30)
                           : rng.chance(75) ? rng.between(30, 300)
                                            : rng.between(300, 3000);
      const int64_t t = at();
      add(Action{.at = t, .op = Op::hold, .a = t + rng.between(0, 3) * bit, .b = bits * bit});
    }
  }
  if (rng.chance(15)) {
    add(Action{.at = at(), .op = Op::suppress_acks, .b = rng.between(50, 2000) * bit});
  }

  // The nodes.
  for (int64_t k = rng.chance(25) ? rng.between(1, 2) : 0; k > 0; --k) {
    pair(Op::connect, node(), at(), rng.between(10, 3000) * bit, false);
  }
  for (int64_t k = rng.chance(25) ? rng.between(1, 2) : 0; k > 0; --k) {
    const uint32_t who = node();
    const int64_t t = at();
    const int32_t ppm = rng.chance(50)   ? static_cast<int32_t>(rng.between(-1500, 1500))
                        : rng.chance(80) ? static_cast<int32_t>(rng.between(-20000, 20000))
                                         : static_cast<int32_t>(rng.between(-600000, 600000));
    add(Action{.at = t, .op = Op::oscillator, .node = who, .a = ppm});
    if (rng.chance(50)) {
      add(Action{.at = t + rng.between(10, 3000) * bit,
                 .op = Op::oscillator,
                 .node = who,
                 .a = p.nodes[who].timing.oscillator_ppm});
    }
  }
  if (rng.chance(20)) {
    pair(Op::run, node(), at(), rng.between(10, 3000) * bit, false);
  }
  if (rng.chance(20)) {
    pair(Op::listen, node(), at(), rng.between(10, 3000) * bit, true);
  }
  if (rng.chance(15)) {
    pair(Op::self_test, node(), at(), rng.between(10, 3000) * bit, true);
  }
  if (rng.chance(10)) {
    const uint32_t who = node();
    const int64_t t = at();
    add(Action{.at = t,
               .op = Op::retime,
               .node = who,
               .a = static_cast<int64_t>(rng.below(kClassic.size()))});
    add(Action{.at = t + rng.between(10, 3000) * bit, .op = Op::retime, .node = who, .a = -1});
  }
  if (p.fd_bus && rng.chance(15)) {
    pair(Op::fd, node(), at(), rng.between(10, 3000) * bit, false);
  }
  if (rng.chance(30)) {
    static constexpr std::array<int64_t, 9> kTec{0, 95, 96, 127, 128, 200, 255, 256, 300};
    static constexpr std::array<int64_t, 7> kRec{0, 95, 96, 127, 128, 255, 300};
    for (int64_t k = rng.between(1, 3); k > 0; --k) {
      add(Action{.at = at(),
                 .op = Op::counters,
                 .node = node(),
                 .on = rng.chance(50),
                 .a = rng.chance(80) ? kTec[rng.below(kTec.size())] : rng.between(0, 300),
                 .b = rng.chance(80) ? kRec[rng.below(kRec.size())] : rng.between(0, 300)});
    }
  }
  for (int64_t k = rng.chance(30) ? rng.between(1, 2) : 0; k > 0; --k) {
    add(Action{.at = at(), .op = Op::restart, .node = node()});
  }
  for (int64_t k = rng.chance(30) ? rng.between(1, 3) : 0; k > 0; --k) {
    Action a{.at = at(), .op = Op::withdraw, .node = node(), .on = rng.chance(50)};
    a.frames.push_back(plan_frame(rng, p, p.nodes[a.node]));  // the replacement, if `on`
    add(std::move(a));
  }
  for (int64_t k = rng.chance(20) ? rng.between(1, 2) : 0; k > 0; --k) {
    const uint32_t who = node();
    const int64_t t = at();
    const auto variant = static_cast<uint8_t>(rng.below(3));
    if (variant == 0) {
      add(Action{.at = t, .op = Op::at_arbitration, .node = who, .on = false, .variant = 0});
      add(Action{.at = t + rng.between(10, 3000) * bit,
                 .op = Op::at_arbitration,
                 .node = who,
                 .on = true,
                 .variant = 0});
    } else if (variant == 1) {
      add(Action{.at = t,
                 .op = Op::at_arbitration,
                 .node = who,
                 .a = rng.chance(50) ? 0 : rng.between(-20000, 20000),
                 .variant = 1});
    } else {
      add(Action{.at = t,
                 .op = Op::at_arbitration,
                 .node = who,
                 .a = rng.between(0, 300),
                 .b = rng.between(0, 300),
                 .variant = 2});
    }
  }
  std::stable_sort(p.actions.begin(), p.actions.end(),
                   [](const Action& x, const Action& y) { return x.at < y.at; });
  return p;
}

}  // namespace canemu::model::testing::engine_trace
