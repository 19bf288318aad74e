// The control protocol's front door: every packet checked, a client that has not said hello
// turned away, and each request type handed to its area's handler.
#include "canemu/daemon/control/control_dispatcher.hpp"

#include <cstring>
#include <utility>

#include <fmt/format.h>

#include "control/requests.hpp"

namespace canemu::daemon {

void ControlDispatcher::error(const Send& send, uint32_t request_id, ipc::ErrorCode code,
                              const std::string& text) {
  auto e = ipc::make_message<ipc::ErrorReply>(request_id);
  e.code = static_cast<uint32_t>(code);
  ipc::copy_name(e.message, text);
  send(&e, sizeof e, {});
}

ControlDispatcher::Handler ControlDispatcher::handler_for(ipc::MsgType type) {
  // Each area's requests are answered in a file of its own (docs in control_dispatcher.hpp).
  static const std::pair<ipc::MsgType, Handler> kHandlers[] = {
      {ipc::MsgType::hello, &ControlDispatcher::on_hello},
      {ipc::MsgType::status_request, &ControlDispatcher::on_status},
      {ipc::MsgType::time_step_request, &ControlDispatcher::on_time_step},
      {ipc::MsgType::open_channel_request, &ControlDispatcher::on_open_channel},
      {ipc::MsgType::close_channel_request, &ControlDispatcher::on_close_channel},
      {ipc::MsgType::channel_status_request, &ControlDispatcher::on_channel_status},
      {ipc::MsgType::lin_node_request, &ControlDispatcher::on_lin_node},
      {ipc::MsgType::can_node_request, &ControlDispatcher::on_can_node},
      {ipc::MsgType::timeline_request, &ControlDispatcher::on_timeline},
      {ipc::MsgType::device_list_request, &ControlDispatcher::on_device_list},
      {ipc::MsgType::recorder_list_request, &ControlDispatcher::on_recorder_list},
      {ipc::MsgType::bridge_add_request, &ControlDispatcher::on_bridge_add},
      {ipc::MsgType::bridge_remove_request, &ControlDispatcher::on_bridge_remove},
      {ipc::MsgType::bridge_restart_request, &ControlDispatcher::on_bridge_restart},
      {ipc::MsgType::bridge_list_request, &ControlDispatcher::on_bridge_list},
      {ipc::MsgType::peer_list_request, &ControlDispatcher::on_peer_list},
      {ipc::MsgType::client_list_request, &ControlDispatcher::on_client_list},
      {ipc::MsgType::fault_load_request, &ControlDispatcher::on_fault_load},
      {ipc::MsgType::fault_list_request, &ControlDispatcher::on_fault_list},
      {ipc::MsgType::fault_clear_request, &ControlDispatcher::on_fault_clear},
      {ipc::MsgType::subscribe_request, &ControlDispatcher::on_subscribe},
      {ipc::MsgType::vci_request, &ControlDispatcher::on_vci},
      {ipc::MsgType::xcan_request, &ControlDispatcher::on_xcan},
      {ipc::MsgType::slcan_request, &ControlDispatcher::on_slcan},
  };
  for (const auto& [t, h] : kHandlers) {
    if (t == type) {
      return h;
    }
  }
  return nullptr;
}

void ControlDispatcher::handle(Session& c, const uint8_t* data, std::size_t size,
                               const Send& send) {
  uint32_t request_id = 0;
  if (size >= sizeof(ipc::MsgHeader)) {
    ipc::MsgHeader h;
    std::memcpy(&h, data, sizeof h);
    request_id = h.request_id;
  }
  const ipc::ErrorCode check = ipc::check_message(data, size);
  if (check != ipc::ErrorCode::none) {
    error(send, request_id, check, fmt::format("rejected a {}-byte message", size));
    return;
  }
  ipc::MsgHeader h;
  std::memcpy(&h, data, sizeof h);
  const auto type = static_cast<ipc::MsgType>(h.type);
  if (!c.greeted && type != ipc::MsgType::hello) {
    error(send, request_id, ipc::ErrorCode::not_hello, "say hello first");
    return;
  }
  const Handler handler = handler_for(type);
  if (handler == nullptr) {
    error(send, request_id, ipc::ErrorCode::unknown_type,
          fmt::format("message type {} is not a request", h.type));
    return;
  }
  (this->*handler)(c, data, request_id, send);
}

// ---- the adapters' own requests: their services answer them ----

void ControlDispatcher::on_vci(Session& c, const uint8_t* data, uint32_t, const Send& send) {
  vci_.handle(c.vci, read_as<ipc::VciRequest>(data), send);
}

void ControlDispatcher::on_xcan(Session& c, const uint8_t* data, uint32_t, const Send& send) {
  xcan_.handle(c.xcan, read_as<ipc::XcanRequest>(data), send);
}

void ControlDispatcher::on_slcan(Session& c, const uint8_t* data, uint32_t, const Send& send) {
  slcan_.handle(c.slcan, read_as<ipc::SlcanRequest>(data), send);
}

void ControlDispatcher::end_session(Session& session) {
  for (auto& [id, sc] : session.channels) {
    loop_.unwatch(*sc.channel);
  }
  session.channels.clear();
  vci_.close_all(session.vci);
  xcan_.close_all(session.xcan);
  slcan_.close_all(session.slcan);
}

}  // namespace canemu::daemon
