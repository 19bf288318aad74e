// The world's recorders and bridges: added from the configuration or at run time, found and
// removed by their bus or interface.
#include <sys/socket.h>

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/bridges/dds_bridge.hpp"
#include "canemu/daemon/bridges/lcm_bridge.hpp"
#include "canemu/daemon/world/simulation.hpp"

namespace canemu::daemon {

using namespace canemu::model;

Result<> Simulation::add_recorder(const RecorderConfig& r) {
  const std::size_t bus = *bus_index(r.bus);
  const BusConfig& bc = config_.buses[bus];
  if (buses_[bus].lin != nullptr) {
    auto recorder = Recorder::start_lin(r, bus, *buses_[bus].lin);
    if (!recorder) {
      return fail(Errc::io, recorder.error().text, place(r.line));
    }
    recorders_.push_back(std::move(*recorder));
    return {};
  }
  const auto timing = bus_timing(bus);
  if (!timing) {
    return fail(Errc::bad_bit_timing,
                fmt::format("recorder of {}: no controller runs at {} bit/s", r.bus, bc.bitrate),
                place(r.line));
  }
  auto recorder = Recorder::start(r, bus, nodes_.spare(bus), *timing);
  if (!recorder) {
    return fail(Errc::io, recorder.error().text, place(r.line));
  }
  recorders_.push_back(std::move(*recorder));
  return {};
}

Result<Bridge*> Simulation::add_bridge(const BridgeConfig& b) {
  const auto bus = bus_index(b.bus);
  if (b.kind == "lcm") {
    if (!bus) {
      return fail(Errc::not_found, fmt::format("no bus is named \"{}\"", b.bus));
    }
    if (find_bridge(BridgeKind::lcm, b.bus) != nullptr) {
      return fail(Errc::exists, fmt::format("{} has an LCM bridge already", b.bus));
    }
    const std::string url = b.url.empty() ? std::string(kDefaultLcmUrl) : b.url;
    const std::string prefix =
        b.channel_prefix.empty() ? default_lcm_prefix(b.bus) : b.channel_prefix;
    for (const auto& other : bridges_) {
      if (other->kind() == BridgeKind::lcm && other->options().url == url &&
          other->options().channel_prefix == prefix) {
        return fail(Errc::exists, fmt::format("the LCM bridge of {} uses the channels {}* on {} "
                                              "already (their frames would loop)",
                                              other->options().bus, prefix, url));
      }
    }
    if (auto family = refused_family(AF_INET); !family) {
      return fail(Errc::unavailable, "LCM bridge of " + b.bus + ": " + family.error().text);
    }
    auto transport = open_lcm(b.bus, url, prefix);
    if (!transport) {
      return tl::unexpected(std::move(transport.error()));
    }
    BridgeConfig resolved = b;
    resolved.url = url;
    resolved.channel_prefix = prefix;
    return add_bridge(resolved, std::move(*transport));
  }
  if (b.kind == "dds") {
    if (!bus) {
      return fail(Errc::not_found, fmt::format("no bus is named \"{}\"", b.bus));
    }
    if (find_bridge(BridgeKind::dds, b.bus) != nullptr) {
      return fail(Errc::exists, fmt::format("{} has a DDS bridge already", b.bus));
    }
    DdsOptions o;
    o.domain = b.domain;
    o.partition = b.partition.empty() ? std::string(kDefaultDdsPartition) : b.partition;
    o.topic_prefix = b.channel_prefix.empty() ? default_dds_prefix(b.bus) : b.channel_prefix;
    o.ros2 = b.ros2;
    const std::string locator = dds_locator(o);
    for (const auto& other : bridges_) {
      if (other->kind() == BridgeKind::dds && other->options().channel_prefix == o.topic_prefix) {
        const auto theirs = parse_dds_locator(other->options().url);
        if (theirs && theirs->domain == o.domain && theirs->partition == o.partition) {
          return fail(
              Errc::exists,
              fmt::format(
                  "the DDS bridge of {} uses the topics {}* in domain {}, partition {} already "
                  "(their frames would loop)",
                  other->options().bus, o.topic_prefix, o.domain, o.partition));
        }
      }
    }
    if (auto family = refused_family(AF_INET); !family) {
      return fail(Errc::unavailable, "DDS bridge of " + b.bus + ": " + family.error().text);
    }
    auto transport = open_dds(b.bus, o);
    if (!transport) {
      return tl::unexpected(std::move(transport.error()));
    }
    BridgeConfig resolved = b;
    resolved.url = locator;
    resolved.channel_prefix = o.topic_prefix;
    return add_bridge(resolved, std::move(*transport));
  }
  auto port = open_can_raw(b.interface);
  if (!port) {
    return fail(port.error().code, "bridge to " + port.error().text);
  }
  const bool fd_bus = bus && config_.buses[*bus].kind == BusKind::can_fd;
  const auto mtu = interface_mtu(port->get(), b.interface);
  auto added = add_bridge(b, std::move(*port));
  if (added && mtu) {
    if (const auto warning = mtu_warning(b.interface, b.bus, fd_bus, *mtu)) {
      log::warning("bridge to {}: {}", b.interface, *warning);
    }
  }
  return added;
}

Result<Bridge*> Simulation::add_bridge(const BridgeConfig& b, ipc::UniqueFd port) {
  for (const auto& other : bridges_) {
    if (other->kind() == BridgeKind::socketcan && other->options().interface == b.interface) {
      return fail(Errc::exists, fmt::format("{} is bridged to {} already (its frames would loop)",
                                            b.interface, other->options().bus));
    }
  }
  return add_bridge(b, std::make_unique<SocketCanTransport>(b.interface, std::move(port)));
}

Result<Bridge*> Simulation::add_bridge(const BridgeConfig& b,
                                       std::unique_ptr<BridgeTransport> transport) {
  const auto bus = bus_index(b.bus);
  if (!bus) {
    return fail(Errc::not_found, fmt::format("no bus is named \"{}\"", b.bus));
  }
  const bool lcm = b.kind == "lcm";
  const bool dds = b.kind == "dds";
  const BusConfig& bc = config_.buses[*bus];
  if (bc.kind == BusKind::lin) {
    return fail(Errc::bad_argument,
                fmt::format("\"{}\" is a LIN bus; {} bridges join CAN buses", b.bus,
                            lcm   ? "LCM"
                            : dds ? "DDS"
                                  : "SocketCAN"));
  }
  const auto timing = bus_timing(*bus);
  if (!timing) {
    return fail(Errc::bad_bit_timing,
                fmt::format("no controller runs bus {} at {} bit/s", b.bus, bc.bitrate));
  }
  BridgeOptions o;
  o.kind = lcm ? BridgeKind::lcm : dds ? BridgeKind::dds : BridgeKind::socketcan;
  o.bus = b.bus;
  o.interface = b.interface;
  o.error_frames = lcm || dds || b.error_frames;  // LCM, DDS: always (errors and states)
  o.restart_ms = b.restart_ms;
  o.fd = bc.kind == BusKind::can_fd;
  o.url = b.url;
  o.channel_prefix = b.channel_prefix;
  bridges_.push_back(
      Bridge::start(std::move(o), *bus, nodes_.spare(*bus), *timing, std::move(transport)));
  return bridges_.back().get();
}

Bridge* Simulation::find_bridge(BridgeKind kind, const std::string& name) const {
  for (const auto& b : bridges_) {
    if (b->kind() == kind &&
        (kind == BridgeKind::socketcan ? b->options().interface : b->options().bus) == name) {
      return b.get();
    }
  }
  return nullptr;
}

bool Simulation::remove_bridge(const std::string& interface,
                               const std::function<void(Bridge&)>& before) {
  Bridge* found = find_bridge(BridgeKind::socketcan, interface);
  return found != nullptr && remove(found, before);
}

bool Simulation::remove_bus_bridge(BridgeKind kind, const std::string& bus,
                                   const std::function<void(Bridge&)>& before) {
  Bridge* found = find_bridge(kind, bus);
  return found != nullptr && remove(found, before);
}

bool Simulation::remove(Bridge* bridge, const std::function<void(Bridge&)>& before) {
  for (auto it = bridges_.begin(); it != bridges_.end(); ++it) {
    if (it->get() == bridge) {
      if (before) {
        before(**it);
      }
      bridges_.erase(it);
      return true;
    }
  }
  return false;
}

std::vector<std::string> Simulation::flush_recorders() {
  std::vector<std::string> news;
  for (auto& r : recorders_) {
    if (r->flush()) {
      news.push_back(fmt::format("recorder of {}: {}; frames are being lost ({} so far)",
                                 r->config().bus, r->writer().error(), r->writer().lost()));
    }
  }
  return news;
}

}  // namespace canemu::daemon
