#include "canemu/firmware_model/bus/fault_confinement.hpp"

#include <algorithm>

namespace canemu::model {

ErrorState FaultConfinement::state() const {
  if (bus_off_) {
    return ErrorState::bus_off;
  }
  if (tec_ >= kErrorPassiveLimit || rec_ >= kErrorPassiveLimit) {
    return ErrorState::passive;
  }
  if (tec_ >= warning_limit_ || rec_ >= warning_limit_) {
    return ErrorState::warning;
  }
  return ErrorState::active;
}

void FaultConfinement::add_tec(uint16_t n) {
  if (bus_off_) {
    return;
  }
  ++changes_.n;
  tec_ = static_cast<uint16_t>(tec_ + n);
  if (tec_ >= kBusOffLimit) {
    bus_off_ = true;
    recovering_ = false;
    sequences_seen_ = 0;
  }
}

void FaultConfinement::add_rec(uint16_t n) {
  if (bus_off_) {
    return;
  }
  ++changes_.n;
  // The receive counter has no upper state; it stops at the width of the controller's counter.
  rec_ = static_cast<uint16_t>(std::min<uint32_t>(uint32_t{rec_} + n, rec_limit_));
}

bool FaultConfinement::recessive_sequences(uint32_t n) {
  if (!recovering()) {
    return false;
  }
  sequences_seen_ = std::min(kBusOffRecoverySequences, sequences_seen_ + n);
  if (sequences_seen_ < kBusOffRecoverySequences) {
    return false;
  }
  reset();
  return true;
}

void FaultConfinement::set_counters(uint16_t tec, uint16_t rec) {
  ++changes_.n;
  tec_ = tec;
  rec_ = std::min(rec, rec_limit_);
  bus_off_ = tec_ >= kBusOffLimit;
  recovering_ = false;
  sequences_seen_ = 0;
}

void FaultConfinement::reset() {
  ++changes_.n;
  tec_ = 0;
  rec_ = 0;
  bus_off_ = false;
  recovering_ = false;
  sequences_seen_ = 0;
}

}  // namespace canemu::model
