#include "canemu/firmware_model/bus/error_phase.hpp"

#include <algorithm>

namespace canemu::model {

namespace {

constexpr uint32_t kErrorFlagBits = 6;
constexpr uint32_t kErrorDelimiterBits = 8;
// A hold keeps everybody waiting for recessive bits for as long as it lasts, up to this many
// bit times per activity (docs/bus-engine.md).
constexpr uint32_t kMaxHeldBits = 1'000'000;

}  // namespace

uint16_t ErrorPhase::stuffed_end(const EncodedFrame& e) {
  return e.fd ? e.field_begin(Field::stuff_count) : e.crc_delimiter_index;
}

ErrorPhase::ErrorPhase(const Setup& setup, std::span<const BusParticipant> parts)
    : setup_(setup),
      parts_(parts),
      e_(setup.frame),
      // Bit times: the frame's own (with its rate switch) up to the first detection, then the
      // nominal rate: error flags and delimiters always run at the nominal rate.
      error_start_(e_ != nullptr ? setup.sof + frame_prefix_duration(*e_, setup.nominal, setup.data,
                                                                     setup.first_bit)
                                 : setup.sof),
      bit_time_(setup.nominal.bits_duration(1)),
      st_(parts.size()) {
  if (e_ != nullptr) {
    length_ = e_->length;
    ack_slot_ = static_cast<uint16_t>(e_->crc_delimiter_index + 1);
    stuff_end_ = stuffed_end(*e_);
  }
  for (std::size_t k = 0; k < parts.size(); ++k) {
    st_[k].is_tx = parts[k].transmitter;
    any_ack_ = any_ack_ || (!parts[k].transmitter && parts[k].acks);
  }
}

SimTime ErrorPhase::bit_end(uint32_t i) const {
  if (e_ != nullptr && i < setup_.first_bit) {
    return setup_.sof + frame_prefix_duration(*e_, setup_.nominal, setup_.data, i + 1);
  }
  return error_start_ + SimDuration(bit_time_.ns() * (int64_t{i} - setup_.first_bit + 1));
}

bool ErrorPhase::held(uint32_t i) const {
  const SimTime end = bit_end(i);
  const SimTime start = end - (e_ != nullptr && i < setup_.first_bit ? SimDuration(0) : bit_time_);
  for (const auto& [from, duration] : setup_.holds) {
    if (from < end && from + duration > start) {
      return true;
    }
  }
  return false;
}

bool ErrorPhase::frame_bit(uint32_t i) const {
  if (e_ == nullptr || i >= length_) {
    return true;
  }
  if (i == ack_slot_) {
    return !any_ack_;
  }
  return e_->level_at(i);
}

bool ErrorPhase::driven_level(std::size_t k, uint32_t i) const {
  const State& s = st_[k];
  const BusParticipant& p = parts_[k];
  if (s.phase == Phase::frame) {
    if (s.is_tx && p.bits != nullptr && i < p.bits->length) {
      return p.bits->level_at(i);
    }
    return !(!s.is_tx && p.acks && i == ack_slot_ && e_ != nullptr);
  }
  return !(s.phase == Phase::flag && !p.passive && i < s.flag_start + kErrorFlagBits);
}

ErrorPhase::Outcome ErrorPhase::run() {
  const uint32_t first_bit = setup_.first_bit;
  // The bus before the first detection is the frame as sent, with the ACK if anybody gives it.
  bool last_level = true;
  for (uint32_t i = 0; i < first_bit; ++i) {
    const bool b = frame_bit(i);
    run_ = b == last_level ? run_ + 1 : 1;
    last_level = b;
  }

  const uint32_t max_bits = 4096 + static_cast<uint32_t>(length_);
  uint32_t last_dominant = first_bit;  // last bit the bus was dominant
  uint32_t i = first_bit;
  for (;; ++i) {
    // What each node drives, wired-AND.
    bool bus = true;
    for (std::size_t k = 0; k < parts_.size(); ++k) {
      if (parts_[k].drives) {
        bus = bus && driven_level(k, i);
      }
    }
    if (held(i)) {
      bus = false;
    }
    const bool prev_bus = last_level;
    run_ = bus == last_level ? run_ + 1 : 1;
    last_level = bus;
    if (!bus) {
      last_dominant = i;
    }

    // What each node makes of it.
    bool all_done = true;
    for (std::size_t k = 0; k < parts_.size(); ++k) {
      switch (st_[k].phase) {
        case Phase::frame:
          in_frame(k, i, bus, prev_bus);
          break;
        case Phase::flag:
          in_flag(k, i, bus);
          break;
        case Phase::wait_recessive:
          waiting_recessive(k, i, bus);
          break;
        case Phase::delimiter:
          in_delimiter(k, bus);
          break;
        case Phase::done:
          break;
      }
      all_done = all_done && st_[k].phase == Phase::done;
    }
    if ((all_done && !held(i + 1)) || (i >= max_bits && !held(i + 1)) ||
        i >= max_bits + kMaxHeldBits) {
      break;
    }
  }

  // The activity ends with the last node's delimiter; a hold keeps the bus until it ends.
  Outcome out;
  out.end_bit = i;
  out.end = bit_end(i);
  out.ifs_end = out.end + setup_.nominal.bits_duration(kIntermissionBits);
  out.dominant_end = bit_end(last_dominant);
  std::stable_sort(actions_.begin(), actions_.end(),
                   [](const Action& a, const Action& b) { return a.at < b.at; });
  out.actions = std::move(actions_);
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    if (parts_[k].transmitter) {
      // A transmitter that lost arbitration did not send its frame, whatever it saw after.
      out.transmitters.push_back(Outcome::Transmitter{
          parts_[k].id, st_[k].is_tx && !st_[k].detected && st_[k].phase == Phase::done,
          !st_[k].is_tx});
    }
  }
  return out;
}

void ErrorPhase::detect(std::size_t k, uint32_t i, CanErrorType type, bool count) {
  State& s = st_[k];
  const BusParticipant& p = parts_[k];
  s.detected = true;
  s.phase = Phase::flag;
  s.flag_start = i + 1;
  s.equal_run = 0;
  s.dominant_run = 0;
  // Rule 3, exception a: an error-passive transmitter's ACK error counts only if it sees a
  // dominant bit during its passive flag (in_flag()).
  const bool passive_ack = s.is_tx && p.passive && type == CanErrorType::ack;
  s.passive_ack_pending = passive_ack;
  const EncodedFrame* seen = s.is_tx && p.bits != nullptr ? p.bits : e_;
  const bool inside = seen != nullptr && i < seen->length;
  actions_.push_back(Action{
      .at = bit_end(i),
      .node = p.id,
      .kind = Action::Kind::error,
      .type = type,
      .role = s.is_tx ? ErrorRole::transmitter : ErrorRole::receiver,
      .bit = static_cast<uint16_t>(i),
      .count = count && p.drives && !passive_ack,
      .in_frame = e_ != nullptr,
      .field = inside ? seen->field_at(i) : Field::eof,
      .destuffed_bit =
          inside ? seen->destuffed_index(static_cast<uint16_t>(i)) : static_cast<uint16_t>(i),
      .extended = seen != nullptr && seen->field_begin(Field::srr) < seen->length,
      .data_phase = inside && seen->brs && i > seen->brs_index && i < seen->crc_delimiter_index,
  });
}

void ErrorPhase::in_frame(std::size_t k, uint32_t i, bool bus, bool prev_bus) {
  State& s = st_[k];
  const BusParticipant& p = parts_[k];
  if (p.planned && p.planned->second == i) {
    detect(k, i, p.planned->first, true);
    return;
  }
  if (s.is_tx && p.bits != nullptr && i < p.bits->length) {
    const bool sent = p.bits->level_at(i);
    if (i == ack_slot_) {
      if (bus && !p.self_test) {
        detect(k, i, CanErrorType::ack, true);
      }
    } else if (sent != bus) {
      if (sent && i < p.bits->arbitration_end) {
        if (p.bits->is_stuff(i)) {
          // A recessive stuff bit overwritten in arbitration: stuff error, no TEC increment
          // (rule 3, exception b).
          detect(k, i, CanErrorType::stuff, false);
        } else {
          s.is_tx = false;  // lost arbitration: it receives from here on
          actions_.push_back(Action{
              .at = bit_end(i),
              .node = p.id,
              .kind = Action::Kind::arbitration_lost,
              .type = CanErrorType::bit,
              .role = ErrorRole::transmitter,
              .bit = static_cast<uint16_t>(i),
              .count = false,
              .in_frame = true,
              .field = Field::sof,
              .destuffed_bit = p.bits->destuffed_index(static_cast<uint16_t>(i)),
          });
        }
      } else {
        detect(k, i, CanErrorType::bit, true);
      }
    } else if (i + 1u == p.bits->length) {
      s.phase = Phase::done;  // sent the whole frame without seeing an error
      actions_.push_back(Action{.at = bit_end(i), .node = p.id, .kind = Action::Kind::tx_ok});
    }
    return;
  }
  // Receiver (or a node that has nothing to send while the bus is held).
  if (i < stuff_end_ && run_ >= 6) {
    detect(k, i, CanErrorType::stuff, true);
  } else if (e_ != nullptr && !bus &&
             (i == e_->crc_delimiter_index || (i > ack_slot_ && i + 1u < length_))) {
    // Fixed-form bits: CRC delimiter, ACK delimiter, EOF up to its last-but-one bit (a dominant
    // last bit is an overload condition for receivers, not modelled).
    detect(k, i, CanErrorType::form, true);
  } else if (e_ != nullptr && e_->fd && i >= stuff_end_ && i < e_->crc_delimiter_index &&
             e_->is_stuff(i) && bus == prev_bus) {
    detect(k, i, CanErrorType::form, true);  // fixed stuff bit with the wrong level
  } else if (e_ != nullptr && i + 2u == length_) {
    // Valid for receivers once the last-but-one bit of EOF is through without error; delivered
    // at the end of EOF like any frame.
    if (p.decodes) {
      // Rule 8 needs the ACK sent: a node that could not give it keeps its counter.
      actions_.push_back(Action{
          .at = bit_end(i + 1),
          .node = p.id,
          .kind = Action::Kind::rx_ok,
          .type = CanErrorType::bit,
          .role = ErrorRole::receiver,
          .bit = static_cast<uint16_t>(i),
          .count = p.acks,
      });
    }
    s.phase = Phase::done;
  }
}

void ErrorPhase::in_flag(std::size_t k, uint32_t i, bool bus) {
  State& s = st_[k];
  const BusParticipant& p = parts_[k];
  if (!p.passive) {
    if (i + 1 >= s.flag_start + kErrorFlagBits) {
      s.phase = Phase::wait_recessive;
      s.flag_end = i;
      s.dominant_run = kErrorFlagBits;
    }
    return;
  }
  // Passive flag: done after six equal consecutive bits, whatever their level.
  if (!bus && s.passive_ack_pending) {
    // A dominant bit during the passive flag: the ACK-error exception no longer holds.
    s.passive_ack_pending = false;
    actions_.push_back(Action{
        .at = bit_end(i),
        .node = p.id,
        .kind = Action::Kind::severe,
        .type = CanErrorType::ack,
        .role = ErrorRole::transmitter,
        .bit = static_cast<uint16_t>(i),
    });
  }
  s.equal_run = (s.equal_run > 0 && bus == s.equal_level) ? s.equal_run + 1 : 1;
  s.equal_level = bus;
  if (s.equal_run >= kErrorFlagBits) {
    s.phase = Phase::wait_recessive;
    s.flag_end = i;
    s.dominant_run = 0;
  }
}

void ErrorPhase::waiting_recessive(std::size_t k, uint32_t i, bool bus) {
  State& s = st_[k];
  const BusParticipant& p = parts_[k];
  if (bus) {
    s.phase = Phase::delimiter;
    s.delimiter = 1;
    return;
  }
  ++s.dominant_run;
  // Rule 2: a receiver sees a dominant bit right after its own error flag.
  if (!s.is_tx && i == s.flag_end + 1 && p.drives) {
    actions_.push_back(Action{
        .at = bit_end(i),
        .node = p.id,
        .kind = Action::Kind::severe,
        .type = CanErrorType::bit,
        .role = ErrorRole::receiver,
        .bit = static_cast<uint16_t>(i),
    });
  }
  // Rule 6: 14 dominant bits from an active flag's start (8 after a passive flag), and every 8
  // more.
  const uint32_t first = p.passive ? 8u : 14u;
  if (s.dominant_run >= first && (s.dominant_run - first) % 8 == 0 && p.drives) {
    actions_.push_back(Action{
        .at = bit_end(i),
        .node = p.id,
        .kind = Action::Kind::severe,
        .type = CanErrorType::bit,
        .role = s.is_tx ? ErrorRole::transmitter : ErrorRole::receiver,
        .bit = static_cast<uint16_t>(i),
    });
  }
}

void ErrorPhase::in_delimiter(std::size_t k, bool bus) {
  State& s = st_[k];
  if (!bus) {
    s.phase = Phase::wait_recessive;  // not modelled: overload after an error frame
    s.dominant_run = 1;
    return;
  }
  if (++s.delimiter >= kErrorDelimiterBits) {
    s.phase = Phase::done;
  }
}

}  // namespace canemu::model
