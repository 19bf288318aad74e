// The message filters of the VCI firmware (VCI C++ guide 5.2.4, 8.3.14): one for 11-bit and
// one for 29-bit identifiers, on the control unit and on every v2 channel. Each has an operating
// mode (LOCK, PASS, INCL, EXCL), an acceptance filter (code and mask) and an ID list. Filter
// values are (identifier << 1) | RTR; a mask bit of 1 makes the bit relevant.
//
// Decisions (docs/vci.md): the ID list holds filter values, so RTR frames are listed apart from
// data frames; the 11-bit list always has room for all 4096 values; adding a pattern that does
// not fit whole adds nothing and returns VCI_E_OUTOFMEMORY (also when there is no list).
#pragma once

#include <cstdint>
#include <vector>

#include "vci/cantype.h"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

constexpr uint32_t filter_value(uint32_t id, bool rtr) {
  return (id << 1) | (rtr ? 1U : 0U);
}

inline constexpr uint32_t kStdListCapacity = 4096;  // every 11-bit identifier, with and without RTR
inline constexpr uint32_t kMaxExtListCapacity = 65536;

bool valid_filter_mode(uint8_t mode);

class IdFilter {
 public:
  // `list_capacity`: filter values the ID list can hold (0: no list). A disabled filter passes
  // every frame whatever its mode (ICanControl2 with no identifiers).
  IdFilter(bool extended, uint32_t list_capacity, uint8_t mode, bool enabled = true);

  uint8_t mode() const { return mode_; }
  bool extended() const { return extended_; }
  // VCI_E_INVALIDARG for a mode that is not LOCK, PASS, INCL or EXCL.
  HRESULT set_mode(uint8_t mode);
  void set_acceptance(uint32_t code, uint32_t mask) {
    code_ = code;
    mask_ = mask;
  }
  // Every value that matches code/mask enters (or leaves) the list.
  HRESULT add_ids(uint32_t code, uint32_t mask);
  HRESULT remove_ids(uint32_t code, uint32_t mask);
  uint32_t list_size() const;
  bool listed(uint32_t value) const;

  // The CAN_ACCEPT_* code a data frame with this filter value gets, CAN_ACCEPT_REJECT when it
  // is blocked.
  uint8_t accept(uint32_t value) const;
  // Back to the initial state: `mode`, acceptance filter open, list empty.
  void reset(uint8_t mode);

 private:
  uint32_t valid_bits() const { return extended_ ? 0x3FFFFFFFU : 0xFFFU; }
  template <typename F>
  void for_each_match(uint32_t code, uint32_t mask, F&& f) const;
  uint64_t match_count(uint32_t code, uint32_t mask) const;

  bool extended_;
  bool enabled_;
  uint32_t capacity_;
  uint8_t mode_;
  uint32_t code_ = CAN_ACC_CODE_ALL;
  uint32_t mask_ = CAN_ACC_MASK_ALL;
  std::vector<uint64_t> std_list_;  // 11-bit: a bitmap of the 4096 values
  std::vector<uint32_t> ext_list_;  // 29-bit: sorted values
};

// The pair a control unit or a v2 channel has.
struct FilterPair {
  IdFilter std;
  IdFilter ext;
  IdFilter& select(bool extended) { return extended ? ext : std; }
  const IdFilter& select(bool extended) const { return extended ? ext : std; }
  uint8_t accept(uint32_t id, bool extended, bool rtr) const {
    return (extended ? ext : std).accept(filter_value(id, rtr));
  }
};

}  // namespace canemu::model::ixxat
