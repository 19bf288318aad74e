#include "canemu/ipc/ring_pair.hpp"

#include <cerrno>

namespace canemu::ipc {

IpcResult<SharedRing> SharedRing::create(uint32_t capacity, uint32_t element_size,
                                         const std::string& name, WriterWaits writer_waits) {
  auto memory = RingMemory::create(capacity, element_size, name);
  if (!memory) {
    return tl::unexpected(memory.error());
  }
  auto reader_event = make_eventfd();
  if (!reader_event) {
    return tl::unexpected(reader_event.error());
  }
  UniqueFd writer_event;
  if (writer_waits == WriterWaits::yes) {
    auto made = make_eventfd();
    if (!made) {
      return tl::unexpected(made.error());
    }
    writer_event = std::move(*made);
  }
  return SharedRing(std::move(*memory), std::move(*reader_event), std::move(writer_event));
}

IpcResult<SharedRing> SharedRing::map(UniqueFd memory, UniqueFd reader_event, UniqueFd writer_event,
                                      uint32_t element_size) {
  auto mapped = RingMemory::map(std::move(memory));
  if (!mapped) {
    return tl::unexpected(mapped.error());
  }
  if (element_size != 0 && mapped->element_size() != element_size) {
    return tl::unexpected(IpcError{EPROTO, "ring of " + std::to_string(mapped->element_size()) +
                                               "-byte elements where " +
                                               std::to_string(element_size) + " were expected"});
  }
  return SharedRing(std::move(*mapped), std::move(reader_event), std::move(writer_event));
}

IpcResult<RingPair> RingPair::create(uint32_t rx_capacity, uint32_t tx_capacity,
                                     uint32_t element_size, std::string_view prefix,
                                     std::string_view name) {
  const std::string stem = std::string(prefix) + "-";
  // canemud writes the receive ring and never waits for room there: the ring drops (and
  // counts) what does not fit.
  auto rx = SharedRing::create(rx_capacity, element_size, stem + "rx-" + std::string(name),
                               SharedRing::WriterWaits::no);
  if (!rx) {
    return tl::unexpected(rx.error());
  }
  auto tx = SharedRing::create(tx_capacity, element_size, stem + "tx-" + std::string(name));
  if (!tx) {
    return tl::unexpected(tx.error());
  }
  return RingPair(std::move(*rx), std::move(*tx));
}

IpcResult<RingPair> RingPair::map(std::vector<UniqueFd> fds, uint32_t element_size) {
  if (fds.size() != kChannelFdCount) {
    return tl::unexpected(IpcError{EPROTO, "a ring pair comes with " +
                                               std::to_string(kChannelFdCount) +
                                               " descriptors, not " + std::to_string(fds.size())});
  }
  // The order of fds(): rx memory, tx memory, rx reader, tx writer, tx reader (the doorbell).
  auto rx = SharedRing::map(std::move(fds[0]), std::move(fds[2]), UniqueFd(), element_size);
  if (!rx) {
    return tl::unexpected(rx.error());
  }
  auto tx = SharedRing::map(std::move(fds[1]), std::move(fds[4]), std::move(fds[3]), element_size);
  if (!tx) {
    return tl::unexpected(tx.error());
  }
  return RingPair(std::move(*rx), std::move(*tx));
}

}  // namespace canemu::ipc
