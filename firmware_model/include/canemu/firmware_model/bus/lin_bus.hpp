// The LIN bus engine: one wire, frames as events at their exact instants (lin_frame.hpp).
//
// A commander asks for a header (and, publishing itself, its response); at the header's end
// every node that synchronized on it is asked whether its response table holds the identifier;
// the responders' characters go on the wire one by one, wired-AND (dominant 0 wins), and a
// responder that reads back another character than it sent has a bit error and stops after
// that character. Listeners then check the checksum. Nobody answering is a no-response error
// after the longest response time. Wake-up pulses, the go-to-sleep command and 4 s of bus
// inactivity are reported as events; what a node does about them is its own business (an IXXAT
// LIN controller keeps answering; a simulated ECU may sleep).
//
// Decisions where LIN leaves the emulation free, written down in docs/lin.md:
// - A listener whose bit rate differs from the header's by more than 14 % cannot synchronize on
//   the sync byte (LIN's tolerance for an unsynchronized responder): it reports a sync error
//   and takes no part in the frame; within 14 % it synchronizes and works at the header's rate.
//   A node with bit rate 0 detects the rate from the sync byte (LIN_BITRATE_AUTO).
// - A listener does not know the response's length and kind: it takes the last character as
//   the checksum and reports the frame with the kind that matches (enhanced first), or a
//   checksum error when neither does.
// - Requests are served one at a time in the order they came (two commanders on one bus are
//   not detected); a request while a frame runs starts when the bus is free again.
// - The no-response error comes at the header's end + the maximum response time of the longest
//   response (8 bytes) unless the commander said how long it expects (schedules know it).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "canemu/firmware_model/bus/bus_load.hpp"
#include "canemu/firmware_model/bus/lin_frame.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::model::lin {

using LinNodeId = uint32_t;
inline constexpr LinNodeId kNoNode = 0xFFFFFFFFu;

// A response: what a response table entry, or a commander publishing a frame, sends.
struct Response {
  std::array<uint8_t, kMaxData> data{};
  uint8_t size = 0;  // 1..8
  Checksum checksum = Checksum::enhanced;
};

// Error kinds, as a LIN controller reports them (the VCI's LIN_ERROR_* names them alike).
enum class ErrorKind : uint8_t {
  bit = 1,          // what the node sent is not what it read back
  checksum = 2,     // the response's checksum does not match
  parity = 3,       // the protected identifier's parity bits are wrong
  no_response = 4,  // a header nobody answered
  sync = 5,         // the sync byte could not be used (corrupted, or the bit rate is too far off)
  inactive = 6,     // 4 s without activity on the bus
  other = 7,        // a break too short to be seen as one
};

struct Event {
  enum class Kind : uint8_t {
    frame,   // a complete frame: id, data, checksum kind, sender, responder
    error,   // `error` at `at` (id when known, else kNoId)
    wakeup,  // a wake-up pulse from `sender` ended
    sleep,   // the go-to-sleep command (a frame 0x3C with data[0] = 0) ended
  };
  static constexpr uint8_t kNoId = 0xFF;
  Kind kind = Kind::frame;
  SimTime at;
  uint8_t id = kNoId;
  Response response;              // frame: its data, size and checksum kind; checksum error: the
                                  // data characters received (size 0..8)
  uint8_t checksum_byte = 0;      // frame and checksum error: the last character received
  LinNodeId sender = kNoNode;     // who sent the header (or the wake-up pulse)
  LinNodeId responder = kNoNode;  // who sent the response (frame): the first in node order
  // frame: every node that sent the whole response. Several when their characters were the
  // same (identical bits on the wire collide into no error: each sent all of them, as on a
  // real bus, so each sees the frame as its own).
  std::vector<LinNodeId> responders;
  bool responded(LinNodeId n) const {
    return std::find(responders.begin(), responders.end(), n) != responders.end();
  }
  ErrorKind error = ErrorKind::other;
  uint32_t bitrate = 0;  // the frame's (the commander's) bit rate; 0 for bus inactivity
};

// A node on the bus: a controller, or a simulated ECU.
class LinNode {
 public:
  virtual ~LinNode() = default;
  // The response this node sends for `id` at this header (its response table), if any.
  virtual std::optional<Response> respond(uint8_t id) = 0;
  virtual void on_lin_event(const Event& e) = 0;
  // The node's bit rate, 0 to take it from each header's sync byte.
  virtual uint32_t lin_bitrate() const = 0;
};

// What a fault does to one frame, asked for at the header's start (bus/fault_plan's LIN part,
// docs/faults.md).
struct FrameFaults {
  bool short_break = false;         // the break is too short: listeners see no frame (error other)
  bool sync_error = false;          // the sync byte is corrupted: listeners report a sync error
  bool parity_error = false;        // the identifier goes with wrong parity bits
  bool header_bit_error = false;    // a header bit flips: the commander sees a bit error and
                                    // listeners a parity error
  bool no_response = false;         // the responders stay silent
  bool checksum_error = false;      // the responder sends a wrong checksum
  bool response_bit_error = false;  // a bit of the first response character flips: the
                                    // responder sees a bit error and stops there
  LinNodeId silent = kNoNode;       // this responder does not answer (it is switched off)
};

class LinFaultSource {
 public:
  virtual FrameFaults faults_for(SimTime at, uint8_t id, LinNodeId sender) = 0;

 protected:
  ~LinFaultSource() = default;
};

struct LinBusStats {
  uint64_t frames = 0;   // complete frames (checksum correct)
  uint64_t headers = 0;  // headers sent
  uint64_t errors = 0;   // frames with an error (no response, checksum, parity, ...)
  uint64_t wakeups = 0;
  uint64_t busy_ns = 0;  // time the wire carried frames, since the start
};

class LinBus final : private EventHandler {
 public:
  // `layout`: the bus's break, delimiter and spaces (its bit rate is each commander's own).
  LinBus(SimScheduler& scheduler, Layout layout);
  LinBus(const LinBus&) = delete;
  LinBus& operator=(const LinBus&) = delete;
  ~LinBus();

  LinNodeId attach(LinNode& node);
  // The node leaves: its request is dropped, it is asked and told nothing more.
  void detach(LinNodeId node);

  // One request per node at a time (the controller's one transmit buffer): false while the
  // node's previous request is not done. The frame goes at the requesting node's bit rate
  // (the layout's when the node has none).
  bool send_header(LinNodeId from, uint8_t id, std::optional<uint8_t> expected_size = {});
  bool send_frame(LinNodeId from, uint8_t id, const Response& response);
  bool send_sleep(LinNodeId from);  // 0x3C 00 FF FF FF FF FF FF FF, classic checksum
  bool send_wakeup(LinNodeId from, SimDuration pulse);
  bool pending(LinNodeId node) const;
  // The node's request is dropped if it has not started (a controller reset).
  void withdraw(LinNodeId node);

  void set_fault_source(LinFaultSource* faults) { faults_ = faults; }

  const Layout& layout() const { return layout_; }
  const LinBusStats& stats() const { return stats_; }
  // The load as on a CAN bus (bus/bus_load.hpp): over the last second, and in 100 ms bins.
  double load_percent(SimTime now) const { return load_.percent(now); }
  std::vector<BusLoad::Bin> load_history(SimTime now) const { return load_.history(now); }
  bool busy() const { return busy_; }
  SimScheduler& scheduler() { return scheduler_; }

  static constexpr uint32_t kSyncTolerancePercent = 14;
  static constexpr SimDuration kInactivity = seconds(4);
  static constexpr SimDuration kMinWakeup = microseconds(150);  // what a listener recognizes

 private:
  enum class RequestKind : uint8_t { header, frame, wakeup };
  struct Request {
    RequestKind kind = RequestKind::header;
    LinNodeId from = kNoNode;
    uint8_t id = 0;
    std::optional<uint8_t> expected_size;
    std::optional<Response> response;  // frame: the commander publishes
    SimDuration pulse;
  };
  struct Slot {
    LinNode* node = nullptr;
    bool pending = false;
  };
  enum Tag : uint64_t {
    tag_next = 1,
    tag_header_end,
    tag_response_end,
    tag_no_response,
    tag_wakeup_end,
    tag_inactive
  };

  bool enqueue(Request r);
  void start_next(SimTime now);
  void on_event(SimTime now, uint64_t tag) override;
  void header_end(SimTime now);
  void response_end(SimTime now);
  void finish(SimTime now);
  void deliver(const Event& e, const std::vector<LinNodeId>& to);
  bool synchronizes(LinNodeId node, uint32_t rate) const;
  std::vector<LinNodeId> live_nodes() const;

  SimScheduler& scheduler_;
  Layout layout_;
  std::vector<Slot> nodes_;
  std::deque<Request> queue_;
  LinFaultSource* faults_ = nullptr;
  LinBusStats stats_;
  BusLoad load_;

  // The frame on the wire.
  bool busy_ = false;
  Request current_;
  SimTime started_;
  uint32_t rate_ = 0;
  FrameFaults frame_faults_;
  std::vector<LinNodeId> synced_;          // the listeners (and the commander) in this frame
  std::vector<uint8_t> wire_;              // the response characters as the wire carried them
  std::vector<LinNodeId> bit_errors_;      // responders that read back something else
  LinNodeId responder_ = kNoNode;          // the responder that completed the response
  std::vector<LinNodeId> responders_;      // every one that did (node order)
  std::optional<EventId> step_;            // the frame's next event
  std::vector<EventId> bit_error_events_;  // responders' bit errors still to come
  std::optional<EventId> inactivity_;
};

}  // namespace canemu::model::lin
