// The session's own requests: hello, the notifications it subscribes to, the list of clients.
#include <cstring>
#include <memory>

#include <fmt/format.h>

#include <unistd.h>
#include "canemu/daemon/control/control_dispatcher.hpp"
#include "control/requests.hpp"

namespace canemu::daemon {

void ControlDispatcher::on_hello(Session& c, const uint8_t* data, uint32_t request_id,
                                 const Send& send) {
  const auto m = read_as<ipc::Hello>(data);
  c.greeted = true;
  c.name = ipc::printable_name_of(m.client_name);  // shown in tables, JSON and logs
  auto r = ipc::make_message<ipc::HelloReply>(request_id);
  r.server_pid = static_cast<uint32_t>(::getpid());
  send_reply(send, r);
}

void ControlDispatcher::on_subscribe(Session& c, const uint8_t* data, uint32_t request_id,
                                     const Send& send) {
  const auto m = read_as<ipc::SubscribeRequest>(data);
  if (m.events & ~ipc::kEventDevices) {
    error(send, request_id, ipc::ErrorCode::bad_argument,
          fmt::format("unknown events {:#x}", m.events));
    return;
  }
  c.events = m.events;
  auto r = ipc::make_message<ipc::SubscribeReply>(request_id);
  r.events = c.events;
  send_reply(send, r);
}

void ControlDispatcher::on_client_list(Session&, const uint8_t* data, uint32_t request_id,
                                       const Send& send) {
  const auto m = read_as<ipc::ClientListRequest>(data);
  auto r =
      std::make_unique<ipc::ClientListReply>(ipc::make_message<ipc::ClientListReply>(request_id));
  r->first = m.first;
  loop_.fill_clients(*r);
  send_reply(send, *r);
}

}  // namespace canemu::daemon
