// What the files of the control requests share: a request's bytes as its message type (checked
// by ipc::check_message before), and a reply sent without descriptors.
#pragma once

#include <cstdint>
#include <cstring>

#include "canemu/daemon/control/control_dispatcher.hpp"

namespace canemu::daemon {

template <class T>
T read_as(const uint8_t* data) {
  T m;
  std::memcpy(&m, data, sizeof m);
  return m;
}

template <class T>
void send_reply(const ControlDispatcher::Send& send, const T& reply) {
  send(&reply, sizeof reply, {});
}

}  // namespace canemu::daemon
