// Stand-alone VCI FIFOs (VciCreateFifo / VciAccessFifo, ipc::VciOp::fifo_*): rings canemud holds
// for the processes that share them. A client creates one and gets its id and descriptors;
// other clients of the same user (or root) reach it by that id, a random 64-bit number that
// cannot be guessed from another FIFO's. Each side (reader, writer) is taken by one client at a
// time, so there is one reader and one writer in all processes together. A FIFO lives while a
// client holds it; its memory counts against the daemon-wide ring budget.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <vector>

#include "canemu/daemon/base/ring_budget.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/ring_pair.hpp"

namespace canemu::daemon {

inline constexpr std::size_t kMaxVciFifosPerClient = 64;

class VciFifos {
 public:
  // Who holds FIFOs: a client's session, by address (never dereferenced).
  using Holder = const void*;

  explicit VciFifos(RingLedger& rings) : rings_(rings) {}

  // Answers fifo_create (args: capacity, element size), fifo_access (args: the id's low and
  // high words) and fifo_side (args: the id's words, side 0 reader / 1 writer, 1 take / 0 give
  // back) for `holder`, whose peer runs as `uid`, in `r`. Create and access give the id, capacity
  // and element size in r.values and the descriptors (ipc::kFifoFdCount) in `fds`. Access by a
  // uid other than the creator's (root excepted) is VCI_E_ACCESSDENIED.
  void handle(Holder holder, uint32_t uid, const ipc::VciRequest& m, ipc::VciReply& r,
              std::vector<int>& fds);
  // `holder` is gone: it gives back its sides, and a FIFO nobody holds any more is freed.
  void release(Holder holder);

  std::size_t count() const { return fifos_.size(); }

 private:
  struct SharedFifo {
    ipc::SharedRing ring;
    RingBudget budget;
    std::set<Holder> holders;
    Holder reader = nullptr;
    Holder writer = nullptr;
    uint32_t owner_uid = 0;
  };
  uint64_t fresh_id() const;
  std::size_t held_by(Holder holder) const;
  void side(Holder holder, SharedFifo& f, const ipc::VciRequest& m, ipc::VciReply& r);

  RingLedger& rings_;
  std::map<uint64_t, SharedFifo> fifos_;
  std::map<Holder, std::set<uint64_t>> held_;  // the FIFOs each holder holds
};

}  // namespace canemu::daemon
