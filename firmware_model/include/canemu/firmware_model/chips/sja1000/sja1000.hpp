// The NXP (Philips) SJA1000 stand-alone CAN controller in PeliCAN mode, as a chip core: the
// registers of its datasheet (section 6.4) wherever behaviour depends on them, the 64-byte
// receive FIFO with its message counter and real data overrun, the acceptance filter, error
// counters, error code and arbitration-lost capture, and the interrupt line.
//
// The IXXAT adapter firmware model programs it through read()/write() as the vendor firmware
// would. Register names copy the datasheet mnemonics.
//
// Not modelled: BasicCAN mode (CDR.7 is treated as set), sleep mode and wake-up, the output
// control register's effect on the transceiver, RS/TS status bits during a frame (they read 1
// in reset mode, 0 otherwise), and clock-out.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/controller_events.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace canemu::model {

namespace sja1000 {

// Register addresses in PeliCAN mode (datasheet table 3).
enum Reg : uint8_t {
  MOD = 0,
  CMR = 1,
  SR = 2,
  IR = 3,
  IER = 4,
  BTR0 = 6,
  BTR1 = 7,
  OCR = 8,
  ALC = 11,
  ECC = 12,
  EWLR = 13,
  RXERR = 14,
  TXERR = 15,
  FRAME = 16,  // TX/RX frame information; ACR0 in reset mode
  ACR0 = 16,
  AMR0 = 20,
  RMC = 29,
  RBSA = 30,
  CDR = 31,
  RX_FIFO = 32,  // 64 bytes of receive FIFO RAM, readable in reset mode
  TX_BUFFER = 96,
};

// MOD bits
inline constexpr uint8_t MOD_RM = 0x01;
inline constexpr uint8_t MOD_LOM = 0x02;
inline constexpr uint8_t MOD_STM = 0x04;
inline constexpr uint8_t MOD_AFM = 0x08;
inline constexpr uint8_t MOD_SM = 0x10;
// CMR bits
inline constexpr uint8_t CMR_TR = 0x01;
inline constexpr uint8_t CMR_AT = 0x02;
inline constexpr uint8_t CMR_RRB = 0x04;
inline constexpr uint8_t CMR_CDO = 0x08;
inline constexpr uint8_t CMR_SRR = 0x10;
// SR bits
inline constexpr uint8_t SR_RBS = 0x01;
inline constexpr uint8_t SR_DOS = 0x02;
inline constexpr uint8_t SR_TBS = 0x04;
inline constexpr uint8_t SR_TCS = 0x08;
inline constexpr uint8_t SR_RS = 0x10;
inline constexpr uint8_t SR_TS = 0x20;
inline constexpr uint8_t SR_ES = 0x40;
inline constexpr uint8_t SR_BS = 0x80;
// IR / IER bits
inline constexpr uint8_t IR_RI = 0x01;
inline constexpr uint8_t IR_TI = 0x02;
inline constexpr uint8_t IR_EI = 0x04;
inline constexpr uint8_t IR_DOI = 0x08;
inline constexpr uint8_t IR_WUI = 0x10;
inline constexpr uint8_t IR_EPI = 0x20;
inline constexpr uint8_t IR_ALI = 0x40;
inline constexpr uint8_t IR_BEI = 0x80;

inline constexpr std::size_t kRxFifoBytes = 64;

// Packs a frame in the PeliCAN buffer layout (frame information, identifier bytes, data):
// 3 + data bytes for a standard frame, 5 + data bytes for an extended one. RTR frames carry no
// data bytes. Writes those bytes at `out` (room for 13) and no others; returns their number.
std::size_t pack_frame(const Frame& frame, uint8_t* out);
inline std::size_t pack_frame(const Frame& frame, std::array<uint8_t, 13>& out) {
  return pack_frame(frame, out.data());
}
// Reads a frame from that layout; nothing if the bytes do not describe one.
std::optional<Frame> unpack_frame(const uint8_t* bytes);
// The bytes a frame takes in that layout, from its frame information byte alone: what
// pack_frame() wrote (a DLC above 8 carries 8 data bytes).
constexpr std::size_t packed_size(uint8_t frame_info) {
  const std::size_t header = (frame_info & 0x80) != 0 ? 5 : 3;
  const std::size_t data = (frame_info & 0x40) != 0 ? 0 : frame_info & 0x0F;
  return header + (data > 8 ? 8 : data);
}
// The same from the frame: what pack_frame() writes for it.
inline std::size_t packed_size(const Frame& frame) {
  return (frame.extended() ? 5u : 3u) + std::min<std::size_t>(frame.length(), 8);
}

// The acceptance filter (datasheet 6.4.15): single (AFM = 1) or dual filter over identifier,
// RTR and, for standard frames, the first data bytes. Data bytes a frame does not have are not
// compared.
bool accepts(const std::array<uint8_t, 4>& acr, const std::array<uint8_t, 4>& amr, bool single,
             const Frame& frame);
// Whether the mask lets every frame through (every bit "don't care"), whatever the filter mode
// and code: the reset value, and what drivers that filter in software write.
inline bool accepts_all(const std::array<uint8_t, 4>& amr) {
  return amr == std::array<uint8_t, 4>{0xFF, 0xFF, 0xFF, 0xFF};
}

// SJA1000 error code capture segment (datasheet table 19) of a bit the bus reports.
uint8_t ecc_segment(const BusErrorEvent& e, uint16_t destuffed_bit, bool extended);

}  // namespace sja1000

class Sja1000 final : public CanController {
 public:
  explicit Sja1000(uint32_t oscillator_hz = sja1000::kIxxatOscillatorHz);

  // Puts the chip on `bus`. It starts in reset mode, as after a hardware reset.
  void connect(CanBus& bus);
  // The RST pin: every register back to its reset value, counters cleared, the transmit request
  // and the receive FIFO dropped, reset mode (a frame already on the wire completes without
  // retransmission; its outcome was fixed at its start of frame).
  void hardware_reset();
  NodeId node() const { return node_; }

  // Register access (PeliCAN addresses 0..127). Reading IR clears it (but RI), reading ALC and
  // ECC re-arms their capture; writes follow the datasheet's access rules per mode.
  uint8_t read(uint8_t address);
  void write(uint8_t address, uint8_t value);
  // What a driver's writes of `frame` (pack_frame's bytes) into the transmit buffer at FRAME
  // and then of `cmr` into CMR do, in one call: the same registers and request as those writes,
  // without reading the frame back out of the buffer's bytes.
  void write_transmit(const Frame& frame, uint8_t cmr);
  // What a driver's read of MOD and SR tells of the transmit buffer (operating mode and TBS
  // set), and what its write of CMR_RRB into CMR does, without the registers' decoding: the
  // reads have no side effects, and the write is the command.
  bool transmit_buffer_free() const { return (mod_ & sja1000::MOD_RM) == 0 && !tx_; }
  void release_receive_buffer() {
    if ((mod_ & sja1000::MOD_RM) == 0) {
      fifo_release();  // what command(CMR_RRB) does: commands do nothing in reset mode
    }
  }

  // The interrupt line: active while IR has a bit set. IR bits are only set for sources enabled
  // in IER; RI follows the FIFO (set while it holds a message and RIE is set). Called when the
  // line goes active.
  std::function<void(SimTime)> on_interrupt;
  bool interrupt_line() const { return ir_value() != 0; }
  void set_listener(ControllerEvents* listener) { listener_ = listener; }

  // --- CanController ---
  NodeTiming timing() const override;
  bool participating() const override { return !(mod_ & sja1000::MOD_RM); }
  bool listen_only() const override { return (mod_ & sja1000::MOD_LOM) != 0; }
  bool self_test() const override { return (mod_ & sja1000::MOD_STM) != 0; }
  bool fd_capable() const override { return false; }
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
  Frame end_tx(SimTime at, bool complete);  // ends the request (TCS = complete, TI); its frame
  uint8_t ir_value() const {
    return static_cast<uint8_t>(ir_ | ((rmc_ > 0 && (ier_ & sja1000::IR_RI)) ? sja1000::IR_RI : 0));
  }
  void set_ir(uint8_t bits, SimTime at);
  void command(uint8_t cmr);
  void enter_reset();
  void leave_reset();
  // EI on every change of SR.ES or SR.BS (datasheet 6.4.4); inline, as every frame's end asks.
  void update_error_status(SimTime at) {
    const uint8_t bits = error_bits();
    if (bits != error_status_) {
      error_status_ = bits;
      set_ir(sja1000::IR_EI, at);
    }
  }
  void counters_written();
  uint8_t status() const;
  uint8_t error_bits() const {  // SR.ES and SR.BS
    if (fc_.bus_off()) {
      return sja1000::SR_ES | sja1000::SR_BS;
    }
    const uint16_t limit = fc_.warning_limit();
    return fc_.tec() >= limit || fc_.rec() >= limit ? sja1000::SR_ES : 0;
  }
  // Receive FIFO.
  std::size_t fifo_used() const { return fifo_used_; }
  bool fifo_push(const Frame& frame);
  void fifo_release();
  uint8_t fifo_byte(std::size_t offset) const {
    return fifo_[(rbsa_ + offset) % sja1000::kRxFifoBytes];
  }

  CanBus* bus_ = nullptr;
  NodeId node_ = 0;
  uint32_t oscillator_hz_;
  ControllerEvents* listener_ = nullptr;
  FaultConfinement fc_{255};  // RXERR is 8 bits wide

  uint8_t mod_ = sja1000::MOD_RM;
  uint8_t ir_ = 0;
  uint8_t ier_ = 0;
  uint8_t btr0_ = 0;
  uint8_t btr1_ = 0;
  uint8_t ocr_ = 0;
  uint8_t cdr_ = 0x80;
  uint8_t alc_ = 0;
  uint8_t ecc_ = 0;
  bool alc_armed_ = true;
  bool ecc_armed_ = true;
  std::array<uint8_t, 4> acr_{};
  std::array<uint8_t, 4> amr_{0xFF, 0xFF, 0xFF, 0xFF};
  std::array<uint8_t, 13> tx_buffer_{};
  std::optional<TxFrame> tx_;  // the request being transmitted
  bool tx_complete_ = true;    // TCS
  bool data_overrun_ = false;  // DOS
  ErrorState state_ = ErrorState::active;
  uint8_t error_status_ = 0;  // SR.ES | SR.BS as last reported through EI

  std::array<uint8_t, sja1000::kRxFifoBytes> fifo_{};
  std::size_t rbsa_ = 0;       // start of the current message
  std::size_t fifo_used_ = 0;  // bytes held
  uint8_t rmc_ = 0;            // messages held
};

}  // namespace canemu::model
