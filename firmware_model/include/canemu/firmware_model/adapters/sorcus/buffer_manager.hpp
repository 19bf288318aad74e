// The SORCUS buffer manager of one Intel 82527, shared by the X-CAN-2i module driver (MDD) and
// the SL-CANi driver task (SL64TASK): both manuals describe it in the same words (digest §1.4,
// §1.5). It programs the chip's 15 buffers for the driver's message objects and serves its
// interrupt:
// - with at most 14 objects each has a buffer of its own among 1..14;
// - beyond, exclusive objects keep one of buffers 1..13 (at most 13 of them), passive
//   non-exclusive objects share the receive-only buffer 15 behind the automatic acceptance
//   filter (acceptance.hpp), Data-only or Remote-only, and everything else is sent through the
//   temporary pool (the rest of 1..14); a request waits in the driver FIFO when no temporary
//   buffer is free, holding the object, not its data;
// - a manual acceptance mask on buffer 15 (the X-CAN filter device, sl064_set_acceptance_mask).
//
// The owner (the adapter firmware) keeps what its API adds to an object (roles as its API names
// them, callbacks, counters) in a vector parallel to objects(): objects are only appended, and
// removed all at once by reset().
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <vector>

#include "canemu/firmware_model/adapters/sorcus/acceptance.hpp"
#include "canemu/firmware_model/chips/i82527/i82527.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"

namespace canemu::model::sorcus {

// A message object as the buffer manager sees it. X-CAN roles: active send = send + active,
// passive send = send + passive, active receive = active, passive receive = passive. SL-CANi
// objects may combine both (send + active + passive: sent on request and answering remote
// frames).
struct ManagedObject {
  uint32_t id = 0;
  bool extended = false;
  bool send = false;     // a data frame goes out (else: a receive object, remote frames out)
  bool active = false;   // the application starts its traffic
  bool passive = false;  // another node does: its remote frame (send), its data frame (receive)
  bool excl = false;     // an exclusive buffer (XCAN_EXCL_BUFFER, _SL064_EXCL_BUFFER)
  bool general = false;  // the X-CAN general-ID channel: its buffer is loaded per message
  // SL-CANi _SL064_DISABLE_INT: a later request for another object may take over the temporary
  // buffer of its pending request (it is dropped).
  bool preemptible = false;
  uint8_t size = 0;
  std::array<uint8_t, 8> data{};
  uint8_t buffer = 0;  // its own buffer 1..14, 15 (receive-only), or 0 (temporary pool)
};

// A frame sent without an object (the X-CAN general-ID channel).
struct DirectMessage {
  uint32_t id = 0;
  bool extended = false;
  bool remote = false;
  uint8_t size = 0;  // DLC
  std::array<uint8_t, 8> data{};
};

// A send request: an object's data frame or remote frame, or a direct message.
struct SendRequest {
  int object = -1;
  bool remote = false;
  std::optional<DirectMessage> message;
};

// What a buffer holds, for tests and status views.
struct BufferView {
  enum class Use : uint8_t { unused, own, exclusive, temporary, general, receive_only };
  Use use = Use::unused;
  std::optional<uint32_t> id;  // the object programmed into it (temporary: the cached one)
  bool busy = false;           // a driver request waits for its acknowledgement
};

// The manual override of buffer 15.
struct ManualFilter {
  bool open = false;             // a filter channel is open / a mask was set
  bool remote = false;           // buffer 15 takes remote frames (else data frames)
  bool extended = false;         // its format when no object is in buffer 15
  std::optional<uint32_t> mask;  // 1 = compare; unset: FFFFFFFFh
  std::optional<uint32_t> id;    // compared with; unset: the automatic ID mask (or 0)
};

enum class PlanError : uint8_t { none, excl_limit, no_memory, buffer15_mixed };
enum class RequestResult : uint8_t { started, queued, merged, fifo_full };

class BufferEvents {
 public:
  // The status change interrupt: the owner reads STATUS itself.
  virtual void status_changed() = 0;
  // A request's frame went (acknowledged, error-free); `answered`: a passive send object's
  // data frame answering a remote frame in hardware, with no request of the driver.
  virtual void sent(const SendRequest& request, bool answered) = 0;
  // A data frame for a configured object, from its buffer or from buffer 15; `lost`: the
  // buffer had lost a frame before it (MsgLst).
  virtual void received(int object, const Frame& frame, bool lost) = 0;
  // A frame buffer 15 took that matches no object.
  virtual void unconfigured(const Frame& frame) = 0;
  // True while the driver holds its interrupt back (SL-CANi sl064_enable_int_mask): the
  // service stops and the chip keeps what it receives.
  virtual bool hold() const { return false; }

 protected:
  ~BufferEvents() = default;
};

// The status change interrupt as both drivers serve it: STATUS read (which ends the source),
// TXOK/RXOK reset and LEC set to 7 (to see whether a new code comes); `error_bits` (WARN |
// BOFF as last served) and `last_lec` (the last real error code) updated. Returns the bits of
// WARN and BOFF that rose.
uint8_t serve_status_register(I82527& chip, uint8_t& error_bits, uint16_t& last_lec);

class BufferManager {
 public:
  static constexpr std::size_t kMaxExclusive = 13;

  BufferManager(I82527& chip, BufferEvents& events, std::size_t fifo_depth, std::size_t max_objects)
      : chip_(chip), events_(events), fifo_depth_(fifo_depth), max_objects_(max_objects) {}
  BufferManager(const BufferManager&) = delete;
  BufferManager& operator=(const BufferManager&) = delete;
  ~BufferManager();

  // Loading an object into a buffer (an object not cached there, or a direct message) takes
  // `ns` on `scheduler` before its transmit request; 0 (the default): at once.
  void set_load_time(SimScheduler& scheduler, int64_t ns) {
    scheduler_ = &scheduler;
    load_ns_ = ns;
  }
  int64_t load_time() const { return load_ns_; }

  // As the driver starts the chip: configuration access, the clock divider, global masks
  // "every bit must match", every object invalid, interrupts enabled, still off the bus (INI).
  void init_chip(bool divide_clock);
  // BIT_TIMING0/1 from `timing` (tq = prescaler clock periods), INI kept as it is.
  void program_timing(const BitTiming& timing);
  // CONTROL with interrupts enabled; `on` clears INI.
  void set_bus_on(bool on);

  const std::vector<ManagedObject>& objects() const { return objects_; }
  ManagedObject& object(int k) { return objects_[static_cast<std::size_t>(k)]; }
  int find(uint32_t id, bool extended) const;
  // Whether `added` (or nothing, to check a change of the manual filter) fits the plan.
  PlanError check(const ManagedObject* added, const ManualFilter& manual) const;
  // Appends an object that passed check() and plans the buffers again; its index.
  int add(const ManagedObject& o);
  // Objects, buffers, FIFO and the manual filter forgotten (the chip is the owner's).
  void reset();

  ManualFilter& manual() { return manual_; }
  const ManualFilter& manual() const { return manual_; }
  void program_buffer15();
  std::vector<int> buffer15_objects() const;
  // The automatic filter of the objects in buffer 15 ({0, 0} without any).
  AcceptanceFilter buffer15_filter() const;

  // A changed data set reaches every buffer that holds the object.
  void update_data(int object);
  RequestResult request(const SendRequest& r);
  // Withdraws the object's pending requests (buffer and FIFO); true if there was one.
  bool abort(int object);
  bool pending(int object) const;
  // The interrupt service: until the interrupt register reads 0.
  void service();

  BufferView buffer(uint8_t n) const;  // n = 1..15
  std::size_t fifo_size() const { return fifo_.size(); }
  bool shared() const { return shared_; }

 private:
  struct Buffer {
    int owner = -1;  // the object programmed into it (cached, for a temporary buffer)
    bool permanent = false;
    bool busy = false;
    SendRequest sending;
    uint64_t load = 0;  // the pending load's token (0: none): its transmit request is due
  };

  void plan();
  void program_object(uint8_t n, int object);
  void start_on(uint8_t n, const SendRequest& r);
  void request_transmission(uint8_t n);
  void stop_buffer(uint8_t n);
  void serve_buffer(uint8_t n);
  void serve_buffer15();
  void tx_done(uint8_t n);
  void next_from_fifo(uint8_t n);
  Frame read_frame(uint8_t n, bool remote);

  I82527& chip_;
  BufferEvents& events_;
  std::size_t fifo_depth_;
  std::size_t max_objects_;
  std::vector<ManagedObject> objects_;
  std::array<Buffer, 14> buffers_{};  // [n - 1]
  bool shared_ = false;               // more than 14 objects: the shared plan
  std::deque<SendRequest> fifo_;
  ManualFilter manual_;
  SimScheduler* scheduler_ = nullptr;
  int64_t load_ns_ = 0;
  uint64_t next_load_ = 1;
  std::map<uint64_t, EventId> loads_;  // pending loads' events by token (cancelled with us)
};

}  // namespace canemu::model::sorcus
