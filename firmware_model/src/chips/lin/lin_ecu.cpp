#include "canemu/firmware_model/chips/lin/lin_ecu.hpp"

#include <algorithm>

namespace canemu::model::lin {

namespace {
constexpr uint64_t kSlot = 1;

bool same(const Response& a, const Response& b) {
  return a.size == b.size && a.checksum == b.checksum &&
         std::equal(a.data.begin(), a.data.begin() + a.size, b.data.begin());
}
}  // namespace

LinEcu::LinEcu(LinBus& bus, uint32_t bitrate)
    : bus_(bus), scheduler_(bus.scheduler()), id_(bus.attach(*this)), bitrate_(bitrate) {}

LinEcu::~LinEcu() {
  stop_schedule();
  bus_.detach(id_);
}

void LinEcu::set_response(uint8_t id, const Response& response) {
  id &= kMaxId;
  auto it = responses_.find(id);
  if (it == responses_.end() || !same(it->second, response)) {
    changed_[id] = true;
  }
  responses_[id] = response;
}

void LinEcu::clear_response(uint8_t id) {
  responses_.erase(id & kMaxId);
  changed_.erase(id & kMaxId);
}

std::optional<Response> LinEcu::response(uint8_t id) const {
  auto it = responses_.find(id & kMaxId);
  return it == responses_.end() ? std::nullopt : std::optional<Response>(it->second);
}

void LinEcu::add_event_triggered(uint8_t et_id, uint8_t id) {
  et_frames_[et_id & kMaxId].push_back(id & kMaxId);
}

void LinEcu::set_powered(bool on) {
  if (on == powered_) {
    return;
  }
  powered_ = on;
  if (!on) {
    if (timer_) {
      scheduler_.cancel(*timer_);
      timer_.reset();
    }
    bus_.withdraw(id_);
  } else if (!running_.empty()) {
    timer_ = scheduler_.schedule_at(scheduler_.now(), *this, kSlot);
  }
}

void LinEcu::add_schedule(ScheduleTable table) {
  std::string name = table.name;
  schedules_[name] = std::move(table);
}

bool LinEcu::run_schedule(const std::string& name) {
  auto it = schedules_.find(name);
  if (it == schedules_.end() || it->second.slots.empty()) {
    return false;
  }
  stop_schedule();
  running_ = name;
  next_slot_ = 0;
  resolving_.clear();
  if (powered_) {
    timer_ = scheduler_.schedule_at(scheduler_.now(), *this, kSlot);
  }
  return true;
}

void LinEcu::stop_schedule() {
  if (timer_) {
    scheduler_.cancel(*timer_);
    timer_.reset();
  }
  running_.clear();
  resolving_.clear();
  et_pending_.reset();
}

const ScheduleTable* LinEcu::table() const {
  auto it = schedules_.find(running_);
  return it == schedules_.end() ? nullptr : &it->second;
}

void LinEcu::on_event(SimTime now, uint64_t tag) {
  if (tag == kSlot) {
    timer_.reset();
    slot(now);
  }
}

void LinEcu::slot(SimTime now) {
  const ScheduleTable* t = table();
  if (t == nullptr || !powered_) {
    return;
  }
  SimDuration delay;
  if (!resolving_.empty()) {
    // Collision resolution: the associated frames one by one.
    const uint8_t id = resolving_.front();
    resolving_.erase(resolving_.begin());
    if (bus_.send_header(id_, id)) {
      ++counters_.headers;
    }
    delay = resolving_delay_;
  } else {
    const ScheduleSlot& s = t->slots[next_slot_];
    next_slot_ = (next_slot_ + 1) % t->slots.size();
    delay = s.delay;
    switch (s.kind) {
      case ScheduleSlot::Kind::unconditional:
        if (bus_.send_header(id_, s.id)) {
          ++counters_.headers;
        }
        break;
      case ScheduleSlot::Kind::event_triggered:
        if (bus_.send_header(id_, s.id)) {
          ++counters_.headers;
          et_pending_ = s.id;
          resolving_delay_ = s.delay;
          resolving_ = {};
          et_slot_frames_ = s.frames;
        }
        break;
      case ScheduleSlot::Kind::sporadic:
        for (uint8_t id : s.frames) {
          auto c = changed_.find(id);
          if (c != changed_.end() && c->second && responses_.contains(id)) {
            if (bus_.send_header(id_, id)) {
              ++counters_.headers;
            }
            break;
          }
        }
        break;
    }
  }
  timer_ = scheduler_.schedule_at(now + delay, *this, kSlot);
}

std::optional<Response> LinEcu::respond(uint8_t id) {
  if (!powered_) {
    return std::nullopt;
  }
  et_answer_.reset();
  if (auto et = et_frames_.find(id); et != et_frames_.end()) {
    for (uint8_t frame : et->second) {
      auto r = responses_.find(frame);
      auto c = changed_.find(frame);
      if (r != responses_.end() && c != changed_.end() && c->second) {
        Response answer = r->second;
        answer.data[0] = protected_id(frame);
        et_answer_ = frame;
        return answer;
      }
    }
    return std::nullopt;
  }
  auto it = responses_.find(id);
  return it == responses_.end() ? std::nullopt : std::optional<Response>(it->second);
}

void LinEcu::on_lin_event(const Event& e) {
  if (recording_) {
    seen_.push_back(e);
  }
  const bool awaited = et_pending_ && e.id == *et_pending_ && e.sender == id_;
  if (awaited) {
    et_pending_.reset();
  }
  switch (e.kind) {
    case Event::Kind::frame:
      ++counters_.frames;
      if (e.responded(id_)) {
        ++counters_.responses;
        changed_[et_answer_.value_or(e.id)] = false;  // went out whole
      }
      et_answer_.reset();
      return;
    case Event::Kind::error:
      ++counters_.errors;
      et_answer_.reset();
      if (awaited && (e.error == ErrorKind::checksum || e.error == ErrorKind::bit)) {
        // Several responders answered: poll each associated frame on its own.
        ++counters_.collisions;
        resolving_ = et_slot_frames_;
      }
      return;
    case Event::Kind::wakeup:
    case Event::Kind::sleep:
      return;
  }
}

}  // namespace canemu::model::lin
