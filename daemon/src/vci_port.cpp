#include "canemu/daemon/vci_port.hpp"

#include <cstring>

namespace canemu::daemon {

CANMSG to_canmsg(const CANMSG2& m) {
  CANMSG c{};
  c.dwTime = m.dwTime;
  c.dwMsgId = m.dwMsgId;
  c.uMsgInfo = m.uMsgInfo;
  std::memcpy(c.abData, m.abData, sizeof c.abData);
  return c;
}

CANMSG2 to_canmsg2(const CANMSG& m) {
  CANMSG2 c{};
  c.dwTime = m.dwTime;
  c.dwMsgId = m.dwMsgId;
  c.uMsgInfo = m.uMsgInfo;
  std::memcpy(c.abData, m.abData, sizeof m.abData);
  return c;
}

tl::expected<std::unique_ptr<VciPort>, std::string> VciPort::create(bool v2, uint32_t rx_capacity,
                                                                    uint32_t tx_capacity,
                                                                    const std::string& name) {
  const uint32_t size = v2 ? sizeof(CANMSG2) : sizeof(CANMSG);
  auto rx = ipc::RingMemory::create(rx_capacity, size, "canemu-vci-rx-" + name);
  auto tx =
      ipc::RingMemory::create(tx_capacity == 0 ? 1 : tx_capacity, size, "canemu-vci-tx-" + name);
  if (!rx || !tx) {
    return tl::unexpected(!rx ? rx.error().message : tx.error().message);
  }
  auto rx_event = ipc::make_eventfd();
  auto tx_writer_event = ipc::make_eventfd();
  auto doorbell = ipc::make_eventfd();
  if (!rx_event || !tx_writer_event || !doorbell) {
    return tl::unexpected(std::string("eventfd: out of descriptors"));
  }
  return std::unique_ptr<VciPort>(new VciPort(v2, std::move(*rx), std::move(*tx),
                                              std::move(*rx_event), std::move(*tx_writer_event),
                                              std::move(*doorbell)));
}

VciPort::VciPort(bool v2, ipc::RingMemory rx_memory, ipc::RingMemory tx_memory,
                 ipc::UniqueFd rx_event, ipc::UniqueFd tx_writer_event, ipc::UniqueFd doorbell)
    : v2_(v2),
      rx_memory_(std::move(rx_memory)),
      tx_memory_(std::move(tx_memory)),
      rx_event_(std::move(rx_event)),
      tx_writer_event_(std::move(tx_writer_event)),
      doorbell_(std::move(doorbell)),
      rx_(rx_memory_, rx_event_.get(), -1),
      tx_(tx_memory_, tx_writer_event_.get(), doorbell_.get()) {}

std::size_t VciPort::bytes() const {
  return (std::size_t{rx_memory_.capacity()} + tx_memory_.capacity()) * rx_memory_.element_size();
}

std::array<int, ipc::kChannelFdCount> VciPort::client_fds() const {
  return {rx_memory_.fd(), tx_memory_.fd(), rx_event_.get(), tx_writer_event_.get(),
          doorbell_.get()};
}

bool VciPort::put(const CANMSG2& msg) {
  ipc::RingStatus status;
  if (v2_) {
    status = rx_.put(&msg);
  } else {
    const CANMSG m = to_canmsg(msg);
    status = rx_.put(&m);
  }
  if (status == ipc::RingStatus::full) {
    rx_.count_overrun();
  }
  return status == ipc::RingStatus::ok;  // corrupted: broken() tells the server
}

std::optional<CANMSG2> VciPort::peek() {
  while (true) {
    const void* element = nullptr;
    uint32_t count = 0;
    const ipc::RingStatus status = tx_.acquire(&element, &count);
    if (status == ipc::RingStatus::ok) {
      if (armed_) {
        tx_.disarm();  // busy again: the client's puts need not write the eventfd
        armed_ = false;
      }
      if (v2_) {
        CANMSG2 m;
        std::memcpy(&m, element, sizeof m);
        return m;
      }
      CANMSG m;
      std::memcpy(&m, element, sizeof m);
      return to_canmsg2(m);
    }
    if (status != ipc::RingStatus::empty || armed_) {
      return std::nullopt;  // corrupted (broken() tells the server), or asleep already
    }
    // Empty: sleep on the doorbell, unless an element came in meanwhile.
    if (tx_.arm_unless_filled()) {
      armed_ = true;
      return std::nullopt;
    }
  }
}

void VciPort::pop() {
  tx_.release(1);
}

void VciPort::kick() {
  // Always drained: a doorbell left readable would wake the loop at once, forever.
  tx_.disarm();
  armed_ = false;
  if (line_ != nullptr) {
    line_->tx_ready();
  }
}

}  // namespace canemu::daemon
