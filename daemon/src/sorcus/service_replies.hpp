// What the SORCUS services (XcanService, SlcanService) share to answer a client: a message as
// the bytes of a session's outbox, and an ErrorReply sent at once.
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

template <class T>
std::vector<uint8_t> bytes_of(const T& m) {
  std::vector<uint8_t> v(sizeof m);
  std::memcpy(v.data(), &m, sizeof m);
  return v;
}

inline void protocol_error(
    const std::function<void(const void*, std::size_t, std::span<const int>)>& send,
    uint32_t request_id, ipc::ErrorCode code, const std::string& text) {
  auto e = ipc::make_message<ipc::ErrorReply>(request_id);
  e.code = static_cast<uint32_t>(code);
  ipc::copy_name(e.message, text);
  send(&e, sizeof e, {});
}

}  // namespace canemu::daemon
