#include "canemu/daemon/vci/vci_port.hpp"

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

Result<std::unique_ptr<VciPort>> VciPort::create(bool v2, uint32_t rx_capacity,
                                                 uint32_t tx_capacity, const std::string& name) {
  const uint32_t size = v2 ? sizeof(CANMSG2) : sizeof(CANMSG);
  // A channel without a transmit FIFO still gets a ring of one page: the descriptors are the
  // same for every channel.
  auto rings = ipc::RingPair::create(rx_capacity, tx_capacity == 0 ? 1 : tx_capacity, size,
                                     "canemu-vci", name);
  if (!rings) {
    return fail(Errc::io, rings.error().message);
  }
  return std::unique_ptr<VciPort>(new VciPort(v2, std::move(*rings)));
}

VciPort::VciPort(bool v2, ipc::RingPair rings)
    : v2_(v2), rings_(std::move(rings)), rx_(rings_.rx().writer()), tx_(rings_.tx().reader()) {}

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
    if (status != ipc::RingStatus::empty || armed_ || !arming_) {
      return std::nullopt;  // corrupted (broken() tells the server), asleep already, or stepped
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

void VciPort::defer() {
  // The doorbell rings by itself: the loop serves the other clients, then kicks this port.
  tx_.wake_self();
  armed_ = true;
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
