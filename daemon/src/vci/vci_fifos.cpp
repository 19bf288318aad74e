#include "canemu/daemon/vci/vci_fifos.hpp"
#include "canemu/daemon/base/log.hpp"

#include <sys/random.h>

#include "vci/vcierr.h"

namespace canemu::daemon {

std::size_t VciFifos::held_by(Holder holder) const {
  auto it = held_.find(holder);
  return it == held_.end() ? 0 : it->second.size();
}

// A random id, neither 0 nor one in use: knowing one FIFO's id tells nothing of another's.
uint64_t VciFifos::fresh_id() const {
  uint64_t id = 0;
  while (id == 0 || fifos_.count(id) != 0) {
    if (::getrandom(&id, sizeof id, 0) != static_cast<ssize_t>(sizeof id)) {
      id = 0;
    }
  }
  return id;
}

void VciFifos::handle(Holder holder, uint32_t uid, const ipc::VciRequest& m, ipc::VciReply& r,
                      std::vector<int>& fds) {
  const auto op = static_cast<ipc::VciOp>(m.op);
  uint64_t id = uint64_t{m.args[0]} | (uint64_t{m.args[1]} << 32);
  if (op == ipc::VciOp::fifo_create) {
    const uint32_t capacity = m.args[0];
    const uint32_t size = m.args[1];
    if (capacity == 0 || capacity > 0xFFFF || size == 0 || size > 0xFFFF) {
      r.hresult = VCI_E_INVALIDARG;
      return;
    }
    if (held_by(holder) >= kMaxVciFifosPerClient) {
      r.hresult = VCI_E_OUTOFMEMORY;
      return;
    }
    // The request is checked before anything is made, the ring as made (rounded to pages) after.
    const auto refused = [&](std::size_t bytes) {
      const std::string why = rings_.refusal(uid, bytes);
      if (!why.empty()) {
        log::warning("VCI FIFO of uid {} not created: {}", uid, why);
        r.hresult = VCI_E_OUTOFMEMORY;
      }
      return !why.empty();
    };
    if (refused(std::size_t{capacity} * size)) {
      return;
    }
    auto ring = ipc::SharedRing::create(capacity, size, "canemu-vci-fifo");
    if (!ring) {
      r.hresult = VCI_E_OUTOFMEMORY;
      return;
    }
    const std::size_t bytes =
        std::size_t{ring->memory().capacity()} * ring->memory().element_size();
    if (refused(bytes)) {
      return;
    }
    id = fresh_id();
    fifos_.emplace(
        id, SharedFifo{std::move(*ring), rings_.take(uid, bytes), {}, nullptr, nullptr, uid});
  }
  auto it = fifos_.find(id);
  if (it == fifos_.end()) {
    r.hresult = VCI_E_INVALIDARG;  // no FIFO with that id (any more)
    return;
  }
  SharedFifo& f = it->second;
  if (uid != 0 && uid != f.owner_uid) {
    r.hresult = VCI_E_ACCESSDENIED;  // another user's FIFO
    return;
  }
  if (op == ipc::VciOp::fifo_side) {
    side(holder, f, m, r);
    return;
  }
  if (op == ipc::VciOp::fifo_access && f.holders.count(holder) == 0 &&
      held_by(holder) >= kMaxVciFifosPerClient) {
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  f.holders.insert(holder);
  held_[holder].insert(id);
  r.hresult = VCI_OK;
  r.values[0] = static_cast<uint32_t>(id);
  r.values[1] = static_cast<uint32_t>(id >> 32);
  r.values[2] = f.ring.memory().capacity();
  r.values[3] = f.ring.memory().element_size();
  const auto ring_fds = f.ring.fds();
  fds.assign(ring_fds.begin(), ring_fds.end());
}

void VciFifos::side(Holder holder, SharedFifo& f, const ipc::VciRequest& m, ipc::VciReply& r) {
  if (f.holders.count(holder) == 0 || m.args[2] > 1) {
    r.hresult = VCI_E_INVALIDARG;
    return;
  }
  Holder& side = m.args[2] == 0 ? f.reader : f.writer;
  if (m.args[3] != 0) {  // take it
    r.hresult = side == nullptr ? VCI_OK : VCI_E_ACCESSDENIED;
    if (side == nullptr) {
      side = holder;
    }
  } else {  // give it back
    r.hresult = side == holder ? VCI_OK : VCI_E_INVALIDARG;
    if (side == holder) {
      side = nullptr;
    }
  }
}

void VciFifos::release(Holder holder) {
  auto held = held_.find(holder);
  if (held == held_.end()) {
    return;
  }
  for (uint64_t id : held->second) {
    auto it = fifos_.find(id);
    if (it == fifos_.end()) {
      continue;
    }
    SharedFifo& f = it->second;
    f.holders.erase(holder);
    if (f.reader == holder) {
      f.reader = nullptr;
    }
    if (f.writer == holder) {
      f.writer = nullptr;
    }
    if (f.holders.empty()) {
      fifos_.erase(it);
    }
  }
  held_.erase(held);
}

}  // namespace canemu::daemon
