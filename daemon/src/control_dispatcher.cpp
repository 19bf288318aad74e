#include "canemu/daemon/control_dispatcher.hpp"

#include <cstring>
#include <memory>

#include <unistd.h>

#include <fmt/format.h>

namespace canemu::daemon {

void ControlDispatcher::error(const Send& send, uint32_t request_id, ipc::ErrorCode code,
                              const std::string& text) {
  auto e = ipc::make_message<ipc::ErrorReply>(request_id);
  e.code = static_cast<uint32_t>(code);
  ipc::copy_name(e.message, text);
  send(&e, sizeof e);
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
  switch (type) {
    case ipc::MsgType::hello: {
      ipc::Hello m;
      std::memcpy(&m, data, sizeof m);
      c.greeted = true;
      c.name = ipc::name_of(m.client_name);
      auto r = ipc::make_message<ipc::HelloReply>(request_id);
      r.server_pid = static_cast<uint32_t>(::getpid());
      send(&r, sizeof r);
      return;
    }
    case ipc::MsgType::status_request: {
      if (before_status) {
        before_status();
      }
      auto r = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>(request_id));
      sim_.fill_status(*r);
      r->time_mode = static_cast<uint8_t>(time_.mode == TimeMode::realtime ? 0
                                          : time_.mode == TimeMode::scaled ? 1
                                                                           : 2);
      r->time_scale = time_.scale;
      r->client_count = client_count ? client_count() : 0;
      send(r.get(), sizeof *r);
      return;
    }
    case ipc::MsgType::time_step_request: {
      ipc::TimeStepRequest m;
      std::memcpy(&m, data, sizeof m);
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
      auto r = ipc::make_message<ipc::TimeStepReply>(request_id);
      model::SimScheduler& s = sim_.scheduler();
      r.events_run = s.run_until(s.now() + model::SimDuration(m.step_ns));
      r.sim_time_ns = s.now().ns();
      send(&r, sizeof r);
      return;
    }
    default:
      error(send, request_id, ipc::ErrorCode::unknown_type,
            fmt::format("message type {} is not a request", h.type));
      return;
  }
}

}  // namespace canemu::daemon
