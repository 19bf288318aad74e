// A client library's link to canemud, one per process: which socket (the usual search, or one
// the program named), the connection (made on the first request and again after it broke),
// and the number of that connection (its generation: a new one means canemud forgot what the
// old one held: channels, S-Links, handles). Two ways of using it:
//
// - one request at a time (the VCI libraries): a thread takes a Turn, holding the connection
//   while it sends, waits and reads (replies with descriptors, paged lists, long steps);
// - any number at once (the SORCUS libraries): a receive thread hands each reply to the thread
//   waiting for it (blocking services of several threads wait together) and each unsolicited
//   message (request id 0: callbacks, events) to a handler, in the order they came.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <cstring>
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
  // One request at a time, by whoever holds a Turn; no thread of its own.
  explicit DaemonLink(std::string client_name) : client_name_(std::move(client_name)) {}
  // Concurrent requests (call) through a receive thread, unsolicited messages to the handler.
  DaemonLink(std::string client_name, Handler on_unsolicited)
      : client_name_(std::move(client_name)),
        concurrent_(true),
        on_unsolicited_(std::move(on_unsolicited)) {}
  ~DaemonLink();
  DaemonLink(const DaemonLink&) = delete;
  DaemonLink& operator=(const DaemonLink&) = delete;

  // Drops the connection (`why`: the reason lost() gives for it from now on) and talks to
  // `socket` (empty: the usual search, ipc::socket_path) from then on. Does not connect.
  void reconnect(const std::string& socket, std::string why = {});
  // Connects unless a connection is up; the error says why not (where canemud was looked for).
  Result<void> connect();
  // Connections made so far (the current one's number; 0 before the first).
  uint64_t generation() const;
  // A connection of its own to the same canemud, named `name`: for a wait that must not hold
  // this one, or for replies that do not pass through the receive thread.
  Result<Connection> open_another(const std::string& name) const;
  // Whether connection number `generation` is gone, and why: what canemud said before it closed
  // it, that it went away, or that it is an older one. Never waits: while another thread holds
  // the connection it counts as up (that thread finds out itself).
  std::optional<std::string> lost(uint64_t generation);

  // --- one request at a time ---
  class Turn {
   public:
    Connection& connection() { return *link_->connection_; }
    uint64_t generation() const { return link_->generation_; }
    // The connection broke (`why`, for lost()): it goes; the next turn connects again.
    void drop(std::string why) { link_->drop_locked(std::move(why)); }

   private:
    friend class DaemonLink;
    Turn(DaemonLink* link, std::unique_lock<std::mutex> lock)
        : link_(link), lock_(std::move(lock)) {}
    DaemonLink* link_;
    std::unique_lock<std::mutex> lock_;
  };
  // The connection for this thread until the Turn goes, connecting first if none is up.
  Result<Turn> turn();

  // --- concurrent requests (the receive thread) ---
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
  Result<void> connect_locked();
  void drop_locked(std::string why);
  void stop_receiver(std::unique_lock<std::mutex>& lock);
  void receive_loop(int fd);

  const std::string client_name_;
  const bool concurrent_ = false;
  Handler on_unsolicited_;
  mutable std::mutex mutex_;
  std::condition_variable replied_;
  std::optional<Connection> connection_;
  std::string socket_;       // empty: ipc::socket_path()'s search
  uint64_t generation_ = 0;  // of connection_, or of the last one
  std::string lost_reason_;  // why connection number generation_ went, once it did
  // Concurrent use: the receive thread, and whether it left (the connection broke).
  std::thread receiver_;
  bool broken_ = false;
  uint32_t next_request_ = 0;
  std::map<uint32_t, Waiter*> waiters_;
};

}  // namespace canemu::client
