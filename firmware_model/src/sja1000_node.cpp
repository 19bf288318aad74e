#include "canemu/firmware_model/sja1000_node.hpp"

namespace canemu::model {

using namespace sja1000;

Sja1000Node::Sja1000Node(SimScheduler& scheduler, CanBus& bus) : scheduler_(scheduler), bus_(bus) {
  chip_.connect(bus);
  chip_.set_listener(this);
}

void Sja1000Node::start(const Sja1000NodeSettings& settings, ControllerEvents* sink,
                        TxSource source) {
  settings_ = settings;
  sink_ = nullptr;  // the counter writes below report a state nobody asked about
  ++generation_;
  chip_.write(MOD, MOD_RM);
  chip_.write(TXERR, 0);
  chip_.write(RXERR, 0);
  chip_.write(BTR0, settings.btr0);
  chip_.write(BTR1, settings.btr1);
  for (uint8_t k = 0; k < 4; ++k) {
    chip_.write(static_cast<uint8_t>(AMR0 + k), 0xFF);  // accept everything
  }
  bus_.reset_stats(chip_.node());
  sink_ = sink;
  source_ = std::move(source);
  running_ = true;
  tx_loaded_ = false;
  chip_.write(MOD, settings.listen_only ? MOD_LOM : 0);
  load_next();
}

void Sja1000Node::stop() {
  running_ = false;
  sink_ = nullptr;
  source_ = nullptr;
  tx_loaded_ = false;
  ++generation_;
  chip_.write(MOD, MOD_RM);
}

void Sja1000Node::restart() {
  if (running_ && chip_.confinement().bus_off()) {
    chip_.write(MOD, settings_.listen_only ? MOD_LOM : 0);
  }
}

void Sja1000Node::load_next() {
  if (!running_ || tx_loaded_ || !source_ || (chip_.read(SR) & SR_TBS) == 0) {
    return;
  }
  std::optional<TxFrame> next = source_();
  if (!next) {
    return;
  }
  std::array<uint8_t, 13> bytes;
  const std::size_t n = pack_frame(next->frame, bytes);
  for (std::size_t k = 0; k < n; ++k) {
    chip_.write(static_cast<uint8_t>(FRAME + k), bytes[k]);
  }
  uint8_t cmr = next->self_reception ? CMR_SRR : CMR_TR;
  if (next->single_shot) {
    cmr |= CMR_AT;
  }
  tx_loaded_ = true;
  chip_.write(CMR, cmr);
}

void Sja1000Node::frame_received(SimTime at, const Frame& frame, bool own) {
  chip_.write(CMR, CMR_RRB);  // the driver copies the frame out at once
  if (sink_ != nullptr) {
    sink_->frame_received(at, frame, own);
  }
}

void Sja1000Node::frame_transmitted(SimTime at, const Frame& frame) {
  tx_loaded_ = false;
  if (sink_ != nullptr) {
    sink_->frame_transmitted(at, frame);
  }
  load_next();
}

void Sja1000Node::transmission_dropped(SimTime at, const Frame& frame) {
  tx_loaded_ = false;
  if (sink_ != nullptr) {
    sink_->transmission_dropped(at, frame);
  }
  load_next();
}

void Sja1000Node::bus_error(const BusErrorEvent& event) {
  if (sink_ != nullptr) {
    sink_->bus_error(event);
  }
}

void Sja1000Node::state_changed(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) {
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
}

void Sja1000Node::overrun(SimTime at, const Frame& lost) {
  if (sink_ != nullptr) {
    sink_->overrun(at, lost);
  }
}

void Sja1000Node::arbitration_lost(SimTime at, uint16_t bit) {
  if (sink_ != nullptr) {
    sink_->arbitration_lost(at, bit);
  }
}

}  // namespace canemu::model
