// The SORCUS SL-CANi (S-Link type 64) in one Multi-COM slot: one Intel 82527 at 10 MHz, its
// EEPROM, and the driver task SL64TASK as the library SL64_LIB sees it, one call per sl064_*
// function with the slot implied (../shared/spec/sorcus-digest.md §1, §3.2, §3.4, §3.5, §4).
//
// What it models:
// - the configuration order bib_startup -> config_module -> config_msg_object... ->
//   [set_acceptance_mask, once] -> start_com, with diagnosis 2Dh for a call out of it;
//   clear_configuration back to the object phase; stop_com / start_com, also the way out of
//   bus-off (both counters reset);
// - message objects with handles and the role flags _SL064_SEND, _ACTIVE, _PASSIVE,
//   _EXCL_BUFFER, _DISABLE_INT and their rules, on the buffer manager shared with the X-CAN-2i
//   (buffer_manager.hpp): own buffers up to 14 objects, exclusive buffers (at most 13, 27h),
//   buffer 15 for passive non-exclusive objects of one kind (2Ch), the temporary pool and the
//   driver FIFO holding handles only (warning 6 when queued, 2Bh when full);
// - one identifier format for every object, the bit timing and the termination from the EEPROM
//   (slcan_eeprom.hpp), checked at config_module (24h, 31h);
// - repetition until acknowledged (the 82527's), sl064_clear_msg aborting it;
// - the diagnosis of the last call (warnings 1..6 are not in the return value; 21h and above
//   return 42h), reset to 0 when read;
// - service routines by task and function number, called at the manual's instants: a send
//   after its acknowledgement (an answer to a remote frame after the answer's data frame), a
//   reception by a receive object, the error routine with status 1 (heavily disturbed) and 2
//   (bus-off); function 14 of SL64TASK as the buffered service request (sl064_evaluate_srq)
//   with the interrupt lock of sl064_enable_int_mask / sl064_end_of_srq, under which only the
//   newest frame per buffer survives (warning 5);
// - the LED; faults that make the S-Link answer 22h, 2Eh, 2Fh, 30h, 32h, 33h or 35h.
//
// Every decision where the manual is silent is marked `Decision:` and listed in docs/sorcus.md.
// Not modelled: the two S-Links of one SCC sharing an interrupt line (each slot serves its own
// chip), the few µs a buffer load takes, the 82527 bug that sends a remote frame with ID 0, the
// on-card real-time return value 42E0h (the library is a PC program's).
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <set>
#include <span>
#include <utility>
#include <vector>

#include "canemu/firmware_model/adapters/sorcus/buffer_manager.hpp"
#include "canemu/firmware_model/adapters/sorcus/slcan_eeprom.hpp"
#include "canemu/firmware_model/chips/i82527/i82527.hpp"
#include "canemu/firmware_model/sim/sim_scheduler.hpp"
#include "sorcus/sl64_types.h"

namespace canemu::model::sorcus {

// A service routine call (a real-time routine on the card; a callback in canemu's library).
struct SlcanServiceCall {
  enum class Kind : uint8_t { message, error };
  SimTime at;
  Kind kind = Kind::message;
  USHORT task = 0;
  USHORT func = 0;
  SL064Handle handle = 0;  // message: the object (0: an unconfigured message, see get_id)
  ULONG status = 0;        // error: SL064_STATUS_HEAVY or SL064_STATUS_BUS_OFF
  // message with handle 0: the identifier of the unconfigured frame this call is for. Each call
  // carries its own, so that calls queued before the routine runs (the routine is a function of
  // the PC program, run later than the card would) each read their frame's ID (get_id).
  ULONG id = 0;
};

class SlcanSink {
 public:
  // An installed routine is called.
  virtual void service(const SlcanServiceCall& call) = 0;
  // Function 14 raised a service request to the PC (the word: 80h | slot << 8).
  virtual void service_request(SimTime at, USHORT word) = 0;

 protected:
  ~SlcanSink() = default;
};

// Hardware and installation failures, for fault scenarios; each gives its diagnosis at
// sl064_bib_startup and sl064_config_module (no_response at every call).
enum class SlcanFault : uint8_t {
  none,
  no_response,    // 22h
  reset,          // 2Eh
  async_init,     // 2Fh
  sync_init,      // 30h
  no_m6p0500,     // 32h
  m6p0500_error,  // 33h
  scc_frequency,  // 35h
};

class SlcanModule {
 public:
  // Decision: the manual gives no FIFO depth (digest §7.3); 64 handles, as the X-CAN FIFO.
  static constexpr std::size_t kFifoDepth = 64;
  // Decision: «beliebig viele» objects, bounded by memory: 1024 per S-Link, then 21h.
  static constexpr std::size_t kMaxObjects = 1024;
  // Decision: the service request buffer holds 256 causes; more are counted, not kept.
  static constexpr std::size_t kSrqDepth = 256;
  static constexpr uint32_t kCrystalHz = 10'000'000;

  // `scheduler` is the bus's; `sink` outlives the module; `slot` 0..5 (channels A..F).
  SlcanModule(SimScheduler& scheduler, uint8_t slot, SlcanSink& sink);
  SlcanModule(const SlcanModule&) = delete;
  SlcanModule& operator=(const SlcanModule&) = delete;

  void connect(CanBus& bus);
  // Back to the state after power-up (a client's session ended): driver unconfigured, objects
  // gone, chip reset and off the bus, LED off; the EEPROM and installed routines stay.
  void reset();
  uint8_t slot() const { return slot_; }
  // Decision: SL64TASK's task number for slot s is 40h + s; function 14 of that task is the
  // buffered service request.
  USHORT driver_task() const { return static_cast<USHORT>(0x40 + slot_); }
  I82527& chip() { return chip_; }
  const EepromWords& eeprom() const { return eeprom_; }
  // A program's write: false (and no change) for a read-only word.
  bool write_eeprom(unsigned word, uint16_t value);
  // The contents as stored (a state file): any values, checked at config_module.
  void load_eeprom(const EepromWords& words) { eeprom_ = words; }
  void set_fault(SlcanFault fault) { fault_ = fault; }
  // A routine the client installed (and its removal), for warning 2 and the calls.
  void install_routine(USHORT task, USHORT func) { routines_.insert({task, func}); }
  void remove_routine(USHORT task, USHORT func) { routines_.erase({task, func}); }

  // --- SL64_LIB: what each function returns (0, or SL064_E_DRIVER) ---
  USHORT bib_startup();
  USHORT config_module(USHORT err_task, USHORT err_func);
  USHORT config_msg_object(const SL064MsgType& config, SL064Handle& handle);
  USHORT clear_configuration();
  USHORT start_com();
  USHORT stop_com();
  USHORT get_diagnosis();  // the code; reset to 0
  USHORT set_data(SL064Handle handle, std::span<const uint8_t> data);
  // `size` in: bytes wanted (at most 8), out: bytes delivered.
  USHORT get_data(SL064Handle handle, std::array<uint8_t, 8>& data, uint8_t& size);
  USHORT send_data(SL064Handle handle);
  USHORT send_data_request(SL064Handle handle);
  USHORT clear_msg(SL064Handle handle);
  USHORT set_acceptance_mask(ULONG& mask, USHORT usage, USHORT serv_task, USHORT serv_func);
  // Handle 0 (with the acceptance mask set): `call_id` when the caller is the mask's routine
  // serving a call (SlcanServiceCall::id, which the library passes back), else the ID of the
  // last unconfigured frame a call was made for.
  USHORT get_id(SL064Handle handle, ULONG& id, std::optional<ULONG> call_id = std::nullopt);
  USHORT get_msg_count(SL064Handle handle, ULONG& count);
  void set_led(UCHAR on) { led_ = on != 0; }
  UCHAR get_led() const { return led_ ? 1 : 0; }
  // 0 with a handle: that object's success; 1 or 2: the error status; 0 with handle 0: none,
  // or (the acceptance mask's routine being function 14) an unconfigured frame, whose ID
  // get_id(0) then reads: each request keeps its own ID in the bounded request buffer.
  USHORT evaluate_srq(SL064Handle& handle);
  void enable_int_mask() { int_mask_ = true; }
  void end_of_srq();

  // --- views ---
  BufferView buffer(uint8_t n) const { return mgr_.buffer(n); }
  AcceptanceFilter buffer15_filter() const { return mgr_.buffer15_filter(); }
  std::size_t fifo_size() const { return mgr_.fifo_size(); }
  std::size_t object_count() const { return objects_.size(); }
  bool configured() const { return phase_ >= Phase::configured; }
  bool running() const { return running_; }
  bool locked() const { return locked_; }
  uint8_t error_bits() const { return error_bits_; }  // WARN | BOFF as last served
  std::optional<SlcanSettings> settings() const { return settings_; }
  std::size_t srq_pending() const { return srq_.size(); }
  uint64_t srq_overflows() const { return srq_overflows_; }
  uint64_t discarded() const { return discarded_; }  // unconfigured frames with no routine
  USHORT last_diagnosis() const { return diag_; }    // without resetting it

 private:
  enum class Phase : uint8_t { off, started, configured };
  struct Object {
    USHORT flags = 0;
    USHORT task = 0;
    USHORT func = 0;
    ULONG count = 0;
    bool lost = false;  // a frame was lost before the last one (warning 5 at the next read)
  };
  struct Events final : BufferEvents {
    SlcanModule* m = nullptr;
    void status_changed() override { m->serve_status(); }
    void sent(const SendRequest& r, bool answered) override { m->sent(r, answered); }
    void received(int object, const Frame& frame, bool lost) override {
      m->received(object, frame, lost);
    }
    void unconfigured(const Frame& frame) override { m->unconfigured(frame); }
    bool hold() const override { return m->locked_; }
  };
  struct Srq {
    SL064Handle handle = 0;
    USHORT status = 0;
    ULONG id = 0;  // handle 0 (the mask's): the unconfigured frame's ID
  };

  USHORT done(USHORT diagnosis);  // stores it; the return value
  std::optional<USHORT> fault_diagnosis() const;
  int object_of(SL064Handle handle) const;  // -1: invalid
  SL064Handle handle_of(int object) const {
    return static_cast<SL064Handle>(handle_base_ + object + 1);
  }
  bool installed(USHORT task, USHORT func) const;
  void call(SlcanServiceCall c);
  USHORT send(SL064Handle handle, bool remote);
  void on_interrupt(SimTime at);
  void serve_status();
  void sent(const SendRequest& r, bool answered);
  void received(int object, const Frame& frame, bool lost);
  void unconfigured(const Frame& frame);
  void message_event(int object);

  SimScheduler& scheduler_;
  uint8_t slot_;
  SlcanSink& sink_;
  I82527 chip_{kCrystalHz};
  Events events_;
  BufferManager mgr_;
  CanBus* bus_ = nullptr;
  EepromWords eeprom_ = slcan_eeprom_defaults();
  SlcanFault fault_ = SlcanFault::none;
  std::set<std::pair<USHORT, USHORT>> routines_;

  Phase phase_ = Phase::off;
  bool mask_set_ = false;
  bool running_ = false;
  std::optional<SlcanSettings> settings_;
  USHORT err_task_ = 0;
  USHORT err_func_ = 0;
  USHORT mask_task_ = 0;
  USHORT mask_func_ = 0;
  ULONG unconfigured_id_ = 0;  // get_id with handle 0 outside a routine: the last call's
  std::vector<Object> objects_;
  USHORT handle_base_ = 0;  // handles of the current configuration are base + 1..
  USHORT diag_ = 0;
  bool led_ = false;
  uint8_t error_bits_ = 0;
  uint16_t last_lec_ = 0;
  bool isr_scheduled_ = false;
  bool int_mask_ = false;
  bool locked_ = false;
  std::deque<Srq> srq_;
  uint64_t srq_overflows_ = 0;
  uint64_t discarded_ = 0;
};

}  // namespace canemu::model::sorcus
