// The CAN bus engine: arbitration, acknowledgement, error signalling and fault confinement
// between the controllers attached to one bus, in simulated time.
//
// What is exact and what is approximated is in docs/bus-engine.md. In short: a frame without
// errors is resolved at its start of frame from the bit sequences of all transmitters
// (arbitration bit by bit, wired-AND), and completes at the end of its EOF; nobody pays per
// bit. When any node detects an error, the bits from the first detection to the end of the
// error delimiter are simulated one by one for every node (error flags, superposition,
// delimiters, the counter rules that depend on what each node sees).
//
// CanBus owns the timeline, the nodes' cached state, fault confinement bookkeeping and bus-off
// recovery; the decisions within one frame are separate pieces it drives: Arbitration (who
// sends), FrameRoles (who acknowledges, who will detect what), ErrorPhase (the bits from the
// first detection on) and BusLoad.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "canemu/firmware_model/bus/arbitration.hpp"
#include "canemu/firmware_model/bus/bus_load.hpp"
#include "canemu/firmware_model/bus/can_controller.hpp"
#include "canemu/firmware_model/bus/error_phase.hpp"
#include "canemu/firmware_model/bus/frame_roles.hpp"
#include "canemu/firmware_model/bus/node_list.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::model {

class CanBus;

struct FrameContext {
  SimTime sof;
  NodeId transmitter;
  const Frame& frame;
  const EncodedFrame& bits;
};

// Consulted by the bus at its injection points. The default does nothing.
class FaultInjector {
 public:
  virtual ~FaultInjector() = default;
  // Whenever the bus is free and about to look for transmitters: node-level faults (unplug,
  // oscillator, counters) applied here take effect from this start of frame on.
  virtual void before_arbitration(SimTime /*now*/, CanBus& /*bus*/) {}
  // At every start of frame that wins arbitration, while frames_wanted().
  virtual FrameFault on_frame(const FrameContext&) { return {}; }
  // Whether on_frame() may return a fault: an injector with nothing to inject says so, and the
  // bus spares every frame the call (a bus with a fault plan and no rules, the common case).
  bool frames_wanted() const { return frames_wanted_; }

 protected:
  void set_frames_wanted(bool wanted) { frames_wanted_ = wanted; }

 private:
  bool frames_wanted_ = true;
};

struct ErrorCounts {
  uint64_t bit = 0, stuff = 0, form = 0, crc = 0, ack = 0;
  uint64_t& operator[](CanErrorType t);
  uint64_t total() const { return bit + stuff + form + crc + ack; }
};

struct StateChange {
  SimTime at;
  ErrorState state;
};

// Why a node's error counters changed: a frame that went well (each counts one down), an error
// it detected (which, in what role), a dominant-bit sequence after its error flag, the end of
// bus-off recovery, or a direct write (SJA1000 TXERR/RXERR, a fault scenario).
enum class CounterCause : uint8_t { success, error, severe, recovered, written };

constexpr std::string_view to_string(CounterCause c) {
  switch (c) {
    case CounterCause::success:
      return "success";
    case CounterCause::error:
      return "error";
    case CounterCause::severe:
      return "severe";
    case CounterCause::recovered:
      return "recovered";
    case CounterCause::written:
      return "written";
  }
  return "?";
}

struct CounterSample {
  SimTime at;
  uint16_t tec = 0;
  uint16_t rec = 0;
  ErrorState state = ErrorState::active;
  CounterCause cause = CounterCause::success;
  CanErrorType error = CanErrorType::bit;   // cause error: what was detected
  ErrorRole role = ErrorRole::transmitter;  // cause error or severe
};

// A node's error counters and state over time (`canemu timeline`): every change, by an error, a
// good frame, a recovery or a write, at its instant; the newest kSamples, with the number of
// older ones forgotten.
class CounterTimeline {
 public:
  static constexpr std::size_t kSamples = 1024;
  void add(const CounterSample& s);
  const std::deque<CounterSample>& samples() const { return samples_; }
  uint64_t forgotten() const { return forgotten_; }

 private:
  std::deque<CounterSample> samples_;
  uint64_t forgotten_ = 0;
};

struct NodeStats {
  uint64_t frames_sent = 0;
  uint64_t frames_received = 0;
  uint64_t arbitration_lost = 0;
  uint64_t tx_dropped = 0;
  ErrorCounts errors_as_transmitter;
  ErrorCounts errors_as_receiver;
  std::vector<StateChange> state_changes;
  CounterTimeline timeline;
};

// One line of what happened on the wire, for traces and tests.
struct BusEvent {
  enum class Kind : uint8_t { frame, error_frame, bus_held };
  Kind kind = Kind::frame;
  SimTime start;  // SOF (or start of the dominant hold)
  SimTime end;    // end of EOF, or end of the error delimiter
  NodeId transmitter = 0;
  std::optional<Frame> frame;
  uint16_t error_bit = 0;  // first detection
};

class CanBus final : private EventHandler {
 public:
  CanBus(SimScheduler& scheduler, std::string name);
  ~CanBus();
  CanBus(const CanBus&) = delete;
  CanBus& operator=(const CanBus&) = delete;

  const std::string& name() const { return name_; }
  SimTime now() const { return scheduler_.now(); }
  // Whether `node`'s pending frame is on the wire right now (from its start of frame to the end
  // of the frame or error frame).
  bool in_flight(NodeId node) const;

  NodeId attach(CanController& controller);
  std::size_t node_count() const { return node_count_; }

  // The controller has a new or changed pending_tx() (or wants to try again).
  void tx_changed(NodeId node);
  // Something the bus asks the controller changed: timing(), participating(), listen_only(),
  // self_test(), fd_capable() or bus_off_recovery(). The bus caches these and reads them again
  // only after this call, so a controller must make it whenever one of them changes.
  void controller_changed(NodeId node);
  // A controller with BusOffRecovery::on_restart was restarted: recovery counting begins.
  void restart(NodeId node);
  // The controller's counters were written directly (SJA1000 RXERR/TXERR in reset mode): the
  // state they give is reported as any other change.
  void counters_changed(NodeId node);

  // --- fault injection (programmatic API) ---
  void set_injector(FaultInjector* injector) { injector_ = injector; }
  // Transceiver unplugged (false) or back (true).
  void set_connected(NodeId node, bool connected);
  bool connected(NodeId node) const { return nodes_[node].connected; }
  void set_oscillator_ppm(NodeId node, int32_t ppm);
  // No node acknowledges anything from now until `until`.
  void suppress_acks_until(SimTime until) { ack_suppressed_until_ = until; }
  // The bus is held dominant from `from` for `duration` (a shorted or stuck transceiver).
  void hold_dominant(SimTime from, SimDuration duration);

  // --- observation ---
  const NodeStats& stats(NodeId node) const { return nodes_[node].stats; }
  // Zeroes a node's statistics (a reused node starts afresh).
  void reset_stats(NodeId node) { nodes_[node].stats = NodeStats{}; }
  // Busy time (start of frame to end of intermission) over the second before `now`, percent.
  double bus_load_percent(SimTime now) const { return bus_load_.percent(now); }
  std::vector<BusLoad::Bin> bus_load_history(SimTime now) const { return bus_load_.history(now); }
  uint64_t frames_on_bus() const { return frames_on_bus_; }
  uint64_t error_frames_on_bus() const { return error_frames_on_bus_; }
  // Called for every frame and error frame, in order.
  std::function<void(const BusEvent&)> on_bus_event;

 private:
  struct Node {
    CanController* controller = nullptr;
    FaultConfinement* fc = nullptr;  // the controller's counters (a stable reference)
    // Cached controller properties, read again after controller_changed().
    bool props_known = false;
    bool participating = true;
    bool timing_valid = true;  // a bit time that is not zero
    bool listen_only = false;
    bool self_test = false;
    bool fd_capable = false;
    BusOffRecovery recovery = BusOffRecovery::automatic;
    bool connected = true;
    int32_t oscillator_ppm = 0;
    SimTime ready_at;  // suspend transmission of error-passive transmitters
    // pending_tx() and its encoding, cached until the controller reports a change or the bus
    // finishes with the frame.
    bool tx_known = false;
    const TxFrame* tx = nullptr;
    bool encoded_valid = false;
    // Whether `encoded` is whole, or its first word only (encode_head): enough for a frame's
    // start and end without errors, and for FrameRoles (fields and positions in the first word;
    // CAN FD frames are always whole). whole_encoding() completes it where more is read: the
    // arbitration's long walk, an injector's look at the frame, the error phase.
    bool encoded_whole = false;
    EncodedFrame encoded;
    std::optional<Frame> encoded_frame;  // what `encoded` encodes (kept across frames)
    ErrorState last_state = ErrorState::active;
    // Timing as last seen (controller timing plus injected oscillator offset) and what follows
    // from it; refreshed when it changes.
    NodeTiming timing;
    TimingProfile profile;
    int64_t bit_ns = 0;  // nominal bit time when it is a whole number of ns (no ppm offset), or 0
    bool timing_known = false;
    uint16_t reported_tec = 0;  // counters at the last state report
    uint16_t reported_rec = 0;
    // Bus-off recovery bookkeeping.
    SimTime recovery_from;  // recessive bits count from here
    EventId recovery_event = 0;
    NodeStats stats;
  };

  // Events the bus schedules on itself, by tag.
  enum EventTag : uint64_t { kAttempt = 1, kFrameEnd = 2, kBusFree = 3 };
  void on_event(SimTime now, uint64_t tag) override;
  // A frame's end, and the bus free after it, are due at `at`. From on_event() they are run by
  // its loop, at once when SimScheduler::run_inline() allows it and scheduled otherwise, once
  // the event that made them due has done all its work; from anywhere else they are scheduled.
  void follow_up(SimTime at, EventTag tag) {
    if (handling_) {
      follow_at_ = at;
      follow_tag_ = tag;
    } else {
      scheduler_.schedule_at(at, *this, tag);
    }
  }
  bool handling_ = false;  // on_event() runs
  SimTime follow_at_;
  uint64_t follow_tag_ = 0;  // 0: none

  // The frame on the bus between its start and its completion.
  struct Completion {
    SimTime sof;
    SimTime eof_end;
    SimTime ifs_end;
    SimTime last_dominant_end;
    BitTiming nominal;
    int32_t ppm = 0;
    int64_t bit_ns = 0;  // the transmitter's Node::bit_ns
    // The transmitters' frames (in_flight_ order): their pending_tx(), valid until they are told
    // the frame is done.
    NodeList<const TxFrame*> sent;
  };
  // The end of bit `bit` of the arbitration field of the frame on the bus, by its transmitter's
  // clock: the instant of a loss there (the bits before a data phase are nominal).
  SimTime arbitration_bit_end(uint16_t bit) const {
    const Completion& c = completion_;
    if (c.bit_ns != 0) {
      return c.sof + SimDuration(c.bit_ns * (int64_t{bit} + 1));
    }
    return arbitration_bit_end_slow(bit);
  }
  SimTime arbitration_bit_end_slow(uint16_t bit) const;

  // A node that may be on the bus (connected, participating, with a usable bit time) and what a
  // start of frame needs of it. The list (in node order) is rebuilt at the first look after
  // anything it depends on changes: attach(), controller_changed(), set_connected(). Bus-off and
  // error-passive are read from the counters at every frame, since they change with errors and
  // may be written directly.
  struct Member {
    Node* node = nullptr;  // into nodes_, which attach() (the only reallocation) invalidates
    NodeId id = 0;
    bool listen_only = false;
    bool self_test = false;
    bool fd_capable = false;
    // Its part as an error-active receiver that follows the frame and has nothing planned.
    BusParticipant receiver;
  };
  const std::vector<Member>& members() {
    if (!members_valid_) {
      load_members();
    }
    return members_;
  }
  void load_members();
  void members_changed() {
    members_valid_ = false;
    plain_valid_ = false;
  }
  // run_frame's roles for a frame with one sender, no injected fault and acknowledgements
  // allowed (nearly every frame): what FrameRoles gives, built directly from the members.
  std::optional<uint16_t> plain_roles(NodeId tx, const EncodedFrame& e, bool fd, bool brs);
  // Whether parts_ holds plain_roles()'s result for a frame of `tx` with this fd and brs, every
  // member still as bus-off and error-passive as then: checked inline on every frame.
  bool plain_roles_kept(NodeId tx, bool fd, bool brs) const {
    if (!plain_valid_ || plain_tx_ != tx || plain_fd_ != fd || plain_brs_ != brs) {
      return false;
    }
    // Each count only grows: their sum is as it was only if every one is.
    uint64_t changes = 0;
    for (const FaultConfinement* fc : plain_checks_) {
      changes += fc->passive_or_off_changes();
    }
    return changes == plain_changes_;
  }
  // The same for any frame, through FrameRoles: `fault` injected, acknowledgements suppressed,
  // several senders. Both fill parts_ and return the first detection, if any.
  std::optional<uint16_t> general_roles(NodeId tx, const EncodedFrame& e, const FrameFault& fault,
                                        bool acks_suppressed);

  NodeTiming timing_of(const Node& n) const;
  const Node& refresh_timing(NodeId id) {
    const Node& n = nodes_[id];
    return n.timing_known ? n : load_timing(id);
  }
  const Node& load_timing(NodeId id);
  // Cached controller state, loaded on first use after a change (fast paths inline).
  Node& refresh(NodeId id) {
    Node& n = nodes_[id];
    if (!n.props_known) {
      load_props(n);
    }
    return n;
  }
  const TxFrame* pending(Node& n) {
    if (!n.tx_known) {
      load_tx(n);
    }
    return n.tx;
  }
  const EncodedFrame& encoded_tx(NodeId id) {
    Node& n = nodes_[id];
    if (!n.encoded_valid) {
      load_encoding(n);
    }
    return n.encoded;
  }
  bool on_bus(const Node& n) const {
    return n.connected && n.participating && n.timing_valid && !n.fc->bus_off();
  }
  bool can_transmit(Node& n) { return on_bus(n) && !n.listen_only && pending(n) != nullptr; }
  bool decodes(NodeId tx, NodeId rx, bool brs) {
    const std::size_t n = node_count_;
    if (!decodes_cache_.empty()) {
      const int8_t c = decodes_cache_[(brs ? n * n : 0) + tx * n + rx];
      if (c >= 0) {
        return c == 1;
      }
    }
    return decodes_slow(tx, rx, brs);
  }
  // The row of decodes_cache_ for transmitter `tx`, or nullptr while the cache is empty.
  const int8_t* decodes_row(NodeId tx, bool brs) const {
    const std::size_t n = node_count_;
    return decodes_cache_.empty() ? nullptr : decodes_cache_.data() + (brs ? n * n : 0) + tx * n;
  }
  void load_props(Node& n);
  void load_tx(Node& n);
  void load_encoding(Node& n);
  // `n`'s encoding (valid), whole.
  const EncodedFrame& whole_encoding(Node& n) {
    if (!n.encoded_whole) {
      make_whole(n);
    }
    return n.encoded;
  }
  void make_whole(Node& n);
  // The encodings of the nodes in arbitration_.senders(), whole.
  void senders_whole();
  bool decodes_slow(NodeId tx, NodeId rx, bool brs);

  static void forget_tx(Node& n) {
    n.tx_known = false;
    n.encoded_valid = false;
  }

  void schedule_attempt(SimTime at);
  void attempt(SimTime now);
  // Arbitration losses of the frame on the bus (arbitration_.lost()) are reported at its end, or
  // at the latest of their instants when an error frame follows, each at its own instant: then
  // only those before the first detection (join_late_contenders).
  // These four are inlined into their callers in can_bus.cpp (the frame's start into attempt(),
  // its end into on_event()), the only file that calls them.
  [[gnu::always_inline]] inline void run_frame(SimTime sof);
  [[gnu::always_inline]] inline void finish_success(SimTime sof, NodeId tx,
                                                    const BitTiming& nominal,
                                                    const BitTiming& data);
  [[gnu::always_inline]] inline void complete_success(SimTime eof_end);
  [[gnu::always_inline]] inline void report_losses();
  // Whether the frame with which `n` lost arbitration in the frame on the bus is still the one
  // it has pending: a single shot is dropped only then. A controller may withdraw or replace it
  // before the loss is reported (the end of the frame).
  bool still_pending(Node& n);
  // An error detected at `first_bit` of the frame: contenders that had not lost by then send
  // too (in_flight_, parts_); their losses are forgotten, the others' counted.
  void join_late_contenders(NodeId tx, const FrameFault& fault, bool acks_suppressed,
                            uint16_t first_bit);
  // Plays the bits from `first_bit` on (ErrorPhase) and schedules what follows from them.
  void run_error_phase(SimTime sof, std::span<const BusParticipant> parts, const EncodedFrame* bits,
                       const BitTiming& nominal, const BitTiming& data, uint16_t first_bit);
  void apply(SimTime now, const ErrorPhase::Action& action, const std::optional<Frame>& frame);
  void run_hold(SimTime now);

  void bus_released(SimTime last_dominant_end, SimTime idle_at);
  void account_recessive(SimTime dominant_start);
  void arm_recovery(NodeId id);
  void recovery_check(NodeId id, SimTime now);
  // `why`: the cause of a counter change (its time and counters are filled in here).
  void report_state(NodeId id, SimTime at, CounterSample why = {});
  // report_state() without a cause, skipped inline when it would do nothing (counters as last
  // reported, not bus-off): after most frames.
  void report_if_changed(NodeId id, SimTime at) {
    const Node& n = nodes_[id];
    if (n.fc->tec() != n.reported_tec || n.fc->rec() != n.reported_rec || n.fc->bus_off()) {
      report_state(id, at);
    }
  }
  void recovered(NodeId id, SimTime at);
  // Whole bits of `node`'s own bit time in `span`, rounded to the nearest bit.
  uint64_t bits_in(NodeId node, SimDuration span);

  SimScheduler& scheduler_;
  std::string name_;
  std::vector<Node> nodes_;
  // nodes_.size(), kept apart: a Node is large and of odd size, so size() would divide.
  std::size_t node_count_ = 0;
  FaultInjector* injector_ = nullptr;
  SimTime ack_suppressed_until_;

  // Bus activity.
  bool busy_ = false;
  // Set whenever a node may have begun bus-off recovery; cleared when a look finds none, so the
  // per-frame recovery bookkeeping costs nothing on a healthy bus.
  bool maybe_recovering_ = false;
  // Transmitters of the current activity: arbitration_.senders(), which no arbitration changes
  // before the bus is free again, or error_senders_: those and the contenders still sending when
  // an error came (join_late_contenders). Empty for a dominant hold.
  std::span<const NodeId> in_flight_;
  std::vector<NodeId> error_senders_;
  SimTime free_at_;            // end of intermission of the last activity
  SimTime last_dominant_end_;  // recessive run on the wire started here
  EventId attempt_event_ = 0;
  bool attempt_pending_ = false;
  SimTime attempt_at_;
  std::vector<DominantHold> holds_;  // pending dominant holds

  // Scratch space reused from frame to frame, and the frame in flight.
  Arbitration arbitration_;
  bool arbitration_room_due_ = false;  // a node attached while busy (attach())
  std::vector<BusParticipant> parts_;
  // Of parts_, the receivers that follow the frame (not its senders), in the same order: what
  // the frame's successful end goes through. Pointers into nodes_: attach() re-points them.
  struct Receiver {
    Node* node;
    NodeId id;
    bool acks;
  };
  NodeList<Receiver> receivers_;
  Completion completion_;
  std::vector<Member> members_;
  bool members_valid_ = false;
  // The last plain_roles() result, kept while it can be used again: a frame of the same sender
  // (fd and brs alike) to the same members, each still as bus-off and error-passive as then, and
  // nobody with an error planned. Forgotten whenever the members or their timings change, and
  // when general_roles() fills parts_.
  bool plain_valid_ = false;
  NodeId plain_tx_ = 0;
  bool plain_fd_ = false;
  bool plain_brs_ = false;
  // Each member's counters, and the sum of their passive_or_off_changes() then.
  std::vector<const FaultConfinement*> plain_checks_;
  uint64_t plain_changes_ = 0;
  // decodes(tx, rx, brs) for every pair: -1 unknown, 0 no, 1 yes; cleared on timing changes.
  std::vector<int8_t> decodes_cache_;

  BusLoad bus_load_;
  uint64_t frames_on_bus_ = 0;
  uint64_t error_frames_on_bus_ = 0;
};

// A controller withdraws its pending frame `tx` (an abort command, a reset). One already on the
// wire completes, since its outcome was fixed at its start of frame, but is not repeated: `tx`
// stays, now single shot, and the result is false. One not yet started is gone: `tx` is
// cleared, the bus (if any) is told, and the result is true.
bool withdraw_tx(CanBus* bus, NodeId node, std::optional<TxFrame>& tx);

}  // namespace canemu::model
