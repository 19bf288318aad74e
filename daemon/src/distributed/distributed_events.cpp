// A user's side of a bus across hosts: the events its owner reports for this daemon's remote
// nodes, placed at their instant in this daemon's time.
#ifdef CANEMU_HAVE_DDS

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "remote_node.hpp"

namespace canemu::daemon {

SimTime Distributed::Impl::local_time(const Peer& owner, int64_t owner_ns) {
  const int64_t now = sim.scheduler().now().ns();
  const int64_t here = owner_ns - owner.offset_ns;
  // The offset underestimates by the heartbeat's delay, so an event is normally a little late
  // here (the link's delay beyond the fastest heartbeat's): late beyond kLateBoundNs counts.
  if (here < now) {
    counters.late_max_ns = std::max(counters.late_max_ns, now - here);
    counters.late += now - here > kLateBoundNs ? 1 : 0;
  }
  return SimTime::from_ns(std::min(here, now));
}

void Distributed::Impl::on_events(const canemu_net_Events& b) {
  const std::string to = get(b.to);
  if (to != cfg.name && !to.empty()) {
    return;
  }
  const std::string from = get(b.from);
  auto pit = peers.find(from);
  if (to.empty() && from != stepped_owner) {
    return;  // another owner's steps
  }
  const uint32_t n = b.list._length;
  if (n == 0) {
    return;
  }
  counters.events_received += n;
  if (pit == peers.end() || pit->second.boot != b.from_boot || pit->second.gone) {
    drop(NetDrop::not_accepted,
         fmt::format("dropped {} ({}) from daemon {}: it is {}",
                     n == 1 ? std::string("an event") : fmt::format("{} events", n),
                     event_name(b.list._buffer[0].kind), printable(from),
                     pit == peers.end()                ? "not heard announcing itself"
                     : pit->second.boot != b.from_boot ? "of another boot than the one heard"
                                                       : "gone (" + pit->second.gone_reason + ")"),
         n);
    return;
  }
  for (uint32_t i = 0; i < n; ++i) {
    on_event(pit->second, from, b.list._buffer[i]);
  }
}

void Distributed::Impl::on_event(Peer& p, const std::string& from, const canemu_net_Event& e) {
  settle();
  SimScheduler& s = sim.scheduler();
  switch (e.kind) {
    case canemu_net_EV_WELCOME:
      if (!p.welcomed && p.refused.empty()) {
        owner_up(p);
      }
      return;
    case canemu_net_EV_STEP_BEGIN: {
      // This daemon's world runs to the owner's instant (it joins at the owner's time), its
      // transmitters look at their rings, and what they send reaches the owner before "ready".
      s.run_until(SimTime::from_ns(std::max(e.at_ns, s.now().ns())));
      if (loop != nullptr) {
        loop->before_step();
      }
      canemu_net_Request r{};
      r.kind = canemu_net_REQ_READY;
      r.step = e.step;
      send_request(from, r);
      return;
    }
    case canemu_net_EV_STEP_DONE: {
      run_to(SimTime::from_ns(std::max(e.at_ns, s.now().ns())),
             [this, mine = get(e.asker) == cfg.name, token = e.token,
              note = printable(get(e.text))](uint64_t events) {
               if (loop != nullptr) {
                 loop->after_step();
               }
               if (mine && loop != nullptr) {
                 loop->step_done(token, events, sim.scheduler().now().ns(), note);
               }
             });
      return;
    }
    default:
      break;
  }
  for (RemoteNode* n : nodes) {
    if (n->owner() == from && n->number() == e.node) {
      deliver(*n, e, p);
      return;
    }
  }
  drop(NetDrop::no_node,
       fmt::format("dropped an event ({}) from daemon {}: node {} is not open here",
                   event_name(e.kind), from, e.node));
}

void Distributed::Impl::deliver(RemoteNode& n, const canemu_net_Event& e, const Peer& owner) {
  if (!stepped()) {
    n.deliver(e, local_time(owner, e.at_ns));
    return;
  }
  // Stepped: this daemon's time is the owner's; an event of the step runs here at its instant
  // when the step's end is reached (EV_STEP_DONE), so everything on this daemon sees it in order.
  SimScheduler& s = sim.scheduler();
  const SimTime at = SimTime::from_ns(e.at_ns);
  if (at <= s.now()) {
    counters.late += at < s.now() ? 1 : 0;
    counters.late_max_ns = std::max(counters.late_max_ns, (s.now() - at).ns());
    n.deliver(e, s.now());
    return;
  }
  s.schedule_at(at, [this, e, number = n.number()](SimTime now) {
    for (RemoteNode* m : nodes) {
      if (m->number() == number) {
        m->deliver(e, now);
        return;
      }
    }
  });
}

}  // namespace canemu::daemon

#endif  // CANEMU_HAVE_DDS
