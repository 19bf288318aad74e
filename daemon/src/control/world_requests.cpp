// Requests that read the world (status, timelines, the lists of devices, recorders, bridges and
// other daemons) and the time step of stepped time.
#include <cstring>
#include <memory>

#include <fmt/format.h>

#include "canemu/daemon/control/control_dispatcher.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu/daemon/world/timeline.hpp"
#include "control/requests.hpp"

namespace canemu::daemon {

void ControlDispatcher::on_status(Session&, const uint8_t* data, uint32_t request_id,
                                  const Send& send) {
  loop_.before_status();
  const auto m = read_as<ipc::StatusRequest>(data);
  auto r = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>(request_id));
  fill_status(sim_, *r, m.first_bus, m.first_node);
  r->time_mode = static_cast<uint8_t>(time_.mode == TimeMode::realtime ? 0
                                      : time_.mode == TimeMode::scaled ? 1
                                                                       : 2);
  r->time_scale = time_.scale;
  r->client_count = loop_.client_count();
  r->ring_bytes = rings_.in_use();
  loop_.fill_pace(*r);
  send_reply(send, *r);
}

void ControlDispatcher::on_time_step(Session&, const uint8_t* data, uint32_t request_id,
                                     const Send& send) {
  const auto m = read_as<ipc::TimeStepRequest>(data);
  if (time_.mode != TimeMode::stepped) {
    error(send, request_id, ipc::ErrorCode::not_stepped,
          fmt::format("time runs {}; steps need --time stepped", to_string(time_)));
    return;
  }
  // At most a minute per request, so one client cannot hold the loop for long.
  if (m.step_ns <= 0 || m.step_ns > int64_t{60} * 1'000'000'000) {
    error(send, request_id, ipc::ErrorCode::bad_argument,
          fmt::format("step of {} ns is outside 1 ns .. 60 s", m.step_ns));
    return;
  }
  if (loop_.defer_step(m.step_ns, request_id)) {
    return;
  }
  loop_.before_step();
  auto r = ipc::make_message<ipc::TimeStepReply>(request_id);
  model::SimScheduler& s = sim_.scheduler();
  r.events_run = s.run_until(s.now() + model::SimDuration(m.step_ns));
  r.sim_time_ns = s.now().ns();
  loop_.after_step();
  send_reply(send, r);
}

void ControlDispatcher::on_timeline(Session&, const uint8_t* data, uint32_t request_id,
                                    const Send& send) {
  loop_.before_status();  // simulated time brought to now
  auto answer = answer_timeline(sim_, read_as<ipc::TimelineRequest>(data), request_id);
  if (auto* e = std::get_if<TimelineError>(&answer)) {
    error(send, request_id, e->code, e->text);
  } else if (auto* t = std::get_if<std::unique_ptr<ipc::TimelineReply>>(&answer)) {
    send_reply(send, **t);
  } else {
    send_reply(send, *std::get<std::unique_ptr<ipc::LoadHistoryReply>>(answer));
  }
}

void ControlDispatcher::on_device_list(Session&, const uint8_t* data, uint32_t request_id,
                                       const Send& send) {
  const auto m = read_as<ipc::DeviceListRequest>(data);
  auto r =
      std::make_unique<ipc::DeviceListReply>(ipc::make_message<ipc::DeviceListReply>(request_id));
  fill_device_list(sim_, *r, m.first);
  send_reply(send, *r);
}

void ControlDispatcher::on_recorder_list(Session&, const uint8_t* data, uint32_t request_id,
                                         const Send& send) {
  loop_.before_status();
  const auto m = read_as<ipc::RecorderListRequest>(data);
  auto r = std::make_unique<ipc::RecorderListReply>(
      ipc::make_message<ipc::RecorderListReply>(request_id));
  fill_recorder_list(sim_, *r, m.first);
  send_reply(send, *r);
}

void ControlDispatcher::on_bridge_list(Session&, const uint8_t* data, uint32_t request_id,
                                       const Send& send) {
  const auto m = read_as<ipc::BridgeListRequest>(data);
  auto r =
      std::make_unique<ipc::BridgeListReply>(ipc::make_message<ipc::BridgeListReply>(request_id));
  fill_bridge_list(sim_, *r, m.first);
  send_reply(send, *r);
}

void ControlDispatcher::on_peer_list(Session&, const uint8_t* data, uint32_t request_id,
                                     const Send& send) {
  const auto m = read_as<ipc::PeerListRequest>(data);
  auto r = std::make_unique<ipc::PeerListReply>(ipc::make_message<ipc::PeerListReply>(request_id));
  fill_peer_list(sim_, *r, m.first_peer, m.first_bus);
  send_reply(send, *r);
}

}  // namespace canemu::daemon
