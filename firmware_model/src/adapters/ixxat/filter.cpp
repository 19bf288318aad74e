#include "canemu/firmware_model/adapters/ixxat/filter.hpp"

#include <algorithm>
#include <bit>

namespace canemu::model::ixxat {

bool valid_filter_mode(uint8_t mode) {
  return mode == CAN_FILTER_LOCK || mode == CAN_FILTER_PASS || mode == CAN_FILTER_INCL ||
         mode == CAN_FILTER_EXCL;
}

IdFilter::IdFilter(bool extended, uint32_t list_capacity, uint8_t mode, bool enabled)
    : extended_(extended),
      enabled_(enabled),
      capacity_(extended ? std::min(list_capacity, kMaxExtListCapacity)
                         : std::min(list_capacity, kStdListCapacity)),
      mode_(mode) {
  if (!extended_ && capacity_ > 0) {
    std_list_.assign(kStdListCapacity / 64, 0);
  }
}

HRESULT IdFilter::set_mode(uint8_t mode) {
  if (!valid_filter_mode(mode)) {
    return VCI_E_INVALIDARG;
  }
  mode_ = mode;
  return VCI_OK;
}

uint64_t IdFilter::match_count(uint32_t code, uint32_t mask) const {
  if ((code & mask & ~valid_bits()) != 0) {
    return 0;  // a relevant bit that no filter value has set
  }
  return uint64_t{1} << std::popcount(~mask & valid_bits());
}

template <typename F>
void IdFilter::for_each_match(uint32_t code, uint32_t mask, F&& f) const {
  if (match_count(code, mask) == 0) {
    return;
  }
  const uint32_t free_bits = ~mask & valid_bits();
  const uint32_t base = code & mask & valid_bits();
  // Every subset of the free bits, from the empty one up.
  uint32_t sub = 0;
  do {
    f(base | sub);
    sub = (sub - free_bits) & free_bits;
  } while (sub != 0);
}

HRESULT IdFilter::add_ids(uint32_t code, uint32_t mask) {
  if (capacity_ == 0) {
    return VCI_E_OUTOFMEMORY;
  }
  const uint64_t n = match_count(code, mask);
  if (!extended_) {
    for_each_match(code, mask, [&](uint32_t v) { std_list_[v / 64] |= uint64_t{1} << (v % 64); });
    return VCI_OK;
  }
  if (n > capacity_) {
    return VCI_E_OUTOFMEMORY;
  }
  std::vector<uint32_t> fresh;
  for_each_match(code, mask, [&](uint32_t v) {
    if (!std::binary_search(ext_list_.begin(), ext_list_.end(), v)) {
      fresh.push_back(v);
    }
  });
  if (ext_list_.size() + fresh.size() > capacity_) {
    return VCI_E_OUTOFMEMORY;
  }
  std::sort(fresh.begin(), fresh.end());
  std::vector<uint32_t> merged;
  merged.reserve(ext_list_.size() + fresh.size());
  std::merge(ext_list_.begin(), ext_list_.end(), fresh.begin(), fresh.end(),
             std::back_inserter(merged));
  ext_list_ = std::move(merged);
  return VCI_OK;
}

HRESULT IdFilter::remove_ids(uint32_t code, uint32_t mask) {
  if (capacity_ == 0) {
    return VCI_E_OUTOFMEMORY;
  }
  const uint32_t relevant = mask & valid_bits();
  if (!extended_) {
    for_each_match(code, mask,
                   [&](uint32_t v) { std_list_[v / 64] &= ~(uint64_t{1} << (v % 64)); });
    return VCI_OK;
  }
  if ((code & mask & ~valid_bits()) != 0) {
    return VCI_OK;
  }
  std::erase_if(ext_list_, [&](uint32_t v) { return ((v ^ code) & relevant) == 0; });
  return VCI_OK;
}

uint32_t IdFilter::list_size() const {
  if (extended_) {
    return static_cast<uint32_t>(ext_list_.size());
  }
  uint32_t n = 0;
  for (uint64_t word : std_list_) {
    n += static_cast<uint32_t>(std::popcount(word));
  }
  return n;
}

bool IdFilter::listed(uint32_t value) const {
  if (extended_) {
    return std::binary_search(ext_list_.begin(), ext_list_.end(), value);
  }
  if (std_list_.empty() || value >= kStdListCapacity) {
    return false;
  }
  return ((std_list_[value / 64] >> (value % 64)) & 1U) != 0;
}

uint8_t IdFilter::accept(uint32_t value) const {
  if (!enabled_) {
    return CAN_ACCEPT_ALWAYS;
  }
  const bool acceptance = ((value ^ code_) & mask_) == 0;
  switch (mode_) {
    case CAN_FILTER_LOCK:
      return CAN_ACCEPT_REJECT;
    case CAN_FILTER_PASS:
      return CAN_ACCEPT_ALWAYS;
    case CAN_FILTER_INCL:
      if (acceptance) {
        return CAN_ACCEPT_FILTER_1;
      }
      return listed(value) ? CAN_ACCEPT_FILTER_2 : CAN_ACCEPT_REJECT;
    case CAN_FILTER_EXCL:
      return acceptance || listed(value) ? CAN_ACCEPT_REJECT : CAN_ACCEPT_PASSEXCL;
    default:
      return CAN_ACCEPT_REJECT;
  }
}

void IdFilter::reset(uint8_t mode) {
  mode_ = mode;
  code_ = CAN_ACC_CODE_ALL;
  mask_ = CAN_ACC_MASK_ALL;
  std::fill(std_list_.begin(), std_list_.end(), 0);
  ext_list_.clear();
}

}  // namespace canemu::model::ixxat
