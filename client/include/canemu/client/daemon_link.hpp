// A connection to canemud shared by the threads of a client library: a receive thread hands
// each reply to the thread waiting for it (several may wait at once) and each unsolicited
// message (request id 0: callbacks, events) to a handler, in the order they came. It connects
// on the first call and again after the connection broke.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "canemu/client/connection.hpp"

namespace canemu::client {

class DaemonLink {
 public:
  // Called on the receive thread with each unsolicited packet (checked, header included).
  using Handler = std::function<void(const std::vector<uint8_t>& packet)>;
  DaemonLink(std::string client_name, Handler on_unsolicited)
      : client_name_(std::move(client_name)), on_unsolicited_(std::move(on_unsolicited)) {}
  ~DaemonLink();
  DaemonLink(const DaemonLink&) = delete;
  DaemonLink& operator=(const DaemonLink&) = delete;

  // Drops the connection; talks to `socket` (empty: the usual search) from now on, connecting
  // at once unless it is empty. False when that connection failed.
  bool reconnect(const std::string& socket);
  // Whether a connection is up (connecting if none is).
  bool connect();
  // Connections made so far (a new one means canemud forgot what the old one held).
  uint64_t generation() const;

  enum class Outcome : uint8_t { replied, refused, no_daemon };
  // Sends `request` (its request id set here) and waits for the reply: `reply` filled when
  // the reply has Reply's type; refused for an ErrorReply (its text in `why`).
  template <class Request, class Reply>
  Outcome call(Request& request, Reply& reply, std::string* why = nullptr) {
    std::vector<uint8_t> packet;
    const Outcome o = call_raw(&request, sizeof request, request.header.request_id, packet);
    if (o != Outcome::replied) {
      return o;
    }
    ipc::MsgHeader h;
    std::memcpy(&h, packet.data(), sizeof h);
    if (h.type != static_cast<uint16_t>(ipc::type_of<Reply>()) || packet.size() != sizeof reply) {
      if (why != nullptr && h.type == static_cast<uint16_t>(ipc::MsgType::error_reply) &&
          packet.size() == sizeof(ipc::ErrorReply)) {
        ipc::ErrorReply e;
        std::memcpy(&e, packet.data(), sizeof e);
        *why = ipc::name_of(e.message);
      }
      return Outcome::refused;
    }
    std::memcpy(&reply, packet.data(), sizeof reply);
    return Outcome::replied;
  }

 private:
  struct Waiter {
    bool done = false;
    bool lost = false;
    std::vector<uint8_t> packet;
  };
  Outcome call_raw(const void* request, std::size_t size, uint32_t& request_id,
                   std::vector<uint8_t>& reply);
  bool connect_locked();
  void disconnect_locked();
  void receive_loop(int fd);

  std::string client_name_;
  Handler on_unsolicited_;
  mutable std::mutex mutex_;
  std::condition_variable replied_;
  std::optional<Connection> connection_;
  std::string socket_;
  std::thread receiver_;
  bool broken_ = false;
  uint64_t generation_ = 0;
  uint32_t next_request_ = 0;
  std::map<uint32_t, Waiter*> waiters_;
};

}  // namespace canemu::client
