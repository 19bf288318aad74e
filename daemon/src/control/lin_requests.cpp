// `canemu lin`: simulated LIN nodes loaded, switched, stopped and removed at run time.
#include <algorithm>
#include <memory>
#include <string>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/control/control_dispatcher.hpp"
#include "control/requests.hpp"

namespace canemu::daemon {

std::unique_ptr<ipc::LinNodeReply> answer_lin_nodes(Simulation& sim, const ipc::LinNodeRequest& m,
                                                    uint32_t request_id) {
  auto r = std::make_unique<ipc::LinNodeReply>(ipc::make_message<ipc::LinNodeReply>(request_id));
  const std::string name = ipc::name_of(m.name);
  std::string error;
  switch (static_cast<ipc::LinNodeOp>(m.op)) {
    case ipc::LinNodeOp::list:
      break;
    case ipc::LinNodeOp::load: {
      const std::string source = ipc::printable_name_of(m.source);
      const std::string_view text(m.text, std::min<std::size_t>(m.length, sizeof m.text));
      auto loaded = sim.load_lin_nodes(text, source.empty() ? "lin nodes" : source);
      if (!loaded) {
        for (const std::string& e : loaded.error()) {
          error += e + "\n";
        }
      } else {
        log::info("lin: {} loaded from {}", fmt::join(*loaded, ", "), source);
      }
      break;
    }
    case ipc::LinNodeOp::power:
      if (auto done = sim.power_lin_node(name, m.on != 0); !done) {
        error = done.error().what();
      } else {
        log::info("lin: {} switched {}", name, m.on ? "on" : "off");
      }
      break;
    case ipc::LinNodeOp::schedule: {
      const std::string table = ipc::name_of(m.table);
      if (auto done = sim.run_lin_schedule(name, table); !done) {
        error = done.error().what();
      } else {
        log::info("lin: {} {}", name,
                  table.empty() ? std::string("stops its schedule")
                                : fmt::format("runs schedule table {}", table));
      }
      break;
    }
    case ipc::LinNodeOp::remove:
      if (auto done = sim.remove_lin_node(name); !done) {
        error = done.error().what();
      } else {
        log::info("lin: {} removed", name);
      }
      break;
    default:
      error = fmt::format("unknown lin node operation {}", m.op);
      break;
  }
  r->ok = error.empty() ? 1 : 0;
  ipc::copy_name(r->errors, error);
  const auto& nodes = sim.lin_nodes();
  r->total = static_cast<uint16_t>(std::min<std::size_t>(nodes.size(), UINT16_MAX));
  for (const SimulatedLinNode& n : nodes) {
    if (r->count == ipc::kMaxLinNodes) {
      break;
    }
    ipc::LinNodeEntry& e = r->nodes[r->count++];
    ipc::copy_name(e.name, n.name);
    ipc::copy_name(e.bus, sim.bus_config(n.bus).name);
    ipc::copy_name(e.schedule, n.ecu->running_schedule());
    e.powered = n.ecu->powered() ? 1 : 0;
    e.headers = n.ecu->counters().headers;
    e.responses = n.ecu->counters().responses;
  }
  return r;
}

void ControlDispatcher::on_lin_node(Session&, const uint8_t* data, uint32_t request_id,
                                    const Send& send) {
  send_reply(send, *answer_lin_nodes(sim_, read_as<ipc::LinNodeRequest>(data), request_id));
}

}  // namespace canemu::daemon
