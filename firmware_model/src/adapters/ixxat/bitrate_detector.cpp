#include "canemu/firmware_model/adapters/ixxat/bitrate_detector.hpp"

#include <utility>

namespace canemu::model::ixxat {

BitrateDetector::BitrateDetector(SimScheduler& scheduler, HostedNode& node,
                                 ControllerEvents& events, std::function<void()> finished)
    : scheduler_(scheduler), node_(node), events_(events), finished_(std::move(finished)) {}

BitrateDetector::~BitrateDetector() {
  if (event_ != 0) {
    scheduler_.cancel(event_);
  }
}

void BitrateDetector::start(std::vector<HostedNodeSettings> entries, SimDuration per_entry) {
  for (HostedNodeSettings& s : entries) {
    s.listen_only = true;  // the detector never disturbs the traffic it listens to
  }
  running_ = Running{std::move(entries), per_entry};
  result_ = Result{VCI_E_PENDING, 0};
  try_entry(0);
}

void BitrateDetector::start_endless(std::vector<HostedNodeSettings> entries) {
  start(std::move(entries), SimDuration{});
}

void BitrateDetector::cancel() {
  if (running_) {
    finish(VCI_E_ABORT, 0);
  }
}

void BitrateDetector::frame_received() {
  running_->found = true;  // this timing decodes the traffic
  next_entry();
}

void BitrateDetector::bus_error() {
  next_entry();  // this timing does not decode the traffic
}

void BitrateDetector::try_entry(std::size_t i) {
  const bool endless = running_->per_entry.ns() == 0;
  if (i >= running_->entries.size()) {
    if (!endless) {
      finish(VCI_E_TIMEOUT, 0);
      return;
    }
    i = 0;
  }
  running_->current = i;
  running_->moving_on = false;
  node_.configure(running_->entries[i], &events_, [] { return std::optional<TxFrame>(); });
  node_.go_online();
  if (event_ != 0) {
    scheduler_.cancel(event_);
    event_ = 0;
  }
  if (!endless) {
    event_ = scheduler_.schedule_at(scheduler_.now() + running_->per_entry, *this, 0);
  }
}

void BitrateDetector::next_entry() {
  if (running_->moving_on) {
    return;
  }
  // Not from inside the bus's callbacks: the next entry (or the end) comes in an event of its
  // own, at this instant.
  running_->moving_on = true;
  if (event_ != 0) {
    scheduler_.cancel(event_);
  }
  event_ = scheduler_.schedule_at(scheduler_.now(), *this, 0);
}

void BitrateDetector::on_event(SimTime, uint64_t) {
  event_ = 0;
  if (running_ && running_->found) {
    finish(VCI_OK, static_cast<uint32_t>(running_->current));
  } else if (running_) {
    try_entry(running_->current + 1);
  }
}

void BitrateDetector::finish(HRESULT hr, uint32_t index) {
  if (event_ != 0) {
    scheduler_.cancel(event_);
    event_ = 0;
  }
  running_.reset();
  result_ = Result{hr, index};
  node_.go_offline();
  finished_();
}

}  // namespace canemu::model::ixxat
