#include "canemu/firmware_model/chips/lin/lin_controller.hpp"

namespace canemu::model::lin {

LinController::LinController(LinBus& bus) : bus_(bus), id_(bus.attach(*this)) {}

LinController::~LinController() {
  bus_.detach(id_);
}

void LinController::configure(Mode mode, uint32_t bitrate) {
  online_ = false;
  mode_ = mode;
  bitrate_ = bitrate;
  detected_ = 0;
}

void LinController::reset() {
  online_ = false;
  bus_.withdraw(id_);
  clear_responses();
}

void LinController::start() {
  online_ = true;
}

void LinController::stop() {
  online_ = false;
  bus_.withdraw(id_);
}

void LinController::set_response(uint8_t id, const Response& response) {
  table_[id & kMaxId] = response;
}

LinController::SendResult LinController::check(bool master_only) const {
  if (!online_) {
    return SendResult::offline;
  }
  if (master_only && mode_ != Mode::master) {
    return SendResult::not_master;
  }
  if (bus_.pending(id_)) {
    return SendResult::busy;
  }
  return SendResult::ok;
}

LinController::SendResult LinController::send_header(uint8_t id) {
  const SendResult r = check(true);
  if (r == SendResult::ok) {
    bus_.send_header(id_, id);
  }
  return r;
}

LinController::SendResult LinController::send_frame(uint8_t id, const Response& response) {
  const SendResult r = check(true);
  if (r == SendResult::ok) {
    bus_.send_frame(id_, id, response);
  }
  return r;
}

LinController::SendResult LinController::send_sleep() {
  const SendResult r = check(true);
  if (r == SendResult::ok) {
    bus_.send_sleep(id_);
  }
  return r;
}

LinController::SendResult LinController::send_wakeup() {
  const SendResult r = check(false);
  if (r == SendResult::ok) {
    bus_.send_wakeup(id_, kWakeupPulse);
  }
  return r;
}

std::optional<Response> LinController::respond(uint8_t id) {
  if (!online_) {
    return std::nullopt;
  }
  return table_[id & kMaxId];
}

void LinController::on_lin_event(const Event& e) {
  if (!online_) {
    return;
  }
  if (bitrate_ == 0 && e.bitrate != 0) {
    detected_ = e.bitrate;
  }
  if (listener_ != nullptr) {
    listener_->on_lin(e, e.kind == Event::Kind::frame && e.responded(id_));
  }
}

}  // namespace canemu::model::lin
