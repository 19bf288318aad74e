// The SJA1000 seen the way software sees it: chips on one bus, programmed and read through their
// PeliCAN registers.
#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"

#include <gtest/gtest.h>

#include "case_name.hpp"
#include "test_controller.hpp"

namespace canemu::model {
namespace {

using namespace sja1000;
using testing::frame;
using testing::kBit;
using Bus = testing::BusFixture;

struct Chip {
  Sja1000 chip;
  int interrupts = 0;
  Chip() {
    chip.on_interrupt = [this](SimTime) { ++interrupts; };
  }
  // On `bus`, in reset mode.
  explicit Chip(Bus& bus) : Chip() { chip.connect(bus.bus); }
  // Reset mode: 500 kbit/s, accept everything, all interrupts, then operating mode.
  void start(uint8_t mod_bits = 0) {
    chip.write(BTR0, 0x00);
    chip.write(BTR1, 0x1C);
    for (uint8_t i = 0; i < 4; ++i) {
      chip.write(static_cast<uint8_t>(AMR0 + i), 0xFF);
    }
    chip.write(IER, 0xFF);
    chip.write(MOD, static_cast<uint8_t>(mod_bits | MOD_RM));
    chip.write(MOD, mod_bits);
  }
  void load(const Frame& f) {
    std::array<uint8_t, 13> bytes;
    const std::size_t n = pack_frame(f, bytes);
    for (std::size_t k = 0; k < n; ++k) {
      chip.write(static_cast<uint8_t>(FRAME + k), bytes[k]);
    }
  }
  void send(const Frame& f, uint8_t command = CMR_TR) {
    load(f);
    chip.write(CMR, command);
  }
  std::optional<Frame> receive() {
    if (!(chip.read(SR) & SR_RBS)) {
      return std::nullopt;
    }
    std::array<uint8_t, 13> bytes;
    for (uint8_t k = 0; k < 13; ++k) {
      bytes[k] = chip.read(static_cast<uint8_t>(FRAME + k));
    }
    chip.write(CMR, CMR_RRB);
    return unpack_frame(bytes.data());
  }
};

TEST(Sja1000, StartsInResetModeWithTheDatasheetResetValues) {
  Sja1000 c;
  EXPECT_EQ(c.read(MOD), MOD_RM);
  EXPECT_EQ(c.read(SR), 0x3C);  // TBS, TCS, RS, TS
  EXPECT_EQ(c.read(IR), 0x00);
  EXPECT_EQ(c.read(EWLR), 96);
  EXPECT_EQ(c.read(RXERR), 0);
  EXPECT_EQ(c.read(TXERR), 0);
  EXPECT_EQ(c.read(RMC), 0);
  EXPECT_EQ(c.read(CDR) & 0x80, 0x80);
  EXPECT_FALSE(c.participating());
}

TEST(Sja1000, AHardwareResetRestoresTheResetValues) {
  Bus b;
  Chip a(b);
  a.start();
  a.chip.write(MOD, MOD_RM);
  a.chip.write(EWLR, 10);
  a.chip.write(TXERR, 200);
  a.chip.write(ACR0, 0x12);
  a.chip.write(AMR0, 0x00);
  a.chip.hardware_reset();
  EXPECT_EQ(a.chip.read(MOD), MOD_RM);
  EXPECT_EQ(a.chip.read(SR), 0x3C);
  EXPECT_EQ(a.chip.read(IER), 0x00);
  EXPECT_EQ(a.chip.read(EWLR), 96);
  EXPECT_EQ(a.chip.read(TXERR), 0);
  EXPECT_EQ(a.chip.read(BTR0), 0x00);
  EXPECT_EQ(a.chip.read(ACR0), 0x00);
  EXPECT_EQ(a.chip.read(AMR0), 0xFF);
  EXPECT_EQ(a.chip.confinement().state(), ErrorState::active);
}

TEST(Sja1000, TimingAndFiltersAreWritableInResetModeOnly) {
  Chip a;
  a.start();
  a.chip.write(BTR0, 0x03);
  a.chip.write(EWLR, 10);
  EXPECT_EQ(a.chip.read(BTR0), 0x00);
  EXPECT_EQ(a.chip.read(EWLR), 96);
  a.chip.write(MOD, MOD_RM);
  a.chip.write(BTR0, 0x03);
  EXPECT_EQ(a.chip.read(BTR0), 0x03);
  EXPECT_EQ(a.chip.timing().nominal.bit_rate(), (BitRate{125000, 1}));
}

TEST(Sja1000, TwoChipsExchangeAFrameThroughTheirRegisters) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start();
  const Frame f = frame(0x123, {0x11, 0x22});
  a.send(f);
  EXPECT_EQ(a.chip.read(SR) & (SR_TBS | SR_TCS), 0);  // locked, not complete
  b.run_until(62 * kBit - 1);
  EXPECT_EQ(r.chip.read(RMC), 0);
  b.run_until(62 * kBit);
  // Receiver: RI, one message, the PeliCAN layout in the receive window.
  EXPECT_EQ(r.chip.read(IR), IR_RI);
  EXPECT_EQ(r.chip.read(RMC), 1);
  EXPECT_EQ(r.chip.read(FRAME), 0x02);      // SFF, no RTR, DLC 2
  EXPECT_EQ(r.chip.read(FRAME + 1), 0x24);  // ID.28-21
  EXPECT_EQ(r.chip.read(FRAME + 2), 0x60);  // ID.20-18, RTR 0
  EXPECT_EQ(r.chip.read(FRAME + 3), 0x11);
  EXPECT_EQ(r.receive(), f);
  EXPECT_EQ(r.chip.read(RMC), 0);
  EXPECT_EQ(r.chip.read(SR) & SR_RBS, 0);
  EXPECT_EQ(r.chip.read(IR) & IR_RI, 0);
  // Transmitter: TI, buffer released, transmission complete.
  EXPECT_EQ(a.chip.read(IR), IR_TI);
  EXPECT_EQ(a.chip.read(SR) & (SR_TBS | SR_TCS), SR_TBS | SR_TCS);
  EXPECT_EQ(a.interrupts, 1);
}

TEST(Sja1000, SingleAcceptanceFilterPassesOnlyTheProgrammedIdentifier) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start(MOD_AFM);
  r.chip.write(MOD, MOD_RM | MOD_AFM);
  // 0x123: ACR0 = 0x24, ACR1 = 0x60; RTR and the unused nibble and both data bytes don't care.
  const uint8_t acr[4] = {0x24, 0x60, 0, 0};
  const uint8_t amr[4] = {0x00, 0x1F, 0xFF, 0xFF};
  for (uint8_t i = 0; i < 4; ++i) {
    r.chip.write(static_cast<uint8_t>(ACR0 + i), acr[i]);
    r.chip.write(static_cast<uint8_t>(AMR0 + i), amr[i]);
  }
  r.chip.write(MOD, MOD_AFM);
  a.send(frame(0x124, {1}));
  b.run_until(1'000'000);
  a.send(frame(0x123, {2}));
  b.run_until(2'000'000);
  EXPECT_EQ(r.chip.read(RMC), 1);
  EXPECT_EQ(r.receive(), frame(0x123, {2}));
}

TEST(Sja1000, DualFilterOnExtendedFramesComparesTheUpperSixteenIdentifierBits) {
  const std::array<uint8_t, 4> acr{0x12, 0x34, 0xAB, 0xCD};
  const std::array<uint8_t, 4> amr{0x00, 0x00, 0x00, 0x00};
  const Frame f1 = frame((0x1234u << 13) | 0x1FFF, {}, true);  // filter 1, low bits ignored
  const Frame f2 = frame(0xABCDu << 13, {}, true);             // filter 2
  const Frame no = frame(0x1235u << 13, {}, true);
  EXPECT_TRUE(accepts(acr, amr, false, f1));
  EXPECT_TRUE(accepts(acr, amr, false, f2));
  EXPECT_FALSE(accepts(acr, amr, false, no));
}

TEST(Sja1000, DualFilterOnStandardFramesUsesTheFirstDataByteInFilterOne) {
  // Filter 1: ID 0x123, first data byte 0x5A (high nibble in ACR1, low nibble in ACR3).
  // Filter 2 (ACR2, ACR3 high nibble) set to an identifier that never comes.
  const std::array<uint8_t, 4> acr{0x24, 0x65, 0xFF, 0xFA};
  const std::array<uint8_t, 4> amr{0x00, 0x10, 0x00, 0x10};
  EXPECT_TRUE(accepts(acr, amr, false, frame(0x123, {0x5A})));
  EXPECT_FALSE(accepts(acr, amr, false, frame(0x123, {0x5B})));
  EXPECT_TRUE(accepts(acr, amr, false, frame(0x123, {})));  // no data byte: not compared
  EXPECT_FALSE(accepts(acr, amr, false, frame(0x124, {0x5A})));
}

TEST(Sja1000, FullReceiveFifoOverrunsKeepingTheOldestFrames) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start();
  // An 8-byte standard frame takes 11 FIFO bytes: five fit in 64, the sixth overruns.
  for (uint8_t i = 0; i < 7; ++i) {
    a.send(frame(0x100 + i, {i, 1, 2, 3, 4, 5, 6, 7}));
    b.run_until((i + 1) * 1'000'000);
  }
  EXPECT_EQ(r.chip.read(RMC), 5);
  EXPECT_TRUE(r.chip.read(SR) & SR_DOS);
  EXPECT_TRUE(r.chip.read(IR) & IR_DOI);
  for (uint8_t i = 0; i < 5; ++i) {
    EXPECT_EQ(r.receive(), frame(0x100 + i, {i, 1, 2, 3, 4, 5, 6, 7}));
  }
  EXPECT_FALSE(r.receive().has_value());
  r.chip.write(CMR, CMR_CDO);
  EXPECT_FALSE(r.chip.read(SR) & SR_DOS);
  // Frames keep arriving once there is room again.
  a.send(frame(0x200, {}));
  b.run_until(10'000'000);
  EXPECT_EQ(r.receive(), frame(0x200, {}));
}

// The FIFO is a ring of 64 bytes: a message that does not fit before its end goes on at its
// start, and RBSA follows each release round it.
TEST(Sja1000, MessagesWrapRoundTheEndOfTheReceiveFifo) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start();
  int64_t t = 0;
  const auto pass = [&](const Frame& f) {
    a.send(f);
    t += 1'000'000;
    b.run_until(t);
  };
  for (uint8_t i = 0; i < 5; ++i) {  // 5 x 11 bytes, released: RBSA at 55
    pass(frame(0x100 + i, {i, 1, 2, 3, 4, 5, 6, 7}));
    ASSERT_TRUE(r.receive());
  }
  EXPECT_EQ(r.chip.read(RBSA), 55);
  const Frame across = frame(0x1ABCDEF0, {9, 8, 7, 6, 5, 4, 3, 2}, true);  // 13 bytes: 55..3
  pass(across);
  pass(frame(0x7FF, {0xAA}));  // 4 bytes: 4..7
  EXPECT_EQ(r.chip.read(RMC), 2);
  EXPECT_EQ(r.chip.read(FRAME), 0x88);  // EFF, DLC 8, read through the window at RBSA
  EXPECT_EQ(r.receive(), across);
  EXPECT_EQ(r.chip.read(RBSA), 4);
  EXPECT_EQ(r.receive(), frame(0x7FF, {0xAA}));
  EXPECT_EQ(r.chip.read(RBSA), 8);
  EXPECT_EQ(r.chip.read(RMC), 0);
}

// AMR all ones makes every bit "don't care": every frame passes in either filter mode, whatever
// ACR holds.
TEST(Sja1000, AnAcceptanceMaskOfAllOnesPassesEveryFrameInBothModes) {
  const std::array<uint8_t, 4> amr{0xFF, 0xFF, 0xFF, 0xFF};
  const std::array<uint8_t, 4> acr{0x12, 0x34, 0x56, 0x78};
  FrameSpec remote;
  remote.id = 0x1FFFFFFF;
  remote.extended = true;
  remote.remote = true;
  remote.dlc = 3;
  for (const bool single : {true, false}) {
    EXPECT_TRUE(accepts(acr, amr, single, frame(0x000, {})));
    EXPECT_TRUE(accepts(acr, amr, single, frame(0x7FF, {0xFF, 0x00})));
    EXPECT_TRUE(accepts(acr, amr, single, frame(0x0ABCDEF, {1}, true)));
    EXPECT_TRUE(accepts(acr, amr, single, *Frame::create(remote)));
  }
}

// write_transmit() is the driver's register writes in one call: in operating mode the same
// frame goes out with the same request bits; in reset mode the bytes land where register writes
// land (the acceptance registers) and nothing is sent; with a request pending it is ignored.
TEST(Sja1000, WriteTransmitDoesWhatTheRegisterWritesDo) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start();
  const Frame f = frame(0x123, {0x11, 0x22});
  a.chip.write_transmit(f, CMR_TR);
  EXPECT_EQ(a.chip.read(SR) & (SR_TBS | SR_TCS), 0);  // locked, not complete
  a.chip.write_transmit(frame(0x456, {}), CMR_TR);    // ignored: a request is pending
  b.run_until(62 * kBit);
  EXPECT_EQ(r.receive(), f);
  EXPECT_EQ(a.chip.read(IR), IR_TI);
  b.run_until(200 * kBit);
  EXPECT_FALSE(r.receive().has_value());  // 0x456 was never requested
  // Self reception with single shot: the frame comes back to its sender.
  a.chip.write_transmit(frame(0x321, {7}), CMR_SRR | CMR_AT);
  b.run_until(400 * kBit);
  EXPECT_EQ(a.receive(), frame(0x321, {7}));
  EXPECT_EQ(r.receive(), frame(0x321, {7}));
  // The transmit buffer keeps what lies past a shorter frame: 0x321's four bytes, then the
  // last of 0x123's five.
  EXPECT_EQ(a.chip.read(TX_BUFFER), 0x01);
  EXPECT_EQ(a.chip.read(TX_BUFFER + 3), 0x07);
  EXPECT_EQ(a.chip.read(TX_BUFFER + 4), 0x22);
  // Reset mode: the writes at FRAME.. are ACR0..3 and AMR0..3 there.
  a.chip.write(MOD, MOD_RM);
  a.chip.write_transmit(frame(0x7FF, {1, 2, 3, 4, 5}), CMR_TR);
  EXPECT_EQ(a.chip.read(ACR0), 0x05);  // the frame information byte: DLC 5
  EXPECT_EQ(a.chip.read(ACR0 + 1), 0xFF);
  EXPECT_EQ(a.chip.read(ACR0 + 3), 0x01);  // data byte 1
  EXPECT_EQ(a.chip.read(AMR0), 0x02);      // data byte 2
}

TEST(Sja1000, ListenOnlyChipNeitherAcknowledgesNorCounts) {
  Bus b;
  Chip a(b), l(b);
  a.start();
  l.start(MOD_LOM);
  a.send(frame(0x123, {1}));
  b.run_until(1'000'000);
  EXPECT_GT(a.chip.read(TXERR), 0);
  EXPECT_EQ(l.chip.read(RXERR), 0);
  // The transmitter's error code capture: ACK slot, "other" error, while transmitting.
  const uint8_t ecc = a.chip.read(ECC);
  EXPECT_EQ(ecc >> 6, 3);
  EXPECT_EQ((ecc >> 5) & 1, 0);
  EXPECT_EQ(ecc & 0x1F, 0x19);
  EXPECT_TRUE(a.chip.read(IR) & IR_BEI);
}

TEST(Sja1000, SelfReceptionRequestReceivesTheOwnFrame) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start();
  a.send(frame(0x321, {9}), CMR_SRR);
  b.run_until(1'000'000);
  EXPECT_EQ(a.receive(), frame(0x321, {9}));
  EXPECT_EQ(r.receive(), frame(0x321, {9}));
}

TEST(Sja1000, SelfTestModeWithSelfReceptionWorksAlone) {
  Bus b;
  Chip a(b);
  a.start(MOD_STM);
  a.send(frame(0x321, {9}), CMR_SRR);
  b.run_until(1'000'000);
  EXPECT_EQ(a.receive(), frame(0x321, {9}));
  EXPECT_EQ(a.chip.read(TXERR), 0);
}

TEST(Sja1000, SingleShotIsTriedOnceAndReleasesTheBufferIncomplete) {
  Bus b;
  Chip a(b);
  a.start();
  a.send(frame(0x123, {1}), CMR_TR | CMR_AT);
  b.run_until(10'000'000);
  EXPECT_EQ(a.chip.read(TXERR), 8);
  EXPECT_EQ(a.chip.read(SR) & (SR_TBS | SR_TCS), SR_TBS);
  EXPECT_TRUE(a.chip.read(IR) & IR_TI);
  EXPECT_EQ(b.bus.error_frames_on_bus(), 1u);
}

// Three chips started; `a` asks to send 0x7FF while `busy`'s 8-byte frame is on the wire (10 bits
// in), so its request waits for the bus.
struct WaitingRequest {
  WaitingRequest() {
    for (auto* c : {&a, &busy, &r}) {
      c->start();
    }
    busy.send(frame(0x001, {1, 2, 3, 4, 5, 6, 7, 8}));
    b.run_until(10 * kBit);
    a.send(frame(0x7FF, {}));
  }
  Bus b;
  Chip a{b};
  Chip busy{b};
  Chip r{b};
};

TEST(Sja1000, AbortBeforeTheStartOfFrameCancelsTheRequest) {
  WaitingRequest w;
  w.a.chip.write(CMR, CMR_AT);
  EXPECT_EQ(w.a.chip.read(SR) & (SR_TBS | SR_TCS), SR_TBS);
  w.b.run_until(2'000'000);
  EXPECT_EQ(w.r.chip.read(RMC), 1);  // only the other chip's frame
}

TEST(Sja1000, ArbitrationLostCaptureHoldsTheBitNumberUntilRead) {
  Bus b;
  Chip a(b), w(b), r(b);
  for (auto* c : {&a, &w, &r}) {
    c->start();
  }
  a.send(frame(0x123, {}));  // 001 0010 0011
  w.send(frame(0x000, {}));  // loses nothing: wins at ID.26
  b.run_until(1'000'000);
  EXPECT_TRUE(a.chip.read(IR) & IR_ALI);
  EXPECT_EQ(a.chip.read(ALC), 2);  // ID.26 is bit number 2
  EXPECT_EQ(r.chip.read(RMC), 2);  // both frames went out in the end
}

TEST(Sja1000, BusOffSetsResetModeAndRecoversAfterTheHostRestartsIt) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start();
  b.plan.add(testing::fault_rule(CanErrorType::bit, 32));
  a.send(frame(0x123, {1}));
  b.run_until(20'000'000);
  EXPECT_EQ(a.chip.read(SR) & (SR_BS | SR_ES), SR_BS | SR_ES);
  EXPECT_EQ(a.chip.read(MOD) & MOD_RM, MOD_RM);
  EXPECT_EQ(a.chip.read(TXERR), 127);
  EXPECT_TRUE(a.chip.read(IR) & IR_EI);
  EXPECT_EQ(r.chip.read(RMC), 0);
  // Host clears reset mode at 20 ms: 128 x 11 bits later the chip is error-active again and
  // the frame still in its transmit buffer goes out.
  a.chip.write(MOD, 0);
  b.run_until(20'000'000 + 128 * 11 * kBit - 1);
  EXPECT_TRUE(a.chip.read(SR) & SR_BS);
  b.run_until(20'000'000 + 128 * 11 * kBit);
  EXPECT_FALSE(a.chip.read(SR) & SR_BS);
  EXPECT_EQ(a.chip.read(TXERR), 0);
  EXPECT_TRUE(a.chip.read(IR) & IR_EI);
  b.run_until(30'000'000);
  EXPECT_EQ(r.chip.read(RMC), 1);
}

// A chip alone on the bus with a programmed error warning limit, sending a frame nobody
// acknowledges: TXERR climbs by 8 an attempt; ES and its interrupt EI follow the limit, EPI the
// error-passive state.
struct WarningLimit {
  const char* name;
  uint8_t ewlr;
  int64_t run_ns;
  uint8_t txerr;
  bool es;   // SR
  bool ei;   // IR
  bool epi;  // IR
};

class Sja1000WarningLimit : public ::testing::TestWithParam<WarningLimit> {};

TEST_P(Sja1000WarningLimit, ALoneSender) {
  const WarningLimit& c = GetParam();
  Bus b;
  Chip a(b);
  a.chip.write(EWLR, c.ewlr);
  a.start();
  a.send(frame(0x123, {1}));
  b.run_until(c.run_ns);
  EXPECT_EQ(a.chip.read(TXERR), c.txerr);
  EXPECT_EQ((a.chip.read(SR) & SR_ES) != 0, c.es);
  const uint8_t ir = a.chip.read(IR);
  EXPECT_EQ((ir & IR_EI) != 0, c.ei);
  EXPECT_EQ((ir & IR_EPI) != 0, c.epi);
}

INSTANTIATE_TEST_SUITE_P(
    Sja1000, Sja1000WarningLimit,
    ::testing::Values(
        // Two unacknowledged attempts: TXERR 16.
        WarningLimit{"ErrorWarningLimitIsProgrammable", 16, 59 * kBit + 100 * kBit, 16, true, true,
                     false},
        // TXERR climbs to 128 and stays: error-passive, but ES (TXERR >= 200) is never set.
        WarningLimit{"ErrorInterruptFollowsTheEsBitNotTheErrorPassiveState", 200, 20'000'000, 128,
                     false, false, true}),
    test_support::CaseName{});

TEST(Sja1000, ErrorCountersAreWritableInResetModeAnd255StartsBusOff) {
  Sja1000 c;
  c.write(RXERR, 100);
  c.write(TXERR, 50);
  EXPECT_EQ(c.read(RXERR), 100);
  EXPECT_EQ(c.read(TXERR), 50);
  c.write(TXERR, 255);
  EXPECT_TRUE(c.read(SR) & SR_BS);
}

// RXERR is an 8-bit register and the counter behind it is no wider: a receiver that keeps seeing
// errors stays at 255 (ISO 11898-1 sets no upper bound; rule 8 takes any value above 127 back
// to 127).
TEST(Sja1000, ReceiveErrorCounterStopsAt255) {
  Sja1000 c;
  for (int i = 0; i < 2000; ++i) {
    c.confinement().receiver_severe_error();
  }
  EXPECT_EQ(c.confinement().rec(), 255);
  EXPECT_EQ(c.read(RXERR), 255);
  c.confinement().receiver_detected_error();
  EXPECT_EQ(c.confinement().rec(), 255);
  c.confinement().receive_succeeded();
  EXPECT_EQ(c.confinement().rec(), 127);
}

}  // namespace
}  // namespace canemu::model

namespace canemu::model {
namespace {

using namespace sja1000;

TEST(Sja1000Interrupts, SourcesDisabledInIerSetNoIrBits) {
  Bus b;
  Chip a(b), r(b);
  a.start();
  r.start();
  r.chip.write(MOD, MOD_RM);
  r.chip.write(IER, IR_TI);  // receive interrupt disabled
  r.chip.write(MOD, 0);
  a.send(frame(0x123, {1}));
  b.run_until(1'000'000);
  EXPECT_EQ(r.chip.read(RMC), 1);
  EXPECT_EQ(r.chip.read(IR), 0);
  EXPECT_EQ(r.interrupts, 0);
  r.chip.write(IER, IR_RI);  // RI follows the FIFO: enabling it now shows the message
  EXPECT_EQ(r.chip.read(IR), IR_RI);
  EXPECT_EQ(r.interrupts, 1);
}

TEST(Sja1000Interrupts, ArbitrationLostCaptureHoldsUntilReadAndRaisesAliOnce) {
  Bus b;
  Chip a(b), w(b), v(b), r(b);
  for (auto* c : {&a, &w, &v, &r}) {
    c->start();
  }
  a.send(frame(0x123, {}));  // 001 0010 0011
  w.send(frame(0x000, {}));  // beats a at ID.26 (ALC 2)
  v.send(frame(0x120, {}));  // then beats a at ID.19 (ALC 9)
  b.run_until(1'000'000);
  EXPECT_EQ(r.chip.read(RMC), 3);
  EXPECT_TRUE(a.chip.read(IR) & IR_ALI);
  EXPECT_EQ(a.chip.read(ALC), 2);  // the first loss, held; the second was not captured
  // Read: armed again. The next loss is captured.
  v.send(frame(0x120, {}));
  a.send(frame(0x123, {}));
  b.run_until(2'000'000);
  EXPECT_TRUE(a.chip.read(IR) & IR_ALI);
  EXPECT_EQ(a.chip.read(ALC), 9);
}

TEST(Sja1000Interrupts, Writing255ToTxerrStartsABusOffThatTheHostSees) {
  Bus b;
  Chip a(b);
  a.chip.write(IER, 0xFF);
  a.chip.write(TXERR, 255);
  EXPECT_TRUE(a.chip.read(SR) & SR_BS);
  EXPECT_TRUE(a.chip.read(IR) & IR_EI);
  EXPECT_EQ(a.chip.read(RXERR), 0);
  EXPECT_EQ(b.bus.stats(a.chip.node()).state_changes.back().state, ErrorState::bus_off);
  // Leaving reset mode starts the recovery: 128 x 11 bit times on the idle bus.
  a.chip.write(BTR0, 0x00);
  a.chip.write(BTR1, 0x1C);
  a.chip.write(MOD, 0);
  b.run_until(128 * 11 * kBit);
  EXPECT_FALSE(a.chip.read(SR) & SR_BS);
  EXPECT_EQ(a.chip.read(TXERR), 0);
}

TEST(Sja1000, EnteringResetModeDropsAPendingRequest) {
  WaitingRequest w;
  w.a.chip.write(MOD, MOD_RM);
  EXPECT_TRUE(w.a.chip.read(SR) & SR_TBS);
  w.a.chip.write(MOD, 0);
  w.b.run_until(2'000'000);
  EXPECT_EQ(w.r.chip.read(RMC), 1);  // only the other chip's frame
}

}  // namespace
}  // namespace canemu::model
