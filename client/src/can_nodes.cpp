// Requests about canemud's simulated CAN nodes (can_nodes.hpp).
#include "canemu/client/can_nodes.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace canemu::client {

std::unique_ptr<ipc::CanNodeRequest> can_node_request(ipc::CanNodeOp op) {
  auto m = std::make_unique<ipc::CanNodeRequest>(ipc::make_message<ipc::CanNodeRequest>());
  m->op = static_cast<uint8_t>(op);
  return m;
}

std::string can_node_load_problem(std::size_t length) {
  if (length <= ipc::kMaxCanNodeLoad) {
    return {};
  }
  return fmt::format("the tables are longer than {} bytes", ipc::kMaxCanNodeLoad);
}

CanNodeRequests can_node_load_requests(const std::string& text, const std::string& source) {
  CanNodeRequests parts;
  std::size_t at = 0;
  do {
    const std::size_t n = std::min(text.size() - at, ipc::kMaxCanNodeText);
    const bool last = at + n == text.size();
    auto m = can_node_request(last ? ipc::CanNodeOp::load : ipc::CanNodeOp::load_part);
    m->length = static_cast<uint32_t>(n);
    std::copy_n(text.begin() + static_cast<std::ptrdiff_t>(at), n, m->text);
    ipc::copy_name(m->source, source);
    parts.push_back(std::move(m));
    at += n;
  } while (at < text.size());
  return parts;
}

std::string name_can_node(ipc::CanNodeRequest& m, const std::string& node) {
  if (node.size() >= sizeof m.name) {
    return fmt::format("{}: a node is named in at most {} characters", node, sizeof m.name - 1);
  }
  ipc::copy_name(m.name, node);
  return {};
}

std::string name_signal(ipc::CanNodeRequest& m, const std::string& bus, const std::string& text) {
  const auto dot = text.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == text.size()) {
    return fmt::format("\"{}\" is not MESSAGE.SIGNAL", text);
  }
  const std::string message = text.substr(0, dot);
  const std::string signal = text.substr(dot + 1);
  if (bus.size() >= sizeof m.name || message.size() >= sizeof m.message ||
      signal.size() >= sizeof m.signal) {
    return fmt::format("a bus is named in at most {} characters, a message and a signal in {}",
                       sizeof m.name - 1, sizeof m.message - 1);
  }
  ipc::copy_name(m.name, bus);
  ipc::copy_name(m.message, message);
  ipc::copy_name(m.signal, signal);
  return {};
}

CanNodeOutcome call_can_nodes(Connection& c, const CanNodeRequests& requests) {
  CanNodeOutcome out;
  for (const auto& m : requests) {
    auto r = c.call<ipc::CanNodeRequest, ipc::CanNodeReply>(*m);
    if (!r) {
      out.reply.reset();
      out.error = r.error();
      return out;
    }
    if (!r->ok) {
      out.reply.reset();
      out.refused = ipc::name_of(r->errors);
      while (out.refused.ends_with('\n')) {
        out.refused.pop_back();
      }
      return out;
    }
    out.reply = std::make_unique<ipc::CanNodeReply>(*r);
  }
  return out;
}

}  // namespace canemu::client
