#include "canemu/firmware_model/chips/can_fd/can_fd_controller.hpp"

namespace canemu::model {

CanFdController::CanFdController(CanFdConfig config) : config_(config) {}

void CanFdController::connect(CanBus& bus) {
  bus_ = &bus;
  node_ = bus.attach(*this);
}

void CanFdController::changed() {
  if (bus_ != nullptr) {
    bus_->controller_changed(node_);
  }
}

void CanFdController::configure(const CanFdConfig& config) {
  config_ = config;
  while (rx_.size() > config_.rx_capacity) {
    rx_.pop_back();
  }
  changed();
}

void CanFdController::start() {
  running_ = true;
  changed();
  if (fc_.bus_off() && config_.recovery == BusOffRecovery::on_restart) {
    restart();
  }
}

void CanFdController::stop() {
  running_ = false;
  changed();
}

void CanFdController::restart() {
  if (bus_ != nullptr) {
    bus_->restart(node_);
  }
}

NodeTiming CanFdController::timing() const {
  NodeTiming t;
  t.nominal = config_.nominal;
  t.data = config_.data;
  t.has_data_phase = config_.fd_enabled;
  return t;
}

bool CanFdController::submit(const TxFrame& tx) {
  if (tx_.size() >= config_.tx_capacity || (tx.frame.fd() && !config_.fd_enabled)) {
    return false;
  }
  tx_.push_back(tx);
  if (tx_.size() == 1 && bus_ != nullptr) {
    bus_->tx_changed(node_);
  }
  return true;
}

std::size_t CanFdController::abort_pending() {
  const bool head_on_wire = bus_ != nullptr && bus_->in_flight(node_) && !tx_.empty();
  const std::size_t keep = head_on_wire ? 1 : 0;
  const std::size_t dropped = tx_.size() - keep;
  while (tx_.size() > keep) {
    tx_.pop_back();
  }
  if (head_on_wire) {
    tx_.front().single_shot = true;  // completes, but is not repeated
  }
  if (bus_ != nullptr) {
    bus_->tx_changed(node_);
  }
  return dropped;
}

const TxFrame* CanFdController::pending_tx() {
  if (tx_.empty()) {
    return nullptr;
  }
  // ESI tells the receivers the transmitter's error state when the frame starts.
  TxFrame& head = tx_.front();
  if (head.frame.fd() && head.frame.esi() != fc_.error_passive()) {
    head.frame = head.frame.with_esi(fc_.error_passive());
  }
  return &head;
}

std::optional<ReceivedFrame> CanFdController::receive() {
  if (rx_.empty()) {
    return std::nullopt;
  }
  ReceivedFrame r = rx_.front();
  rx_.pop_front();
  return r;
}

void CanFdController::on_frame(SimTime at, const Frame& frame, bool own) {
  if (rx_.size() >= config_.rx_capacity) {
    ++overruns_;
    overrun_flag_ = true;
    if (listener_ != nullptr) {
      listener_->overrun(at, frame);
    }
    return;
  }
  rx_.push_back(ReceivedFrame{at, frame, own});
  if (listener_ != nullptr) {
    listener_->frame_received(at, frame, own);
  }
}

Frame CanFdController::take_tx() {
  const Frame f = tx_.front().frame;
  tx_.pop_front();
  if (!tx_.empty() && bus_ != nullptr) {
    bus_->tx_changed(node_);
  }
  return f;
}

void CanFdController::on_tx_done(SimTime at) {
  if (tx_.empty()) {
    return;  // nothing was pending (the bus only reports a frame it took from here)
  }
  const Frame f = take_tx();
  if (listener_ != nullptr) {
    listener_->frame_transmitted(at, f);
  }
}

void CanFdController::on_tx_dropped(SimTime at) {
  if (tx_.empty()) {
    return;
  }
  const Frame f = take_tx();
  if (listener_ != nullptr) {
    listener_->transmission_dropped(at, f);
  }
}

void CanFdController::on_arbitration_lost(SimTime at, uint16_t bit, uint16_t /*destuffed_bit*/) {
  if (listener_ != nullptr) {
    listener_->arbitration_lost(at, bit);
  }
}

void CanFdController::on_error(const BusErrorEvent& event) {
  if (listener_ != nullptr) {
    listener_->bus_error(event);
  }
}

void CanFdController::on_state_change(SimTime at, ErrorState state) {
  if (!tx_.empty() && bus_ != nullptr) {
    bus_->tx_changed(node_);  // ESI of the pending frame may change
  }
  if (listener_ != nullptr) {
    listener_->state_changed(at, state, fc_.tec(), fc_.rec());
  }
}

}  // namespace canemu::model
