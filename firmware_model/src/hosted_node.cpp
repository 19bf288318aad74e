#include "canemu/firmware_model/hosted_node.hpp"

namespace canemu::model {

void HostedNode::configure(const HostedNodeSettings& settings, ControllerEvents* sink,
                           TxSource source) {
  settings_ = settings;
  sink_ = nullptr;  // the counter reset below reports a state nobody asked about
  ++generation_;
  running_ = false;
  tx_loaded_ = false;
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
  tx_loaded_ = false;
  ++generation_;
  go_off_bus();
}

void HostedNode::stop() {
  go_offline();
  sink_ = nullptr;
  source_ = nullptr;
}

void HostedNode::restart() {
  if (running_ && controller().confinement().bus_off()) {
    leave_bus_off(settings_);
  }
}

void HostedNode::load_next() {
  if (!running_ || tx_loaded_ || !source_ || !buffer_free()) {
    return;
  }
  std::optional<TxFrame> next = source_();
  if (!next) {
    return;
  }
  tx_loaded_ = true;
  load(*next);
}

void HostedNode::frame_received(SimTime at, const Frame& frame, bool own) {
  release_received();  // the driver copies the frame out at once
  if (sink_ != nullptr) {
    sink_->frame_received(at, frame, own);
  }
}

void HostedNode::frame_transmitted(SimTime at, const Frame& frame) {
  tx_loaded_ = false;
  if (sink_ != nullptr) {
    sink_->frame_transmitted(at, frame);
  }
  load_next();
}

void HostedNode::transmission_dropped(SimTime at, const Frame& frame) {
  tx_loaded_ = false;
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
  if (state == ErrorState::bus_off && running_ && settings_.restart_delay.ns() > 0) {
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
  if (sink_ != nullptr) {
    sink_->arbitration_lost(at, bit);
  }
}

}  // namespace canemu::model
