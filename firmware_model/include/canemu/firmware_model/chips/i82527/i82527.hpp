// The Intel 82527 serial communications controller as a chip core: the control, status and CPU
// interface registers, the bit timing registers, the global and message-15 masks, 15 message
// objects (14 for transmit or receive, object 15 receive-only and double-buffered), the
// interrupt register, and the error counters kept inside as the silicon does (not readable).
//
// The SORCUS adapter firmware models program it through read()/write() as their driver does.
// Register names copy the Intel datasheet mnemonics; the map is the one of the Intel 82527
// datasheet (cross-checked with the Linux cc770 driver). The decisions where the
// datasheet as we have it is silent are marked `Decision:` and listed in docs/i82527.md.
//
// Not modelled: the CC770's additions (readable error counters, EAF), sleep and wake-up (WAKE
// reads 0), power-down, the multiplexed/serial CPU interface modes and their timing (DMC, MUX),
// the high-speed read registers (read 0), clock-out, the bus configuration's comparator and
// polarity options (stored, no effect), the I/O ports (writes ignored, reads 0xFF), the serial
// reset address, LEC Bit0Error reports during bus-off recovery, setting INI again during the
// recovery (the count goes on), and the uninitialised message RAM after power-up (decision: the
// model starts with every flag reset and every other byte 0).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/controller_events.hpp"
#include "canemu/firmware_model/chips/i82527/message_object.hpp"

namespace canemu::model {

namespace i82527 {

// Register addresses (datasheet "Address Map"). Message object n (1..15) occupies
// n * 0x10 .. n * 0x10 + 0x0E; the 16th byte of each row holds the registers below.
enum Reg : uint8_t {
  CONTROL = 0x00,
  STATUS = 0x01,
  CPU_INTERFACE = 0x02,
  HIGH_SPEED_READ = 0x04,  // 2 bytes
  GMS = 0x06,              // global mask standard, 2 bytes
  GML = 0x08,              // global mask extended ("long"), 4 bytes
  MSG15_MASK = 0x0C,       // message 15 mask, 4 bytes (extended layout)
  CLKOUT = 0x1F,
  BUS_CONFIG = 0x2F,
  BIT_TIMING0 = 0x3F,
  BIT_TIMING1 = 0x4F,
  INTERRUPT = 0x5F,
};
constexpr uint8_t message(uint8_t n) {
  return static_cast<uint8_t>(n * 0x10);
}
inline constexpr uint8_t kObjects = 15;

// CONTROL bits
inline constexpr uint8_t CONTROL_INI = 0x01;  // initialisation: off the bus
inline constexpr uint8_t CONTROL_IE = 0x02;   // interrupt line enabled
inline constexpr uint8_t CONTROL_SIE = 0x04;  // status change interrupt: TXOK, RXOK, LEC
inline constexpr uint8_t CONTROL_EIE = 0x08;  // error interrupt: changes of WARN, BOFF
inline constexpr uint8_t CONTROL_CCE = 0x40;  // change configuration enable
// STATUS bits
inline constexpr uint8_t STATUS_LEC = 0x07;
inline constexpr uint8_t STATUS_TXOK = 0x08;
inline constexpr uint8_t STATUS_RXOK = 0x10;
inline constexpr uint8_t STATUS_WAKE = 0x20;
inline constexpr uint8_t STATUS_WARN = 0x40;
inline constexpr uint8_t STATUS_BOFF = 0x80;
// Last error codes (STATUS bits 2..0).
enum Lec : uint8_t {
  LEC_NONE = 0,
  LEC_STUFF = 1,
  LEC_FORM = 2,
  LEC_ACK = 3,
  LEC_BIT1 = 4,  // sent recessive, saw dominant
  LEC_BIT0 = 5,  // sent dominant, saw recessive
  LEC_CRC = 6,
  LEC_UNUSED = 7,  // never set by the chip; the CPU writes it to see whether a new code comes
};
// CPU_INTERFACE bits
inline constexpr uint8_t CPUIF_RSTST = 0x80;  // hardware reset in progress (reads 0 here)
inline constexpr uint8_t CPUIF_DSC = 0x40;    // divide system clock: SCLK = XTAL / 2
inline constexpr uint8_t CPUIF_DMC = 0x20;    // divide memory clock: MCLK = SCLK / 2
inline constexpr uint8_t CPUIF_PWD = 0x10;
inline constexpr uint8_t CPUIF_SLEEP = 0x08;
inline constexpr uint8_t CPUIF_MUX = 0x04;
inline constexpr uint8_t CPUIF_CEN = 0x01;
// INTERRUPT register values
inline constexpr uint8_t INTERRUPT_NONE = 0;
inline constexpr uint8_t INTERRUPT_STATUS = 1;
inline constexpr uint8_t INTERRUPT_MSG15 = 2;
constexpr uint8_t interrupt_for_message(uint8_t n) {  // n = 1..14 -> 3..16
  return static_cast<uint8_t>(n + 2);
}

// The crystal the model assumes unless told otherwise; with DSC set it gives the 8 MHz system
// clock (125 ns period) of the X-CAN-2i (X-CAN-2i manual, bit timing).
inline constexpr uint32_t kDefaultCrystalHz = 16'000'000;

}  // namespace i82527

class I82527 final : public CanController {
 public:
  explicit I82527(uint32_t crystal_hz = i82527::kDefaultCrystalHz);

  // Puts the chip on `bus`, in the state after a hardware reset (INI set).
  void connect(CanBus& bus);
  // The RESET pin: registers to their reset values (CONTROL = INI, the rest 0, every message
  // flag reset), counters cleared, off the bus. A frame already on the wire completes (its
  // outcome was fixed at its start of frame) and is not repeated.
  void hardware_reset();
  NodeId node() const { return node_; }

  // Register access, addresses 0x00..0xFF. Reading STATUS clears the status change interrupt;
  // the configuration registers (CPU_INTERFACE, CLKOUT, BUS_CONFIG, BIT_TIMING0/1) are writable
  // only while CONTROL.CCE is set.
  uint8_t read(uint8_t address);
  void write(uint8_t address, uint8_t value);

  // The INT pin: active while CONTROL.IE is set and the interrupt register is not 0. Called when
  // it goes active.
  std::function<void(SimTime)> on_interrupt;
  bool interrupt_line() const;
  void set_listener(ControllerEvents* listener) { listener_ = listener; }

  // The system clock the bit timing counts in: the crystal, halved when DSC is set.
  uint32_t sclk_hz() const;

  // --- CanController ---
  // The error counters are inside confinement(), for the model and its tests only: the 82527
  // has no register to read them (datasheet; Linux cc770).
  NodeTiming timing() const override;
  bool participating() const override { return !(control_ & i82527::CONTROL_INI); }
  BusOffRecovery bus_off_recovery() const override { return BusOffRecovery::on_restart; }
  const TxFrame* pending_tx() override { return tx_ ? &*tx_ : nullptr; }
  FaultConfinement& confinement() override { return fc_; }
  void on_frame(SimTime at, const Frame& frame, bool own) override;
  void on_tx_done(SimTime at) override;
  void on_tx_dropped(SimTime at) override;
  void on_arbitration_lost(SimTime at, uint16_t bit, uint16_t destuffed_bit) override;
  void on_error(const BusErrorEvent& event) override;
  void on_state_change(SimTime at, ErrorState state) override;

 private:
  SimTime now() const;
  i82527::MessageObject& object(uint8_t n) { return objects_[n - 1]; }
  uint8_t interrupt_value() const;
  uint8_t status() const;
  // Runs `change` and calls on_interrupt if the line went active by it.
  template <typename F>
  void raising(SimTime at, F change);
  void status_change(SimTime at);  // the status change source, when enabled
  void update_error_status(SimTime at);
  std::array<uint8_t, 4> mask_for(uint8_t n, bool extended) const;
  // The lowest-numbered object among 1..14 that wants to transmit, or 0.
  uint8_t next_tx_object() const;
  // Brings the request the bus sees in line with the objects, unless one is on the wire.
  void refresh_tx();
  void write_control(uint8_t value);
  void write_object(uint8_t n, uint8_t offset, uint8_t value);
  void receive_into(uint8_t n, const Frame& frame, SimTime at);
  void release_shadow();
  void config_changed();

  CanBus* bus_ = nullptr;
  NodeId node_ = 0;
  uint32_t crystal_hz_;
  ControllerEvents* listener_ = nullptr;
  FaultConfinement fc_;

  uint8_t control_ = i82527::CONTROL_INI;
  uint8_t status_ = 0;  // LEC, TXOK, RXOK as stored; WARN and BOFF follow the counters
  uint8_t cpu_interface_ = 0;
  uint8_t clkout_ = 0;
  uint8_t bus_config_ = 0;
  uint8_t btr0_ = 0;
  uint8_t btr1_ = 0;
  std::array<uint8_t, 2> gms_{};
  std::array<uint8_t, 4> gml_{};
  std::array<uint8_t, 4> msg15_mask_{};
  std::array<i82527::MessageObject, i82527::kObjects> objects_{};
  // Message 15's shadow buffer: the frame received while object 15 still held unread data.
  std::optional<Frame> shadow_;
  bool status_pending_ = false;  // the status change interrupt source
  uint8_t error_status_ = 0;     // WARN | BOFF as last seen

  std::optional<TxFrame> tx_;
  uint8_t tx_object_ = 0;  // the object tx_ came from
};

}  // namespace canemu::model
