// The owner's side of a bus across hosts: the nodes other daemons open on its buses, run as
// real nodes here, and the requests (frames, modes, closes) they send for them.
#ifdef CANEMU_HAVE_DDS

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "distributed_impl.hpp"

namespace canemu::daemon {

void Distributed::Impl::open_hosted(const canemu_net_Request& r) {
  const std::string daemon = get(r.from);
  auto refuse = [&](const std::string& why) {
    canemu_net_Event e{};
    e.kind = canemu_net_EV_REFUSED;
    e.node = r.node;
    e.opened = r.seq;
    e.at_ns = sim.scheduler().now().ns();
    put(e.text, why);
    send_event(daemon, e);
  };
  const std::string bus_name = get(r.bus);
  const auto bus = sim.bus_index(bus_name);
  if (!bus || sim.config().remote(sim.bus_config(*bus))) {
    refuse(fmt::format("daemon {} simulates no bus \"{}\"", cfg.name, bus_name));
    return;
  }
  if (sim.lin_bus(*bus) != nullptr) {
    refuse(fmt::format("\"{}\" is a LIN bus", bus_name));
    return;
  }
  // The controller's programming as the other daemon computed it; checked, so that no value
  // that came over the network can upset the model (a prescaler of 0, a bit of 1 quantum).
  auto timing_ok = [](uint64_t clock, uint32_t prescaler, uint32_t tseg1, uint32_t tseg2,
                      uint32_t sjw) {
    return clock >= 1'000'000 && clock <= 1'000'000'000 && prescaler >= 1 && prescaler <= 1024 &&
           tseg1 >= 1 && tseg1 <= 256 && tseg2 >= 1 && tseg2 <= 128 && sjw >= 1 && sjw <= tseg2;
  };
  // A classic controller may be given by its SJA1000 registers alone (ddstypes/canemu_net.idl):
  // their timing at the IXXAT's 16 MHz is its nominal timing.
  BitTiming nominal{r.clock_hz, r.n_prescaler, r.n_tseg1, r.n_tseg2, r.n_sjw, 1};
  const bool registers_only = !r.fd && r.clock_hz == 0 && r.n_prescaler == 0 && r.n_tseg1 == 0 &&
                              r.n_tseg2 == 0 && r.n_sjw == 0 && (r.btr0 != 0 || r.btr1 != 0);
  if (registers_only) {
    auto t = sja1000::decode_btr(r.btr0, r.btr1);
    if (!t) {
      refuse(fmt::format("BTR0 0x{:02X} BTR1 0x{:02X} are no SJA1000 timing: {}", r.btr0, r.btr1,
                         t.error().message));
      return;
    }
    nominal = *t;
  }
  if (!timing_ok(nominal.clock_hz, nominal.prescaler, nominal.tseg1, nominal.tseg2, nominal.sjw) ||
      (r.fd && !timing_ok(r.clock_hz, r.d_prescaler, r.d_tseg1, r.d_tseg2, r.d_sjw)) ||
      r.restart_ns < 0) {
    refuse(
        fmt::format("the node's bit timing (clock {} Hz, prescaler {}, tseg1 {}, tseg2 {}, "
                    "sjw {}) is no controller's",
                    r.clock_hz, r.n_prescaler, r.n_tseg1, r.n_tseg2, r.n_sjw));
    return;
  }
  const std::string device = get(r.device);
  if (!valid_name(device)) {
    refuse(fmt::format("\"{}\" is not a device name", printable(device)));
    return;
  }
  Hosted* h = find_hosted(daemon, r.node);
  if (h == nullptr) {
    auto made = std::make_unique<Hosted>();
    h = made.get();
    h->link = this;
    h->daemon = daemon;
    h->number = r.node;
    h->bus = *bus;
    h->node = &sim.spare_node(*bus);
    h->node->claim(true);  // until it is closed, whether on the bus or not
    hosted[{daemon, r.node}] = std::move(made);
  }
  h->opened = r.seq;
  h->fd = r.fd && h->node->fd_capable();
  h->queue.clear();
  HostedNodeSettings s;
  s.btr0 = r.btr0;
  s.btr1 = r.btr1;
  s.nominal = nominal;
  s.data = BitTiming{r.clock_hz, r.d_prescaler, r.d_tseg1, r.d_tseg2, r.d_sjw, 1};
  s.listen_only = r.listen_only;
  s.fd = r.fd;
  const BusConfig& bc = sim.bus_config(*bus);
  if (bc.kind == BusKind::can && r.btr0 == 0 && r.btr1 == 0) {
    // A CAN FD controller's node on a classic bus, which this daemon runs on SJA1000s: their
    // registers for the bus's rate.
    if (auto t = node_timing(false, node_rates(bc, false))) {
      s.btr0 = t->btr0;
      s.btr1 = t->btr1;
    }
  }
  s.restart_delay = SimDuration(std::max<int64_t>(0, r.restart_ns));
  h->node->configure(s, h, [h] { return h->next(); });
  const std::string name = daemon + "/" + get(r.device);
  h->lease = {};
  if (!sim.devices().exists(name)) {
    h->lease = sim.add_ephemeral(name, *bus, *h->node, 0);
  }
}

void Distributed::Impl::on_request(const canemu_net_Request& r) {
  if (get(r.to) != cfg.name) {
    return;
  }
  settle();
  ++counters.requests_received;
  const std::string from = get(r.from);
  if (!valid_name(from)) {
    drop(NetDrop::unknown_daemon,
         fmt::format("dropped a request ({}) from \"{}\": a daemon's name {}", request_name(r.kind),
                     printable(from), kNameRule));
    return;
  }
  auto pit = peers.find(from);
  if (pit == peers.end() || pit->second.boot != r.from_boot) {
    return;  // its announcement has not come yet: only its hello, which it repeats until answered
  }
  Peer& p = pit->second;
  if (!p.announced || !p.refused.empty() || p.gone) {
    // Not heard announcing itself yet (its time mode and protocol unchecked), refused, or let
    // go: nothing it asks is done. A daemon says hello again each heartbeat until answered.
    drop(NetDrop::not_accepted,
         fmt::format("dropped a request ({}) from daemon {}: it is {}", request_name(r.kind), from,
                     p.gone               ? "gone (" + p.gone_reason + ")"
                     : !p.refused.empty() ? "refused (" + p.refused + ")"
                                          : std::string("not heard announcing itself yet")));
    return;
  }
  if (p.next_request != 0 && r.seq > p.next_request) {
    // Lost on the way (a reader that fell behind).
    drop(NetDrop::lost,
         fmt::format("{} request{} from daemon {} lost on the way (sequence {} after {})",
                     r.seq - p.next_request, r.seq - p.next_request == 1 ? "" : "s", from, r.seq,
                     p.next_request - 1),
         r.seq - p.next_request);
  }
  p.next_request = r.seq + 1;
  if (r.kind == canemu_net_REQ_HELLO) {
    if (stepped() && stepped_owner.empty() && !p.follower) {
      p.follower = true;
      log::info("daemon {} uses this daemon's buses in stepped time: steps wait for it", from);
    }
    canemu_net_Event e{};
    e.kind = canemu_net_EV_WELCOME;
    e.at_ns = sim.scheduler().now().ns();
    send_event(from, e);
    return;
  }
  if (r.kind == canemu_net_REQ_OPEN) {
    open_hosted(r);
    return;
  }
  if (r.kind == canemu_net_REQ_STEP) {
    if (stepped() && stepped_owner.empty() && r.step_ns > 0 &&
        r.step_ns <= int64_t{60} * 1'000'000'000) {
      enqueue_step(Step{r.step_ns, from, r.step});
    } else {
      drop(NetDrop::malformed,
           fmt::format("dropped a step request of {} ns from daemon {}: {}", r.step_ns, from,
                       !stepped() || !stepped_owner.empty() ? "this daemon leads no steps"
                                                            : "a step is 1 ns to 60 s"));
    }
    return;
  }
  if (r.kind == canemu_net_REQ_READY) {
    if (barrier && r.step == step_no && waiting.erase(from) > 0 && waiting.empty()) {
      run_step();
    }
    return;
  }
  Hosted* h = find_hosted(from, r.node);
  if (h == nullptr) {
    drop(NetDrop::no_node,
         fmt::format("dropped a request ({}) from daemon {}: its node {} ({}) "
                     "is not open here",
                     request_name(r.kind), from, r.node, printable(get(r.device))));
    return;
  }
  switch (r.kind) {
    case canemu_net_REQ_ONLINE:
      h->node->go_online();
      break;
    case canemu_net_REQ_OFFLINE:
      h->queue.clear();
      h->node->go_offline();
      break;
    case canemu_net_REQ_CLOSE:
      hosted.erase({from, r.node});
      break;
    case canemu_net_REQ_RESTART:
      h->node->restart();
      break;
    case canemu_net_REQ_NAME: {
      if (!valid_name(get(r.device))) {
        drop(NetDrop::malformed,
             fmt::format("dropped a name request from daemon {}: \"{}\" is not a device name", from,
                         printable(get(r.device))));
        break;
      }
      const std::string name = from + "/" + get(r.device);
      if (!sim.devices().exists(name)) {
        h->lease = {};
        h->lease = sim.add_ephemeral(name, h->bus, *h->node, 0);
      }
      break;
    }
    case canemu_net_REQ_TX: {
      auto f = frame_of_fields(r);
      if (!f) {
        drop(NetDrop::malformed,
             fmt::format("dropped a frame of daemon {}'s node {}: id 0x{:X}, dlc {}, {} bytes{}{} "
                         "is no frame",
                         from, printable(get(r.device)), r.id, r.dlc, r.len, r.fd ? ", CAN FD" : "",
                         r.remote ? ", remote" : ""));
        break;
      }
      if (f->fd() && !h->fd) {
        // As the LCM and DDS bridges: a frame this node's controller does not send is rejected,
        // not put on the wire as something else; the node's driver hears it was not sent.
        drop(NetDrop::fd_on_classic,
             fmt::format("rejected a CAN FD frame (id 0x{:X}, dlc {}) of daemon {}'s node {}: "
                         "{}",
                         f->id(), f->dlc(), from, printable(get(r.device)),
                         sim.bus_config(h->bus).kind == BusKind::can
                             ? sim.bus_config(h->bus).name + " is a classic CAN bus"
                             : std::string("the node was opened as a classic controller")));
        h->emit(canemu_net_EV_DROPPED, sim.scheduler().now(), &*f);
        break;
      }
      if (h->queue.size() >= kOwnerQueue) {
        h->emit(canemu_net_EV_DROPPED, sim.scheduler().now(), &*f);
        break;
      }
      h->queue.push_back(TxFrame{*f, r.single_shot, r.self_reception});
      h->node->kick();
      break;
    }
    default:
      drop(NetDrop::malformed,
           fmt::format("dropped a request of unknown kind {} from daemon {}", r.kind, from));
      break;
  }
}

}  // namespace canemu::daemon

#endif  // CANEMU_HAVE_DDS
