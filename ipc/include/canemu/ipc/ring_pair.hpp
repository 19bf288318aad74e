// The rings the daemon and a client share, with the eventfds their sides wait on: the data part
// each process holds (memory and descriptors), as opposed to the per-side views that work on it
// (RingWriter and RingReader, shm_ring.hpp).
//
// canemud creates them (create()) and passes the descriptors with SCM_RIGHTS; the client maps
// what it received (map()), which checks every descriptor and the ring headers first. Views
// made by reader() and writer() point into the mapping and use the descriptors: they must not
// outlive the SharedRing or RingPair they came from (moving that is fine: the mapping and the
// descriptor numbers stay).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/seqpacket.hpp"
#include "canemu/ipc/shm_ring.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::ipc {

// One ring and the eventfds of its reader and writer. A side that never waits has no eventfd
// (-1): canemud never blocks for room in a channel's receive ring.
class SharedRing {
 public:
  enum class WriterWaits : bool { no, yes };
  // canemud's side: new ring memory (see RingMemory::create: the capacity is rounded up to
  // whole pages) named `name`, the reader's eventfd, and the writer's unless it never waits.
  static IpcResult<SharedRing> create(uint32_t capacity, uint32_t element_size,
                                      const std::string& name,
                                      WriterWaits writer_waits = WriterWaits::yes);
  // The other process: maps `memory` (see RingMemory::map) and takes the two eventfds (either
  // may be invalid). EPROTO if the ring's elements are not `element_size` bytes (0: any size).
  static IpcResult<SharedRing> map(UniqueFd memory, UniqueFd reader_event, UniqueFd writer_event,
                                   uint32_t element_size);

  // The views of the two sides, with the eventfds the right way round.
  RingReader reader() const {
    return RingReader(memory_, writer_event_.get(), reader_event_.get());
  }
  RingWriter writer() const {
    return RingWriter(memory_, reader_event_.get(), writer_event_.get());
  }

  const RingMemory& memory() const { return memory_; }
  int reader_event() const { return reader_event_.get(); }
  int writer_event() const { return writer_event_.get(); }
  // What goes to the other process for a stand-alone FIFO (kFifoFdCount, in the protocol's
  // order): the memory, the reader's eventfd, the writer's eventfd.
  std::array<int, kFifoFdCount> fds() const {
    return {memory_.fd(), reader_event_.get(), writer_event_.get()};
  }

 private:
  SharedRing(RingMemory memory, UniqueFd reader_event, UniqueFd writer_event)
      : memory_(std::move(memory)),
        reader_event_(std::move(reader_event)),
        writer_event_(std::move(writer_event)) {}

  RingMemory memory_;
  UniqueFd reader_event_;
  UniqueFd writer_event_;
};

// A channel's two rings: the receive ring (canemud writes, the client reads) and the transmit
// ring (the client writes, canemud reads; its reader's eventfd is canemud's doorbell). Both
// hold elements of one size. canemud's views: rx().writer(), tx().reader(); the client's:
// rx().reader(), tx().writer().
class RingPair {
 public:
  // canemud's side: rings of at least `rx_capacity` and `tx_capacity` elements (1..65535), the
  // memfds named "PREFIX-rx-NAME" and "PREFIX-tx-NAME" (shown in /proc/PID/fd).
  static IpcResult<RingPair> create(uint32_t rx_capacity, uint32_t tx_capacity,
                                    uint32_t element_size, std::string_view prefix,
                                    std::string_view name);
  // The client's side: maps the descriptors of an OpenChannelReply or a VCI channel_init reply
  // (kChannelFdCount, in the order of fds()). EPROTO if there are not that many or a ring's
  // elements are not `element_size` bytes; EINVAL (from RingMemory::map) if a ring is not valid.
  static IpcResult<RingPair> map(std::vector<UniqueFd> fds, uint32_t element_size);

  const SharedRing& rx() const { return rx_; }
  const SharedRing& tx() const { return tx_; }
  uint32_t element_size() const { return rx_.memory().element_size(); }
  // The bytes of both rings' elements (what the daemon's ring memory budget counts).
  std::size_t element_bytes() const {
    return (std::size_t{rx_.memory().capacity()} + tx_.memory().capacity()) * element_size();
  }
  // What goes to the client, in the protocol's order: rx memory, tx memory, the rx reader's
  // eventfd, the tx writer's eventfd, the tx reader's eventfd (canemud's doorbell).
  std::array<int, kChannelFdCount> fds() const {
    return {rx_.memory().fd(), tx_.memory().fd(), rx_.reader_event(), tx_.writer_event(),
            tx_.reader_event()};
  }

 private:
  RingPair(SharedRing rx, SharedRing tx) : rx_(std::move(rx)), tx_(std::move(tx)) {}

  SharedRing rx_;
  SharedRing tx_;
};

}  // namespace canemu::ipc
