// `canemu restbus` and `canemu signal`: simulated CAN nodes loaded, switched and removed at run
// time, and their signals set and read.
#include <memory>
#include <string>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/control/control_dispatcher.hpp"
#include "canemu/daemon/restbus/can_ecu.hpp"
#include "control/requests.hpp"

namespace canemu::daemon {

namespace {

void list_nodes(const Simulation& sim, ipc::CanNodeReply& r) {
  const auto& nodes = sim.can_nodes();
  r.total = static_cast<uint16_t>(std::min<std::size_t>(nodes.size(), UINT16_MAX));
  for (const SimulatedCanNode& n : nodes) {
    if (r.count == ipc::kMaxCanNodes) {
      break;
    }
    ipc::CanNodeEntry& e = r.nodes[r.count++];
    ipc::copy_name(e.name, n.ecu->name());
    ipc::copy_name(e.bus, sim.bus_config(n.bus).name);
    e.powered = n.ecu->powered() ? 1 : 0;
    e.messages = static_cast<uint32_t>(n.ecu->config().messages.size());
    e.frames = n.ecu->frames_sent();
  }
}

}  // namespace

std::unique_ptr<ipc::CanNodeReply> answer_can_nodes(Simulation& sim, std::string& pending,
                                                    const ipc::CanNodeRequest& m,
                                                    uint32_t request_id) {
  auto r = std::make_unique<ipc::CanNodeReply>(ipc::make_message<ipc::CanNodeReply>(request_id));
  const std::string name = ipc::name_of(m.name);
  std::string error;
  const auto op = static_cast<ipc::CanNodeOp>(m.op);
  switch (op) {
    case ipc::CanNodeOp::list:
      break;
    case ipc::CanNodeOp::load_part:
    case ipc::CanNodeOp::load: {
      const std::string_view text(m.text, std::min<std::size_t>(m.length, sizeof m.text));
      if (pending.size() + text.size() > ipc::kMaxCanNodeLoad) {
        error = fmt::format("the tables are longer than {} bytes", ipc::kMaxCanNodeLoad);
        pending.clear();
        break;
      }
      pending.append(text);
      if (op == ipc::CanNodeOp::load_part) {
        break;
      }
      const std::string source = ipc::printable_name_of(m.source);
      auto loaded = sim.load_can_nodes(pending, source.empty() ? "can nodes" : source);
      pending.clear();
      if (!loaded) {
        for (const std::string& e : loaded.error()) {
          error += e + "\n";
        }
      } else {
        log::info("restbus: {} loaded from {}", fmt::join(*loaded, ", "), source);
      }
      break;
    }
    case ipc::CanNodeOp::power:
      if (auto node = sim.can_node(name); !node) {
        error = node.error().what();
      } else {
        (*node)->power(m.on != 0);
        log::info("restbus: {} switched {}", name, m.on ? "on" : "off");
      }
      break;
    case ipc::CanNodeOp::remove:
      if (auto done = sim.remove_can_node(name); !done) {
        error = done.error().what();
      } else {
        log::info("restbus: {} removed", name);
      }
      break;
    case ipc::CanNodeOp::set_signal:
    case ipc::CanNodeOp::get_signal: {
      const std::string message = ipc::name_of(m.message);
      const std::string signal = ipc::name_of(m.signal);
      auto sender = sim.can_message(name, message);
      if (!sender) {
        error = sender.error().what();
        break;
      }
      restbus::CanEcu& ecu = **sender;
      if (op == ipc::CanNodeOp::set_signal) {
        if (auto set = ecu.set_signal(message, signal, m.value); !set) {
          error = set.error().what();
          break;
        }
      }
      auto value = ecu.get_signal(message, signal);
      if (!value) {
        error = value.error().what();
        break;
      }
      r->value = *value;
      ipc::copy_name(r->node, ecu.name());
      break;
    }
    default:
      error = fmt::format("unknown can node operation {}", m.op);
      break;
  }
  r->ok = error.empty() ? 1 : 0;
  ipc::copy_name(r->errors, error);
  list_nodes(sim, *r);
  return r;
}

void ControlDispatcher::on_can_node(Session& c, const uint8_t* data, uint32_t request_id,
                                    const Send& send) {
  send_reply(send, *answer_can_nodes(sim_, c.can_node_text, read_as<ipc::CanNodeRequest>(data),
                                     request_id));
}

}  // namespace canemu::daemon
