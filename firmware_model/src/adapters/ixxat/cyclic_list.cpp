#include "canemu/firmware_model/adapters/ixxat/cyclic_list.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <span>
#include <vector>

#include "canemu/firmware_model/bus/frame.hpp"

namespace canemu::model::ixxat {

namespace {

void increment(CANCYCLICTXMSG2& m) {
  switch (m.bIncrMode) {
    case CAN_CTXMSG_INC_ID: {
      const uint32_t wrap = m.uMsgInfo.Bits.ext != 0 ? (kMaxExtendedId + 1) : (kMaxStandardId + 1);
      m.dwMsgId = (m.dwMsgId + 1) % wrap;
      break;
    }
    case CAN_CTXMSG_INC_8:
      ++m.abData[m.bByteIndex];
      break;
    case CAN_CTXMSG_INC_16: {
      // Little endian: the low byte at bByteIndex.
      const uint16_t v =
          static_cast<uint16_t>(m.abData[m.bByteIndex] | (m.abData[m.bByteIndex + 1] << 8)) + 1;
      m.abData[m.bByteIndex] = static_cast<UINT8>(v & 0xFF);
      m.abData[m.bByteIndex + 1] = static_cast<UINT8>(v >> 8);
      break;
    }
    default:
      break;
  }
}

// An unsigned integer wide enough for products of up to 17 cycle times (16 bits each) and
// sums of 17 of them: 32-bit limbs, least significant first.
class Wide {
 public:
  explicit Wide(uint32_t v = 0) { limbs_[0] = v; }
  Wide& operator*=(uint32_t f) {
    uint64_t carry = 0;
    for (uint32_t& l : limbs_) {
      const uint64_t v = uint64_t{l} * f + carry;
      l = static_cast<uint32_t>(v);
      carry = v >> 32;
    }
    return *this;
  }
  Wide& operator+=(const Wide& o) {
    uint64_t carry = 0;
    for (std::size_t i = 0; i < limbs_.size(); ++i) {
      const uint64_t v = uint64_t{limbs_[i]} + o.limbs_[i] + carry;
      limbs_[i] = static_cast<uint32_t>(v);
      carry = v >> 32;
    }
    return *this;
  }
  friend bool operator<=(const Wide& a, const Wide& b) {
    for (std::size_t i = a.limbs_.size(); i-- > 0;) {
      if (a.limbs_[i] != b.limbs_[i]) {
        return a.limbs_[i] < b.limbs_[i];
      }
    }
    return true;
  }

 private:
  std::array<uint32_t, 12> limbs_{};
};

// Whether the list can give every entry its ticks: one frame per tick, so the entries' shares
// 1/cycle must add up to at most 1. Exact: the sum of 1/c_i <= 1 exactly when the sum over i of
// the product of the other cycles is at most the product of all of them.
bool fits(std::span<const uint16_t> cycles) {
  Wide all(1);
  for (uint16_t c : cycles) {
    all *= c;
  }
  Wide sum;
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    Wide others(1);
    for (std::size_t j = 0; j < cycles.size(); ++j) {
      if (j != i) {
        others *= cycles[j];
      }
    }
    sum += others;
  }
  return sum <= all;
}

}  // namespace

CyclicList::CyclicList(SimScheduler& scheduler, const Clocks& clocks, Line& line)
    : scheduler_(scheduler), clocks_(clocks), line_(line) {}

CyclicList::~CyclicList() {
  if (event_ != 0) {
    scheduler_.cancel(event_);
  }
}

void CyclicList::suspend() {
  running_ = false;
  if (event_ != 0) {
    scheduler_.cancel(event_);
    event_ = 0;
  }
}

HRESULT CyclicList::resume() {
  if (running_) {
    return VCI_OK;
  }
  running_ = true;
  epoch_ = scheduler_.now();
  last_tick_ = 0;
  for (Entry& e : entries_) {
    if (e.started) {
      e.due = e.msg.wCycleTime;
    }
  }
  schedule();
  return VCI_OK;
}

void CyclicList::reset() {
  suspend();
  for (Entry& e : entries_) {
    e = Entry{};
  }
}

void CyclicList::clear() {
  pending_.reset();
  reset();
}

tl::expected<uint32_t, HRESULT> CyclicList::add(const CANCYCLICTXMSG2& msg) {
  if (msg.wCycleTime == 0 || msg.wCycleTime > clocks_.cms_max_ticks ||
      msg.uMsgInfo.Bits.type != CAN_MSGTYPE_DATA) {
    return tl::unexpected(VCI_E_INVALIDARG);
  }
  const bool fd = msg.uMsgInfo.Bits.edl != 0 || msg.uMsgInfo.Bits.fdr != 0;
  const uint32_t length =
      msg.uMsgInfo.Bits.rtr != 0 && !fd
          ? 0
          : static_cast<uint32_t>(dlc_to_length(static_cast<uint8_t>(msg.uMsgInfo.Bits.dlc), fd));
  const uint32_t max_id = msg.uMsgInfo.Bits.ext != 0 ? kMaxExtendedId : kMaxStandardId;
  if (msg.dwMsgId > max_id) {
    return tl::unexpected(VCI_E_INVALIDARG);
  }
  switch (msg.bIncrMode) {
    case CAN_CTXMSG_INC_NO:
    case CAN_CTXMSG_INC_ID:
      break;
    case CAN_CTXMSG_INC_8:
      if (msg.bByteIndex >= length) {
        return tl::unexpected(VCI_E_INVALIDARG);
      }
      break;
    case CAN_CTXMSG_INC_16:
      if (msg.bByteIndex + 1U >= length) {
        return tl::unexpected(VCI_E_INVALIDARG);
      }
      break;
    default:
      return tl::unexpected(VCI_E_INVALIDARG);
  }
  // The admission rule (VCI guide 5.2.5): every entry in the list, started or not, holds its
  // share of the ticks; one that would take the total above one frame per tick is refused as
  // a full list is.
  std::vector<uint16_t> cycles{msg.wCycleTime};
  for (const Entry& e : entries_) {
    if (e.status != CAN_CTXMSG_STAT_EMPTY) {
      cycles.push_back(e.msg.wCycleTime);
    }
  }
  if (!fits(cycles)) {
    return tl::unexpected(VCI_E_OUTOFMEMORY);
  }
  for (uint32_t i = 0; i < entries_.size(); ++i) {
    if (entries_[i].status == CAN_CTXMSG_STAT_EMPTY) {
      entries_[i] = Entry{};
      entries_[i].status = CAN_CTXMSG_STAT_DONE;
      entries_[i].msg = msg;
      entries_[i].order = ++order_;
      return i;
    }
  }
  return tl::unexpected(VCI_E_OUTOFMEMORY);
}

bool CyclicList::valid(uint32_t index) const {
  return index < entries_.size() && entries_[index].status != CAN_CTXMSG_STAT_EMPTY;
}

HRESULT CyclicList::remove(uint32_t index) {
  if (!valid(index)) {
    return VCI_E_INVALID_INDEX;
  }
  entries_[index] = Entry{};
  schedule();
  return VCI_OK;
}

HRESULT CyclicList::start(uint32_t index, uint16_t count) {
  if (!valid(index)) {
    return VCI_E_INVALID_INDEX;
  }
  Entry& e = entries_[index];
  e.started = true;
  e.status = CAN_CTXMSG_STAT_BUSY;
  e.endless = count == 0;
  e.remaining = count;
  if (running_) {
    e.due = tick_now() + e.msg.wCycleTime;
    schedule();
  }
  return VCI_OK;
}

HRESULT CyclicList::stop(uint32_t index) {
  if (!valid(index)) {
    return VCI_E_INVALID_INDEX;
  }
  entries_[index].started = false;
  entries_[index].status = CAN_CTXMSG_STAT_DONE;
  schedule();
  return VCI_OK;
}

CANSCHEDULERSTATUS CyclicList::status() const {
  CANSCHEDULERSTATUS s{};
  s.bTaskStat = running_ ? CAN_CTXTSK_STAT_RUNNING : CAN_CTXTSK_STAT_STOPPED;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    s.abMsgStat[i] = entries_[i].status;
  }
  return s;
}

std::optional<CANMSG2> CyclicList::take() {
  std::optional<CANMSG2> m = pending_;
  pending_.reset();
  return m;
}

uint64_t CyclicList::tick_now() const {
  return ns_to_ticks((scheduler_.now() - epoch_).ns(), clocks_.cms_divisor, clocks_.clock_hz);
}

SimTime CyclicList::tick_time(uint64_t tick) const {
  return epoch_ + SimDuration(ticks_to_ns(tick, clocks_.cms_divisor, clocks_.clock_hz));
}

void CyclicList::schedule() {
  if (event_ != 0) {
    scheduler_.cancel(event_);
    event_ = 0;
  }
  if (!running_) {
    return;
  }
  std::optional<uint64_t> next;
  for (const Entry& e : entries_) {
    if (e.started && (!next || e.due < *next)) {
      next = e.due;
    }
  }
  if (!next) {
    return;
  }
  next_tick_ = std::max(*next, last_tick_ + 1);
  event_ = scheduler_.schedule_at(tick_time(next_tick_), *this, 0);
}

void CyclicList::on_event(SimTime, uint64_t) {
  event_ = 0;
  tick();
}

void CyclicList::tick() {
  const uint64_t tick = next_tick_;
  last_tick_ = tick;
  if (!line_.online()) {
    for (Entry& e : entries_) {
      while (e.started && e.due <= tick) {
        e.due += e.msg.wCycleTime;
      }
    }
  } else if (!pending_) {
    Entry* pick = nullptr;
    for (Entry& e : entries_) {
      if (e.started && e.due <= tick &&
          (pick == nullptr || e.due < pick->due || (e.due == pick->due && e.order < pick->order))) {
        pick = &e;
      }
    }
    if (pick != nullptr) {
      CANMSG2 m{};
      m.dwMsgId = pick->msg.dwMsgId;
      m.uMsgInfo = pick->msg.uMsgInfo;
      std::memcpy(m.abData, pick->msg.abData, sizeof(m.abData));
      pending_ = m;
      increment(pick->msg);
      pick->due += pick->msg.wCycleTime;
      if (!pick->endless && --pick->remaining == 0) {
        pick->started = false;
        pick->status = CAN_CTXMSG_STAT_DONE;
      }
      line_.frame_due();
    }
  }
  schedule();
}

}  // namespace canemu::model::ixxat
