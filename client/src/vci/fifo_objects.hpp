// The FIFOs of the VCI C++ API: a channel's reader and writer (IFifoReader, IFifoWriter on
// the channel's rings) and the stand-alone FIFOs of VciCreateFifo / VciAccessFifo (IVciFifo,
// IVciFifo2 and their reader and writer, on a ring canemud holds).
#pragma once

#include <cstdint>
#include <memory>

#include "vci_core.hpp"
#include "vcisdk.h"

namespace canemu::client::vci::cpp {

// A channel's reader (writer): one at a time; VCI_E_ACCESSDENIED while another is out (or, for
// the writer, when the channel has no transmit FIFO), VCI_E_NOT_INITIALIZED before the channel
// has rings.
HRESULT get_reader(const std::shared_ptr<Rings>& rings, IFifoReader** pp);
HRESULT get_writer(const std::shared_ptr<Rings>& rings, IFifoWriter** pp);

// A stand-alone FIFO (VciCreateFifo / VciAccessFifo): a ring canemud holds for the processes
// that use it; each side (reader, writer) is taken from canemud, so there is one of each in all
// processes together. A side's ring view is made when it is taken (the positions in shared
// memory are where the last holder left them).
struct SharedFifo {
  uint64_t id = 0;
  canemu::ipc::SharedRing ring;
  const canemu::ipc::RingMemory& memory() const { return ring.memory(); }
  uint32_t fill() const {
    const auto* h = ring.memory().header();
    return static_cast<uint32_t>(h->write_pos.load(std::memory_order_acquire) -
                                 h->read_pos.load(std::memory_order_acquire));
  }
};

// Creates (VciOp::fifo_create: `a0` capacity, `a1` element size) or reaches
// (VciOp::fifo_access: `a0`, `a1` the low and high half of its id) a FIFO through canemud.
HRESULT shared_fifo(ipc::VciOp op, uint32_t a0, uint32_t a1, std::shared_ptr<SharedFifo>& out);

// The interface `riid` of FIFO `f`: its reader or writer (taking that side from canemud),
// IVciFifo or IVciFifo2.
HRESULT open_fifo(const std::shared_ptr<SharedFifo>& f, REFIID riid, PVOID* ppv);

}  // namespace canemu::client::vci::cpp
