#include "canemu/firmware_model/chips/hosted_node.hpp"

#include <utility>

namespace canemu::model {

void HostedNode::configure(const HostedNodeSettings& settings, ControllerEvents* sink,
                           TxSource source) {
  settings_ = settings;
  sink_ = nullptr;  // the counter reset below reports a state nobody asked about
  ++generation_;
  running_ = false;
  tx_loaded_ = 0;
  babble_.reset();
  babble_loaded_ = false;
  program(settings);
  bus_.reset_stats(node());
  sink_ = sink;
  source_ = std::move(source);
}

void HostedNode::go_online() {
  running_ = true;
  go_on_bus(settings_);
  if (controller().confinement().bus_off()) {
    leave_bus_off(settings_);
  }
  load_next();
}

void HostedNode::go_offline() {
  running_ = false;
  tx_loaded_ = 0;
  babble_loaded_ = false;
  ++generation_;
  go_off_bus();
}

void HostedNode::stop() {
  go_offline();
  sink_ = nullptr;
  source_ = nullptr;
  released();
}

void HostedNode::restart() {
  if (running_ && controller().confinement().bus_off()) {
    leave_bus_off(settings_);
  }
}

bool HostedNode::babble(const Frame& frame, SimTime until) {
  if (!running_) {
    return false;
  }
  babble_ = TxFrame{frame, false, false};
  babble_until_ = until;
  const uint64_t generation = generation_;
  scheduler_.schedule_at(until, [this, generation](SimTime) {
    if (generation == generation_) {
      end_babble();
    }
  });
  load_next();
  return true;
}

void HostedNode::end_babble() {
  if (!babble_ || now() < babble_until_) {
    return;  // a later babble replaced this one
  }
  babble_.reset();
  if (!babble_loaded_) {
    return;
  }
  if (frame_on_wire()) {
    abort_tx();  // completes, or fails, without a repetition; its end is reported then
    return;
  }
  abort_tx();  // gone: the SJA1000 reports the drop at once, the FD controller does not
  if (babble_loaded_) {
    babble_loaded_ = false;
    tx_loaded_ = 0;
  }
  load_next();
}

void HostedNode::load_next() {
  if (babble_ && now() >= babble_until_) {
    babble_.reset();  // ended while the node was off the bus
  }
  if (babble_) {
    if (running_ && tx_loaded_ == 0 && buffer_free()) {
      tx_loaded_ = 1;
      babble_loaded_ = true;
      load(*babble_);
    }
    return;
  }
  while (running_ && tx_loaded_ < tx_window() && buffer_free() && source_) {
    std::optional<TxFrame> next = source_();
    if (!next) {
      return;
    }
    ++tx_loaded_;
    load(*next);
  }
}

void HostedNode::frame_received(SimTime at, const Frame& frame, bool own) {
  release_received();  // the driver copies the frame out at once
  if (sink_ != nullptr) {
    sink_->frame_received(at, frame, own);
  }
}

void HostedNode::frame_transmitted(SimTime at, const Frame& frame) {
  tx_loaded_ -= tx_loaded_ > 0 ? 1 : 0;
  if (std::exchange(babble_loaded_, false)) {
    load_next();
    return;
  }
  if (sink_ != nullptr) {
    sink_->frame_transmitted(at, frame);
  }
  load_next();
}

void HostedNode::transmission_dropped(SimTime at, const Frame& frame) {
  tx_loaded_ -= tx_loaded_ > 0 ? 1 : 0;
  if (std::exchange(babble_loaded_, false)) {
    load_next();
    return;
  }
  if (sink_ != nullptr) {
    sink_->transmission_dropped(at, frame);
  }
  load_next();
}

void HostedNode::bus_error(const BusErrorEvent& event) {
  if (sink_ != nullptr) {
    sink_->bus_error(event);
  }
}

void HostedNode::state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) {
  if (sink_ != nullptr) {
    sink_->state_changed(at, state, tec, rec);
  }
  if (state == ErrorState::bus_off && running_ && settings_.restart_delay.ns() > 0 &&
      !restarts_itself()) {
    const uint64_t generation = generation_;
    scheduler_.schedule_at(at + settings_.restart_delay, [this, generation](SimTime) {
      if (generation == generation_) {
        restart();
      }
    });
  }
  if (state != ErrorState::bus_off) {
    load_next();  // back from bus-off: the buffer may take frames again
  }
}

void HostedNode::overrun(SimTime at, const Frame& lost) {
  if (sink_ != nullptr) {
    sink_->overrun(at, lost);
  }
}

void HostedNode::arbitration_lost(SimTime at, uint16_t bit) {
  if (sink_ != nullptr && !babble_loaded_) {
    sink_->arbitration_lost(at, bit);
  }
  read_arbitration_capture();
}

}  // namespace canemu::model
