// The machinery behind libxcan.so: one link to canemud per process (client::DaemonLink: its
// receive thread gives replies to the thread that waits for them, so blocking services of
// several threads can wait at once, and callbacks to the channel's function), the
// buffered-callback thread (client::CallbackThread), and the handles an application holds
// (modules, MDDs, channels).
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "canemu/client/callback_thread.hpp"
#include "canemu/client/daemon_link.hpp"
#include "canemu/ipc/protocol.hpp"
#include "xcan.h"

namespace canemu::client::xcan {

class Library {
 public:
  static Library& get();

  enum class Kind : uint8_t { module, mdd, channel };
  struct Handle {
    Kind kind = Kind::module;
    std::string device;
    uint32_t remote = 0;  // channel: canemud's channel id
    MAX_CALLBACK callback = nullptr;
  };

  // Drops the connection and every handle; `socket` (empty: the usual search) from now on.
  // Connects at once unless `socket` is empty.
  ULONG reconnect(const std::string& socket);

  // A new handle; 0 when there is no room.
  MAX_HANDLE add(Handle h);
  std::optional<Handle> find(MAX_HANDLE h, Kind kind);
  void remove(MAX_HANDLE h);

  // One request: ERR_OK with the reply (its `error` is the MDD's), ERR_XCAN_NO_DAEMON when
  // canemud cannot be reached or the connection broke, ERR_XCAN_NO_MODULE when canemud refused
  // the request (ErrorReply: no such device, malformed).
  ULONG call(ipc::XcanRequest& request, ipc::XcanReply& reply);

  // canemud's X-CAN-2i interfaces (canemu_xcan_enum_interfaces), asked on a connection of
  // their own (the status reply does not pass through the receive thread).
  ULONG interfaces(std::vector<CANEMU_XCAN_INTERFACE>& out);

  // The simulated instant of the callback running on this thread, if one is.
  static std::optional<int64_t> callback_time();

 private:
  Library();
  struct Queued {
    MAX_HANDLE channel;
    MAX_CALLBACK callback;
    ipc::XcanCallbackMsg message;
  };
  // Connected (the callback thread running); channels of an older connection forgotten.
  ULONG connect();
  void deliver(const ipc::XcanCallbackMsg& m);
  static void invoke(MAX_HANDLE channel, MAX_CALLBACK callback, const ipc::XcanCallbackMsg& m);

  std::mutex mutex_;
  uint64_t generation_ = 0;  // the connection the handles belong to
  std::map<MAX_HANDLE, Handle> handles_;
  MAX_HANDLE next_handle_ = 1;

  // Buffered callbacks, in order; those still queued at the end are called.
  CallbackThread<Queued> callbacks_;
  DaemonLink link_;  // last: its receive thread ends first
};

}  // namespace canemu::client::xcan
