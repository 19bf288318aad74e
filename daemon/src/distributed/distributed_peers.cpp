// The other daemons of the installation as this one hears them: their announcements, the time
// mode and protocol they must share, the hello to an owner, and what goes when one is gone.
#ifdef CANEMU_HAVE_DDS

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "remote_node.hpp"

namespace canemu::daemon {

std::string Distributed::Impl::time_problem(const Peer& p) const {
  const uint8_t ours = wire_time_mode(time.mode);
  if (p.time_mode != ours || (ours == canemu_net_TIME_SCALED && p.scale != time.scale)) {
    return fmt::format("its time is {}, this daemon's {}", time_text(p.time_mode, p.scale),
                       to_string(time));
  }
  return {};
}

void Distributed::Impl::on_daemon(const canemu_net_Daemon& d) {
  settle();
  const std::string name = get(d.name);
  if (!valid_name(name)) {
    // Not a daemon of ours (names follow the configuration's rule).
    drop(NetDrop::unknown_daemon,
         fmt::format("dropped an announcement from \"{}\": a daemon's name {}", printable(name),
                     kNameRule));
    return;
  }
  if (name == cfg.name) {
    if (d.boot != boot) {
      log::warning("another daemon in DDS domain {} partition \"{}\" calls itself \"{}\"",
                   cfg.domain, cfg.partition, name);
    }
    return;
  }
  Peer& p = peers[name];
  const bool fresh = p.name.empty() || p.boot != d.boot;
  if (fresh && !p.name.empty() && !p.gone) {
    peer_gone(p, "restarted");
  }
  if (fresh) {
    p = Peer{};
    p.name = name;
    p.boot = d.boot;
  }
  if (d.leaving) {
    if (!p.gone) {
      peer_gone(p, "it stopped");
    }
    return;
  }
  p.announced = true;
  p.protocol = d.protocol;
  p.version = printable(get(d.version));
  p.time_mode = d.time_mode;
  p.scale = d.scale;
  p.heard_ms = monotonic_ms();
  p.gone = false;
  p.buses.clear();
  p.owned.clear();
  for (uint32_t i = 0; i < d.buses._length && i < 64; ++i) {
    p.buses.push_back(printable(get(d.buses._buffer[i].name)));
    p.owned.emplace_back(p.buses.back(), d.buses._buffer[i]);
  }
  const std::string was_refused = p.refused;
  bool uses_ours = false;
  for (uint32_t i = 0; i < d.uses._length && i < 64; ++i) {
    uses_ours = uses_ours || get(d.uses._buffer[i]).starts_with(cfg.name + "/");
  }
  if (p.protocol != canemu_net_PROTOCOL) {
    p.refused = fmt::format("protocol {}, this daemon speaks {}", p.protocol, canemu_net_PROTOCOL);
  } else {
    p.refused = time_problem(p);
  }
  if (p.refused.empty() && uses_ours && stepped() && !stepped_owner.empty()) {
    p.refused = fmt::format(
        "it uses this daemon's buses in stepped time, and this daemon follows daemon {}'s steps "
        "(an owner follows nobody)",
        stepped_owner);
  }
  // The log says what status says: joined, or refused with the reason (and any change).
  const std::string who = fmt::format("daemon {} (time {}, protocol {}, version {})", name,
                                      time_text(p.time_mode, p.scale), p.protocol, p.version);
  if (fresh || p.refused != was_refused) {
    if (p.refused.empty()) {
      log::info("{} {}", who, fresh ? "joined" : "is accepted now");
    } else {
      log::warning("{} refused: {}", who, p.refused);
    }
  }
  // Simulated time there minus here: its time when it wrote this, against ours now, is the
  // offset less the link's delay, so the largest such value is the best estimate.
  const int64_t offset = d.sim_ns - sim.scheduler().now().ns();
  if (!p.offset_known || offset > p.offset_ns) {
    p.offset_ns = offset;
    p.offset_known = true;
  }
  if (fresh && p.refused.empty()) {
    hello(p);
  }
}

void Distributed::Impl::hello(const Peer& p) {
  for (std::size_t i = 0; i < sim.bus_count(); ++i) {
    const BusConfig& b = sim.bus_config(i);
    if (sim.config().remote(b) && b.owner == p.name) {
      try_link(p);  // an owner on this host: the hello and all after it over the link
      canemu_net_Request r{};
      r.kind = canemu_net_REQ_HELLO;
      send_request(p.name, r);
      return;
    }
  }
}

void Distributed::Impl::peer_gone(Peer& p, const std::string& why) {
  if (p.follower && (barrier || running)) {
    step_dropped.push_back(fmt::format("daemon {} ({})", p.name, why));
  }
  p.gone = true;
  p.gone_reason = why;
  p.welcomed = false;
  p.follower = false;
  log::warning("daemon {} is gone: {}", p.name, why);
  drop_hosted_of(p.name, why);
  for (RemoteNode* n : nodes) {
    if (n->owner() == p.name) {
      n->owner_lost();
    }
  }
  if (barrier && waiting.erase(p.name) > 0 && waiting.empty()) {
    run_step();
  }
  if (p.name == stepped_owner && loop != nullptr) {
    loop->steps_failed(fmt::format("daemon {}, whose steps these are, is gone ({})", p.name, why));
  }
}

void Distributed::Impl::owner_up(Peer& p) {
  p.welcomed = true;
  log::info("daemon {} answers: its buses are attached", p.name);
  for (RemoteNode* n : std::vector<RemoteNode*>(nodes)) {
    if (n->owner() == p.name) {
      n->replay();
    }
  }
}

void Distributed::Impl::drop_hosted_of(const std::string& daemon, const std::string& why) {
  std::size_t n = 0;
  for (auto it = hosted.begin(); it != hosted.end();) {
    if (it->first.first == daemon) {
      it = hosted.erase(it);
      ++n;
    } else {
      ++it;
    }
  }
  if (n > 0) {
    log::warning("daemon {}: its {} node{} left this daemon's buses ({})", daemon, n,
                 n == 1 ? "" : "s", why);
  }
}

}  // namespace canemu::daemon

#endif  // CANEMU_HAVE_DDS
