// CanBus: frames that go wrong. Dominant holds on the wire, the error phase a frame's first
// detected error starts (error flags, delimiters, who counts what), and what its actions do.
#include <algorithm>

#include "bus/can_bus_detail.hpp"
#include "canemu/firmware_model/bus/can_bus.hpp"

namespace canemu::model {

using detail::because;
using detail::kSuspendBits;
using detail::with_ppm;

void CanBus::hold_dominant(SimTime from, SimDuration duration) {
  if (duration.ns() <= 0) {
    return;
  }
  holds_.emplace_back(from, duration);
  scheduler_.schedule_at(from, [this](SimTime now) {
    if (!busy_) {
      run_hold(now);
    }
    // A hold that starts during a frame is seen by that frame's error simulation only if it was
    // known at its start of frame; otherwise it takes effect when the bus is next free.
  });
}

void CanBus::run_hold(SimTime now) {
  busy_ = true;
  in_flight_ = {};
  account_recessive(now);
  std::vector<BusParticipant> parts;
  BitTiming nominal;
  bool have_timing = false;
  for (NodeId id = 0; id < node_count_; ++id) {
    Node& n = refresh(id);
    if (!on_bus(n)) {
      continue;
    }
    BusParticipant p;
    p.id = id;
    p.drives = !n.listen_only;
    p.passive = n.fc->error_passive();
    parts.push_back(p);
    if (!have_timing) {
      nominal = timing_of(n).nominal;
      have_timing = true;
    }
  }
  if (!have_timing) {
    // Nobody to see it: the bus is simply unusable until the hold ends.
    SimTime end = now;
    for (const auto& [from, duration] : holds_) {
      if (from <= now && now < from + duration) {
        end = std::max(end, from + duration);
      }
    }
    scheduler_.schedule_at(end, [this, end](SimTime) { bus_released(end, end); });
    return;
  }
  run_error_phase(now, parts, nullptr, nominal, nominal, 0);
}

void CanBus::join_late_contenders(NodeId tx, const FrameFault& fault, bool acks_suppressed,
                                  uint16_t first_bit) {
  // A contender whose loss lies after the first detection still sends when the error comes
  // (only a dominant hold comes that early: every other detection lies at the first bit after
  // the winner's arbitration field or later, and no loss after it). It is one of the error's
  // transmitters, and the error phase plays out what becomes of it (a loss, an error). The
  // others lost by then, at the latest at the same sample point: receivers, told of the loss at
  // its instant, before the error frame ends.
  bool late = false;
  for (const Arbitration::AtBit& loss : arbitration_.lost()) {
    if (loss.bit > first_bit) {
      if (!late) {
        late = true;
        error_senders_.assign(in_flight_.begin(), in_flight_.end());
      }
      error_senders_.push_back(loss.node);
      whole_encoding(nodes_[loss.node]);
    } else {
      nodes_[loss.node].stats.arbitration_lost++;
    }
  }
  if (late) {
    in_flight_ = error_senders_;  // until the bus is free, as the arbitration's list
    arbitration_.forget_lost_after(first_bit);
    general_roles(tx, nodes_[tx].encoded, fault, acks_suppressed);  // with them as senders
  }
}

void CanBus::run_error_phase(SimTime sof, std::span<const BusParticipant> parts,
                             const EncodedFrame* e, const BitTiming& nominal, const BitTiming& data,
                             uint16_t first_bit) {
  ErrorPhase::Outcome out = ErrorPhase({sof, e, nominal, data, first_bit, holds_}, parts).run();
  // The frame is the arbitration's senders' (not that of a contender still sending when the
  // error came, join_late_contenders).
  const std::vector<NodeId>& senders = arbitration_.senders();
  const auto sends = [&](const BusParticipant& p) {
    return p.transmitter && std::find(senders.begin(), senders.end(), p.id) != senders.end();
  };
  const SimTime ifs_end = out.ifs_end;
  const SimTime dominant_end = out.dominant_end;
  error_frames_on_bus_++;
  bus_load_.record(sof, ifs_end);
  if (on_bus_event) {
    BusEvent ev{e != nullptr ? BusEvent::Kind::error_frame : BusEvent::Kind::bus_held,
                sof,
                out.end,
                0,
                std::nullopt,
                first_bit};
    for (const auto& p : parts) {
      if (sends(p)) {
        ev.transmitter = p.id;
        ev.frame = nodes_[p.id].controller->pending_tx()->frame;
        break;
      }
    }
    on_bus_event(ev);
  }

  // Frames the receivers validated before the error reached them (last EOF bit) are delivered.
  std::optional<Frame> frame;
  for (const auto& p : parts) {
    if (sends(p) && e != nullptr) {
      frame = nodes_[p.id].controller->pending_tx()->frame;
    }
  }
  for (const ErrorPhase::Action& a : out.actions) {
    scheduler_.schedule_at(a.at, [this, a, frame](SimTime now) { apply(now, a, frame); });
  }
  // At the end of the error frame: transmitters that did not succeed retry (or drop a single
  // shot); error-passive transmitters suspend, unless they lost arbitration on the way (they
  // were receivers of it); the bus is free after the intermission.
  scheduler_.schedule_at(
      out.end, [this, transmitters = std::move(out.transmitters), ifs_end, nominal](SimTime now) {
        for (const ErrorPhase::Outcome::Transmitter& t : transmitters) {
          Node& n = nodes_[t.id];
          FaultConfinement& fc = n.controller->confinement();
          if (fc.error_passive() && !t.lost_arbitration) {
            n.ready_at = ifs_end + nominal.bits_duration(kSuspendBits);
          }
          if (t.sent) {
            continue;
          }
          const TxFrame* p = n.controller->pending_tx();
          if (p != nullptr && p->single_shot) {
            n.stats.tx_dropped++;
            forget_tx(n);
            n.controller->on_tx_dropped(now);
          }
        }
      });
  scheduler_.schedule_at(
      ifs_end, [this, dominant_end, ifs_end](SimTime) { bus_released(dominant_end, ifs_end); });
}

void CanBus::apply(SimTime now, const ErrorPhase::Action& a, const std::optional<Frame>& frame) {
  using Kind = ErrorPhase::Action::Kind;
  Node& n = nodes_[a.node];
  FaultConfinement& fc = n.controller->confinement();
  switch (a.kind) {
    case Kind::error: {
      if (a.count) {
        a.role == ErrorRole::transmitter ? fc.transmitter_error() : fc.receiver_detected_error();
      }
      (a.role == ErrorRole::transmitter ? n.stats.errors_as_transmitter
                                        : n.stats.errors_as_receiver)[a.type]++;
      BusErrorEvent ev;
      ev.at = now;
      ev.type = a.type;
      ev.role = a.role;
      ev.bit = a.bit;
      ev.in_frame = a.in_frame;
      ev.field = a.field;
      ev.destuffed_bit = a.destuffed_bit;
      ev.extended_frame = a.extended;
      ev.data_phase = a.data_phase;
      ev.tec = fc.tec();
      ev.rec = fc.rec();
      n.controller->on_error(ev);
      break;
    }
    case Kind::severe:
      a.role == ErrorRole::transmitter ? fc.dominant_sequence(ErrorRole::transmitter)
                                       : fc.receiver_severe_error();
      break;
    case Kind::arbitration_lost:
      n.stats.arbitration_lost++;
      n.controller->on_arbitration_lost(now, a.bit, a.destuffed_bit);
      break;
    case Kind::tx_ok: {
      fc.transmit_succeeded();
      n.stats.frames_sent++;
      const TxFrame* t = pending(n);
      if (t != nullptr && t->self_reception) {
        n.stats.frames_received++;
        n.controller->on_frame(now, t->frame, true);
      }
      forget_tx(n);
      n.controller->on_tx_done(now);
      break;
    }
    case Kind::rx_ok:
      if (a.count) {
        fc.receive_succeeded();
      }
      if (frame) {
        n.stats.frames_received++;
        n.controller->on_frame(now, *frame, false);
      }
      break;
  }
  CounterSample why;
  if (a.kind == Kind::error) {
    why = because(CounterCause::error, a.role, a.type);
  } else if (a.kind == Kind::severe) {
    why = because(CounterCause::severe, a.role);
  }
  report_state(a.node, now, why);
}

}  // namespace canemu::model
