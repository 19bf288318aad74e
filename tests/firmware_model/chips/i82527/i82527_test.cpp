// The 82527 seen the way a driver sees it (the sequence Linux cc770 uses): chips on one bus,
// programmed and read through their registers, with an SJA1000 beside them. Instants are in ns
// at 500 kbit/s (2000 ns per bit), from the frames' bit counts.
#include "canemu/firmware_model/chips/i82527/i82527.hpp"

#include <gtest/gtest.h>

#include "canemu/firmware_model/adapters/sorcus/bit_params.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000.hpp"
#include "test_controller.hpp"

namespace canemu::model {
namespace {

using namespace i82527;
using testing::frame;
using testing::kBit;
using testing::remote_frame;
using Bus = testing::BusFixture;

// SOF through EOF, in ns.
int64_t ns(const Frame& f) {
  return encode(f).length * kBit;
}
constexpr int64_t kIntermission = 3 * kBit;

struct Interrupt {
  SimTime at;
  uint8_t value;   // the interrupt register when the line went active
  uint8_t status;  // the status register, read then (which ends a status change interrupt)
};

struct Node {
  I82527 chip;
  std::vector<Interrupt> interrupts;

  explicit Node(Bus& bus) {
    chip.connect(bus.bus);
    chip.on_interrupt = [this](SimTime at) {
      const uint8_t value = chip.read(INTERRUPT);
      interrupts.push_back({at, value, value == INTERRUPT_STATUS ? chip.read(STATUS) : uint8_t{0}});
    };
  }
  // As a driver initialises it: configuration access and INI; 16 MHz crystal halved (DSC) to
  // the 8 MHz system clock; 500 kbit/s; masks all "must match"; every object invalid with all
  // flags reset; then INI cleared with the given interrupt enables.
  void start(uint8_t control = CONTROL_IE | CONTROL_EIE) {
    chip.write(CONTROL, CONTROL_CCE | CONTROL_INI);
    chip.write(CPU_INTERFACE, CPUIF_DSC);
    chip.write(BIT_TIMING0, 0x00);
    chip.write(BIT_TIMING1, 0x1C);
    set_masks(0x7FF, 0x1FFFFFFF, 0x1FFFFFFF);
    for (uint8_t n = 1; n <= kObjects; ++n) {
      chip.write(message(n) + CTRL0, pair_write(0, MSGVAL | TXIE | RXIE | INTPND));
      chip.write(message(n) + CTRL1, pair_write(0, RMTPND | TXRQST | CPUUPD | NEWDAT));
    }
    chip.write(CONTROL, control);
  }
  void set_masks(uint32_t standard, uint32_t extended, uint32_t msg15) {
    const auto s = encode_id(standard, false);
    const auto e = encode_id(extended, true);
    const auto m = encode_id(msg15, true);
    for (uint8_t k = 0; k < 4; ++k) {
      if (k < 2) {
        chip.write(static_cast<uint8_t>(GMS + k), s[k]);
      }
      chip.write(static_cast<uint8_t>(GML + k), e[k]);
      chip.write(static_cast<uint8_t>(MSG15_MASK + k), m[k]);
    }
  }
  // Object n: identifier, direction, DLC (the data's length unless given), data, interrupt
  // enables; valid, every other flag reset.
  void setup(uint8_t n, uint32_t id, bool extended, bool transmit, std::vector<uint8_t> data = {},
             uint8_t enables = 0, std::optional<uint8_t> dlc = std::nullopt) {
    const uint8_t base = message(n);
    chip.write(base + CTRL0, pair_write(0, MSGVAL));
    chip.write(base + CTRL1, pair_write(0, RMTPND | TXRQST | CPUUPD | NEWDAT));
    const auto arb = encode_id(id, extended);
    for (uint8_t k = 0; k < 4; ++k) {
      chip.write(static_cast<uint8_t>(base + ARB0 + k), arb[k]);
    }
    const uint8_t length = dlc.value_or(static_cast<uint8_t>(data.size()));
    chip.write(base + CONFIG,
               static_cast<uint8_t>((length << kConfigDlcShift) | (transmit ? CONFIG_DIR : 0) |
                                    (extended ? CONFIG_XTD : 0)));
    for (uint8_t k = 0; k < data.size(); ++k) {
      chip.write(static_cast<uint8_t>(base + DATA0 + k), data[k]);
    }
    chip.write(base + CTRL0, pair_write(static_cast<uint8_t>(MSGVAL | enables),
                                        static_cast<uint8_t>((TXIE | RXIE | INTPND) & ~enables)));
  }
  // Transmit object: new data, not updating, request. Receive object: request a remote frame.
  void request(uint8_t n) { chip.write(message(n) + CTRL1, pair_write(TXRQST | NEWDAT, CPUUPD)); }
  void set_data(uint8_t n, std::vector<uint8_t> data) {
    chip.write(message(n) + CTRL1, pair_write(CPUUPD));
    for (uint8_t k = 0; k < data.size(); ++k) {
      chip.write(static_cast<uint8_t>(message(n) + DATA0 + k), data[k]);
    }
  }
  uint8_t ctrl0(uint8_t n) { return chip.read(message(n) + CTRL0); }
  uint8_t ctrl1(uint8_t n) { return chip.read(message(n) + CTRL1); }
  // The object's content as a driver reads it after a reception.
  Frame stored(uint8_t n) {
    MessageObject o;
    for (uint8_t k = 0; k < kObjectBytes; ++k) {
      o.write(k, chip.read(static_cast<uint8_t>(message(n) + k)));
    }
    return o.frame_as(false);
  }
  // Acknowledge a reception: IntPnd first, then NewDat and MsgLst (on message 15 this releases
  // the shadow register, so the data are read before).
  void release(uint8_t n) {
    chip.write(message(n) + CTRL0, pair_write(0, INTPND));
    chip.write(message(n) + CTRL1, pair_write(0, NEWDAT | MSGLST));
  }
};

// An SJA1000 at 500 kbit/s accepting everything.
struct Sja {
  Sja1000 chip;
  explicit Sja(Bus& bus) {
    chip.connect(bus.bus);
    chip.write(sja1000::BTR0, 0x00);
    chip.write(sja1000::BTR1, 0x1C);
    for (uint8_t i = 0; i < 4; ++i) {
      chip.write(static_cast<uint8_t>(sja1000::AMR0 + i), 0xFF);
    }
    chip.write(sja1000::MOD, 0);
  }
  void send(const Frame& f) {
    std::array<uint8_t, 13> bytes;
    const std::size_t n = sja1000::pack_frame(f, bytes);
    for (std::size_t k = 0; k < n; ++k) {
      chip.write(static_cast<uint8_t>(sja1000::FRAME + k), bytes[k]);
    }
    chip.write(sja1000::CMR, sja1000::CMR_TR);
  }
  std::vector<Frame> received() {
    std::vector<Frame> out;
    while (chip.read(sja1000::SR) & sja1000::SR_RBS) {
      std::array<uint8_t, 13> bytes;
      for (uint8_t k = 0; k < 13; ++k) {
        bytes[k] = chip.read(static_cast<uint8_t>(sja1000::FRAME + k));
      }
      chip.write(sja1000::CMR, sja1000::CMR_RRB);
      out.push_back(*sja1000::unpack_frame(bytes.data()));
    }
    return out;
  }
};

// What the chip tells the firmware model above it.
struct Listener : ControllerEvents {
  std::vector<Frame> received, transmitted, lost;
  void frame_received(SimTime, const Frame& f, bool) override { received.push_back(f); }
  void frame_transmitted(SimTime, const Frame& f) override { transmitted.push_back(f); }
  void overrun(SimTime, const Frame& f) override { lost.push_back(f); }
};

// Two 82527s on one bus, `a` and `r`, both initialised as a driver does (Node::start()).
class I82527Pair : public ::testing::Test {
 protected:
  I82527Pair() {
    a.start();
    r.start();
  }
  Bus b;
  Node a{b};
  Node r{b};
};

TEST(I82527, StartsInitialisingWithEveryFlagResetAndNoCounterRegisters) {
  I82527 c;
  EXPECT_EQ(c.read(CONTROL), CONTROL_INI);
  EXPECT_EQ(c.read(STATUS), 0x00);
  EXPECT_EQ(c.read(INTERRUPT), INTERRUPT_NONE);
  EXPECT_EQ(c.read(message(1) + CTRL0), 0x55);
  EXPECT_EQ(c.read(message(15) + CTRL1), 0x55);
  EXPECT_FALSE(c.participating());
  // 0x6F and 0x7F are the CC770's error counters; the 82527 has none there.
  c.confinement().set_counters(100, 50);
  EXPECT_EQ(c.read(0x6F), 0xFF);
  EXPECT_EQ(c.read(0x7F), 0xFF);
}

TEST(I82527, AHardwareResetRestoresTheResetValues) {
  Bus b;
  Node a(b);
  a.start(CONTROL_IE | CONTROL_SIE | CONTROL_EIE);
  a.setup(3, 0x123, true, true, {1, 2}, TXIE | RXIE);
  a.set_masks(0x7F0, 0x1FFFFF00, 0x1FFFF000);
  a.chip.write(STATUS, LEC_UNUSED);
  a.chip.confinement().set_counters(200, 0);
  a.chip.hardware_reset();
  EXPECT_EQ(a.chip.read(CONTROL), CONTROL_INI);
  EXPECT_EQ(a.chip.read(STATUS), 0x00);  // LEC cleared, WARN gone with the counters
  EXPECT_EQ(a.chip.read(CPU_INTERFACE), 0x00);
  EXPECT_EQ(a.chip.read(BIT_TIMING1), 0x00);
  EXPECT_EQ(a.chip.read(GMS), 0x00);
  EXPECT_EQ(a.chip.read(message(3) + CTRL0), 0x55);
  EXPECT_EQ(a.chip.read(message(3) + CONFIG), 0x00);
  EXPECT_EQ(a.chip.confinement().tec(), 0);
  EXPECT_FALSE(a.chip.participating());
}

TEST(I82527, BitTimingCountsInTheSystemClockAndIsWritableOnlyWithCce) {
  I82527 c;  // 16 MHz crystal
  c.write(BIT_TIMING1, 0x1C);
  EXPECT_EQ(c.read(BIT_TIMING1), 0x00);  // CCE clear: ignored
  c.write(CONTROL, CONTROL_CCE | CONTROL_INI);
  c.write(BIT_TIMING0, 0x00);
  c.write(BIT_TIMING1, 0x1C);
  EXPECT_EQ(c.timing().nominal.bit_rate(), (BitRate{1'000'000, 1}));  // SCLK 16 MHz
  c.write(CPU_INTERFACE, CPUIF_DSC);
  EXPECT_EQ(c.sclk_hz(), 8'000'000u);
  EXPECT_EQ(c.timing().nominal.bit_rate(), (BitRate{500'000, 1}));
  EXPECT_EQ(c.timing().nominal.clock_hz, 8'000'000u);
  EXPECT_EQ(c.timing().nominal.prescaler, 1u);
  EXPECT_EQ(c.timing().nominal.quanta_per_bit(), 16u);
  // The X-CAN-2i CiA table rows at 125 ns (the manual's CiA table): 10 kbit/s = 0x67/0x2F (tq 5 us,
  // 16 + 3 + 1 quanta, SJW 2), 125 kbit/s = 0x03/0x1C.
  c.write(BIT_TIMING0, 0x67);
  c.write(BIT_TIMING1, 0x2F);
  EXPECT_EQ(c.timing().nominal.bit_rate(), (BitRate{10'000, 1}));
  EXPECT_EQ(c.timing().nominal.sjw, 2u);
  EXPECT_EQ(c.timing().nominal.sample_point_permille(), 850u);
  c.write(BIT_TIMING0, 0x03);
  c.write(BIT_TIMING1, 0x1C);
  EXPECT_EQ(c.timing().nominal.bit_rate(), (BitRate{125'000, 1}));
  // The same timing as the X-CAN-2i driver's parameters for that row give.
  EXPECT_EQ(c.timing().nominal, *sorcus::decode_sorcus(sorcus::kXCan2i, {500, 13, 2, 1, 1}));
  c.write(CONTROL, CONTROL_INI);
  c.write(BIT_TIMING0, 0x00);
  EXPECT_EQ(c.read(BIT_TIMING0), 0x03);
}

TEST_F(I82527Pair, TwoChipsAndAnSja1000ExchangeFramesBothWays) {
  Sja s(b);
  a.setup(1, 0x123, false, true, {0x11, 0x22}, TXIE);
  r.setup(1, 0x123, false, false, {}, RXIE);
  r.setup(2, 0x18FF0010, true, false, {}, RXIE);
  a.setup(15, 0, true, false, {}, RXIE);
  a.set_masks(0x7FF, 0x1FFFFFFF, 0);  // message 15 takes every extended data frame
  // 82527 -> 82527 and SJA1000.
  const Frame f1 = frame(0x123, {0x11, 0x22});
  a.request(1);
  b.run_until(ns(f1) - 1);
  EXPECT_TRUE(r.interrupts.empty());
  b.run_until(ns(f1));
  ASSERT_EQ(r.interrupts.size(), 1u);
  EXPECT_EQ(r.interrupts[0].at.ns(), ns(f1));
  EXPECT_EQ(r.interrupts[0].value, interrupt_for_message(1));
  EXPECT_EQ(r.stored(1), f1);
  EXPECT_EQ(r.ctrl1(1), 0x56);  // NewDat only
  EXPECT_EQ(r.chip.read(STATUS), STATUS_RXOK);
  ASSERT_EQ(a.interrupts.size(), 1u);
  EXPECT_EQ(a.interrupts[0].at.ns(), ns(f1));
  EXPECT_EQ(a.interrupts[0].value, interrupt_for_message(1));
  EXPECT_EQ(a.chip.read(STATUS), STATUS_TXOK);
  EXPECT_EQ(a.ctrl1(1) & 0x30, 0x10);  // TxRqst reset
  EXPECT_EQ(s.received(), std::vector<Frame>{f1});
  r.release(1);
  a.chip.write(message(1) + CTRL0, pair_write(0, INTPND));
  EXPECT_EQ(r.chip.read(INTERRUPT), INTERRUPT_NONE);
  EXPECT_EQ(a.chip.read(INTERRUPT), INTERRUPT_NONE);
  // SJA1000 -> both 82527: object 2 of one, message 15 of the other.
  const Frame f2 = frame(0x18FF0010, {1, 2, 3}, true);
  const int64_t t2 = 1'000'000;
  b.run_until(t2);
  s.send(f2);
  b.run_until(t2 + ns(f2));
  ASSERT_EQ(r.interrupts.size(), 2u);
  EXPECT_EQ(r.interrupts[1].at.ns(), t2 + ns(f2));
  EXPECT_EQ(r.interrupts[1].value, interrupt_for_message(2));
  EXPECT_EQ(r.stored(2), f2);
  ASSERT_EQ(a.interrupts.size(), 2u);
  EXPECT_EQ(a.interrupts[1].at.ns(), t2 + ns(f2));
  EXPECT_EQ(a.interrupts[1].value, INTERRUPT_MSG15);
  EXPECT_EQ(a.stored(15), f2);  // the received identifier is in the arbitration registers
  EXPECT_EQ(a.chip.read(message(15) + ARB0), 0xC7);
  // The 82527 answers back: the one that received sends.
  r.setup(3, 0x0AA, false, true, {0x5A}, 0);
  r.request(3);
  b.run_until(2'000'000);
  EXPECT_EQ(s.received(), std::vector<Frame>{frame(0x0AA, {0x5A})});
}

TEST(I82527, RegisterIdentifierBytesGoOnTheWireAsTheWorkedExampleSays) {
  Bus b;
  Node a(b);
  Sja s(b);
  a.start();
  a.setup(1, 0, true, true, {0x01});
  const uint8_t bytes[4] = {0x91, 0xA2, 0xB3, 0xC0};  // 0x12345678 << 3
  for (uint8_t k = 0; k < 4; ++k) {
    a.chip.write(static_cast<uint8_t>(message(1) + ARB0 + k), bytes[k]);
  }
  a.setup(2, 0, false, true, {0x02});
  a.chip.write(message(2) + ARB0, 0x24);  // 0x123: 0010 0100, 011x xxxx
  a.chip.write(message(2) + ARB0 + 1, 0x7F);
  a.request(1);
  a.request(2);
  b.run_until(1'000'000);
  EXPECT_EQ(s.received(),
            (std::vector<Frame>{frame(0x12345678, {0x01}, true), frame(0x123, {0x02})}));
}

TEST(I82527, LowestObjectNumberTransmitsFirstWhateverTheIdentifiers) {
  Bus b;
  Node a(b);
  Sja s(b);
  a.start();
  a.setup(5, 0x100, false, true, {5}, TXIE);
  a.setup(3, 0x700, false, true, {3}, TXIE);
  a.setup(9, 0x001, false, true, {9}, TXIE);
  a.chip.write(CONTROL, CONTROL_INI | CONTROL_IE);
  a.request(9);
  a.request(5);
  a.request(3);
  a.chip.write(CONTROL, CONTROL_IE);  // all three pending at once
  const Frame f3 = frame(0x700, {3}), f5 = frame(0x100, {5}), f9 = frame(0x001, {9});
  const int64_t end3 = ns(f3);
  const int64_t end5 = end3 + kIntermission + ns(f5);
  const int64_t end9 = end5 + kIntermission + ns(f9);
  b.run_until(end9);
  EXPECT_EQ(s.received(), (std::vector<Frame>{f3, f5, f9}));
  ASSERT_EQ(a.interrupts.size(), 1u);
  EXPECT_EQ(a.interrupts[0].at.ns(), end3);
  EXPECT_EQ(a.interrupts[0].value, interrupt_for_message(3));
  // All three have IntPnd; the register names the lowest number, then the next.
  a.chip.write(message(3) + CTRL0, pair_write(0, INTPND));
  EXPECT_EQ(a.chip.read(INTERRUPT), interrupt_for_message(5));
  a.chip.write(message(5) + CTRL0, pair_write(0, INTPND));
  EXPECT_EQ(a.chip.read(INTERRUPT), interrupt_for_message(9));
  EXPECT_EQ(b.bus.stats(s.chip.node()).frames_received, 3u);
}

TEST_F(I82527Pair, TransmitObjectAnswersAMatchingRemoteFrameByItself) {
  Sja s(b);
  a.setup(2, 0x321, false, true, {0xCA, 0xFE}, TXIE);
  r.setup(4, 0x321, false, false, {}, RXIE, 2);
  r.request(4);  // a receive object with TxRqst sends a remote frame
  const Frame rtr = remote_frame(0x321, 2);
  const Frame answer = frame(0x321, {0xCA, 0xFE});
  const int64_t answered = ns(rtr) + kIntermission + ns(answer);
  b.run_until(ns(rtr));
  EXPECT_EQ(a.ctrl1(2), 0xA5);         // RmtPnd, TxRqst: the answer is pending
  EXPECT_TRUE(a.interrupts.empty());   // no interrupt for the remote frame itself
  EXPECT_EQ(r.ctrl1(4) & 0x30, 0x10);  // the remote frame went out
  b.run_until(answered);
  EXPECT_EQ(s.received(), (std::vector<Frame>{rtr, answer}));
  ASSERT_EQ(a.interrupts.size(), 1u);
  EXPECT_EQ(a.interrupts[0].at.ns(),
            answered);  // after the answer, as the X-CAN-2i manual §10.9.2.5 says
  EXPECT_EQ(a.interrupts[0].value, interrupt_for_message(2));
  EXPECT_EQ(a.ctrl1(2), 0x55);  // RmtPnd and TxRqst reset (NewDat was never set)
  ASSERT_EQ(r.interrupts.size(), 1u);
  EXPECT_EQ(r.interrupts[0].at.ns(), answered);
  EXPECT_EQ(r.interrupts[0].value, interrupt_for_message(4));
  EXPECT_EQ(r.stored(4), answer);
}

TEST_F(I82527Pair, RemoteRequestedAnswerOvertakesAHigherNumberedObjectThatLostArbitration) {
  Sja s(b);
  a.setup(2, 0x321, false, true, {0xCA, 0xFE});
  a.setup(5, 0x400, false, true, {0x05});
  r.setup(4, 0x321, false, false, {}, 0, 2);
  r.request(4);
  a.request(5);  // both start together; 0x321 wins arbitration
  const Frame rtr = remote_frame(0x321, 2);
  const Frame answer = frame(0x321, {0xCA, 0xFE});
  const Frame other = frame(0x400, {0x05});
  const int64_t end = ns(rtr) + kIntermission + ns(answer) + kIntermission + ns(other);
  b.run_until(end);
  EXPECT_EQ(s.received(), (std::vector<Frame>{rtr, answer, other}));
  EXPECT_EQ(b.bus.stats(a.chip.node()).arbitration_lost, 1u);
  EXPECT_EQ(b.bus.stats(s.chip.node()).frames_received, 3u);
  EXPECT_EQ(r.stored(4), answer);
}

TEST_F(I82527Pair, CpuUpdateHoldsTheAnswerUntilTheCpuIsDone) {
  Sja s(b);
  a.setup(2, 0x321, false, true, {0xCA, 0xFE}, TXIE);
  r.setup(4, 0x321, false, false, {}, RXIE, 2);
  a.set_data(2, {0xBE, 0xEF});  // CPUUpd set while the CPU writes
  r.request(4);
  const Frame rtr = remote_frame(0x321, 2);
  b.run_until(1'000'000);
  EXPECT_EQ(s.received(), std::vector<Frame>{rtr});
  EXPECT_EQ(a.ctrl1(2), 0xA9);  // RmtPnd, TxRqst, CPUUpd: held
  EXPECT_TRUE(a.interrupts.empty());
  // The CPU resets CPUUpd at 1 ms: the answer starts at once, with the new data.
  a.chip.write(message(2) + CTRL1, pair_write(0, CPUUPD));
  const Frame answer = frame(0x321, {0xBE, 0xEF});
  b.run_until(1'000'000 + ns(answer));
  EXPECT_EQ(s.received(), std::vector<Frame>{answer});
  ASSERT_EQ(r.interrupts.size(), 1u);
  EXPECT_EQ(r.interrupts[0].at.ns(), 1'000'000 + ns(answer));
  EXPECT_EQ(r.stored(4), answer);
  EXPECT_EQ(a.ctrl1(2), 0x55);
}

TEST_F(I82527Pair, FrameStoredOverUnreadDataSetsMessageLost) {
  a.setup(1, 0x200, false, true, {1});
  r.setup(1, 0x200, false, false, {}, RXIE);
  a.request(1);
  b.run_until(1'000'000);
  EXPECT_EQ(r.ctrl1(1), 0x56);  // NewDat
  a.set_data(1, {2});
  a.request(1);
  b.run_until(2'000'000);
  EXPECT_EQ(r.ctrl1(1), 0x5A);  // NewDat and MsgLst
  EXPECT_EQ(r.stored(1), frame(0x200, {2}));
  EXPECT_EQ(r.interrupts.size(), 1u);  // IntPnd was still set
  r.release(1);
  EXPECT_EQ(r.ctrl1(1), 0x55);
  EXPECT_EQ(r.chip.read(INTERRUPT), INTERRUPT_NONE);
  // Read in time, the next frame is stored without MsgLst.
  a.set_data(1, {3});
  a.request(1);
  b.run_until(3'000'000);
  EXPECT_EQ(r.ctrl1(1), 0x56);
  EXPECT_EQ(r.interrupts.size(), 2u);
}

TEST_F(I82527Pair, MessageFifteenKeepsASecondFrameInItsShadowAndTheThirdOverwritesIt) {
  a.setup(1, 0x010, false, true, {1});
  a.setup(2, 0x011, false, true, {2});
  a.setup(3, 0x012, false, true, {3});
  r.setup(15, 0x000, false, false, {}, RXIE);
  r.set_masks(0x7FF, 0x1FFFFFFF, 0);  // message 15 takes every standard data frame
  Listener heard;
  r.chip.set_listener(&heard);
  a.chip.write(CONTROL, CONTROL_INI | CONTROL_IE | CONTROL_EIE);
  a.request(1);
  a.request(2);
  a.request(3);
  a.chip.write(CONTROL, CONTROL_IE | CONTROL_EIE);  // a burst, back to back
  const Frame f1 = frame(0x010, {1}), f2 = frame(0x011, {2}), f3 = frame(0x012, {3});
  const int64_t end1 = ns(f1);
  const int64_t end3 = end1 + kIntermission + ns(f2) + kIntermission + ns(f3);
  b.run_until(end3);
  ASSERT_EQ(r.interrupts.size(), 1u);
  EXPECT_EQ(r.interrupts[0].at.ns(), end1);
  EXPECT_EQ(r.interrupts[0].value, INTERRUPT_MSG15);
  // The first frame is in message 15; the third has replaced the second in the shadow
  // register, and MsgLst says so.
  EXPECT_EQ(r.stored(15), f1);
  EXPECT_EQ(r.ctrl1(15), 0x5A);
  EXPECT_EQ(heard.received, (std::vector<Frame>{f1, f2, f3}));
  EXPECT_EQ(heard.lost, std::vector<Frame>{f2});
  // The driver reads, then resets IntPnd and NewDat: the shadow moves in at that instant.
  const int64_t t = 1'000'000;
  b.run_until(t);
  r.release(15);
  ASSERT_EQ(r.interrupts.size(), 2u);
  EXPECT_EQ(r.interrupts[1].at.ns(), t);
  EXPECT_EQ(r.interrupts[1].value, INTERRUPT_MSG15);
  EXPECT_EQ(r.stored(15), f3);
  EXPECT_EQ(r.ctrl1(15), 0x56);  // NewDat; release() reset MsgLst with NewDat
  r.release(15);
  EXPECT_EQ(r.ctrl1(15), 0x55);
  EXPECT_EQ(r.chip.read(INTERRUPT), INTERRUPT_NONE);
  EXPECT_EQ(r.interrupts.size(), 2u);
}

TEST_F(I82527Pair, MessageFifteenHoldsTheSecondFrameWithoutLoss) {
  a.setup(1, 0x010, false, true, {1});
  a.setup(2, 0x011, false, true, {2});
  r.setup(15, 0x000, false, false, {}, RXIE);
  r.set_masks(0x7FF, 0x1FFFFFFF, 0);
  a.request(1);
  a.request(2);
  b.run_until(1'000'000);
  EXPECT_EQ(r.ctrl1(15), 0x56);  // NewDat, no MsgLst
  EXPECT_EQ(r.stored(15), frame(0x010, {1}));
  r.release(15);
  EXPECT_EQ(r.stored(15), frame(0x011, {2}));
  EXPECT_EQ(r.ctrl1(15), 0x56);
}

TEST(I82527, MessageFifteenWithDirSetStoresRemoteFramesOnly) {
  Bus b;
  Node r(b);
  Sja s(b);
  r.start();
  r.setup(1, 0x100, false, false, {}, RXIE);  // a receive object takes no remote frame
  r.setup(15, 0x000, false, true, {}, RXIE);  // DIR = 1: remote frames
  r.set_masks(0x7FF, 0x1FFFFFFF, 0);
  s.send(frame(0x101, {1}));
  b.run_until(1'000'000);
  EXPECT_EQ(r.ctrl1(15), 0x55);
  s.send(remote_frame(0x100, 4));
  b.run_until(2'000'000);
  EXPECT_EQ(r.ctrl1(1), 0x55);
  EXPECT_EQ(r.ctrl1(15), 0x56);
  EXPECT_EQ(r.chip.read(message(15) + CONFIG), 0x48);  // DLC 4, DIR kept
  EXPECT_EQ(r.chip.read(message(15) + ARB0), 0x20);
  ASSERT_EQ(r.interrupts.size(), 1u);
  EXPECT_EQ(r.interrupts[0].value, INTERRUPT_MSG15);
  // Receive-only: TxRqst on message 15 sends nothing.
  r.chip.write(message(15) + CTRL1, pair_write(TXRQST));
  b.run_until(3'000'000);
  EXPECT_EQ(b.bus.stats(r.chip.node()).frames_sent, 0u);
  EXPECT_TRUE(s.received().empty());
}

TEST(I82527, GlobalMasksFilterObjectsAndMessageFifteensMaskIsAndedWithThem) {
  Bus b;
  Node r(b);
  Sja s(b);
  r.start();
  // Standard: 0x7F0 leaves the low nibble open; message 15's own 0x70F gives it 0x700.
  // Extended: the low 8 bits open.
  r.set_masks(0x7F0, 0x1FFFFF00, 0x1C3FFFFF);  // msg15: first 11 bits 0x70F
  EXPECT_EQ(r.chip.read(GMS), 0xFE);
  EXPECT_EQ(r.chip.read(GMS + 1), 0x00);
  EXPECT_EQ(r.chip.read(MSG15_MASK), 0xE1);
  EXPECT_EQ(r.chip.read(MSG15_MASK + 1), 0xFF);
  r.setup(1, 0x120, false, false, {}, RXIE);
  r.setup(2, 0x12345600, true, false, {}, RXIE);
  r.setup(15, 0x3AB, false, false, {}, RXIE);
  const std::vector<Frame> frames{frame(0x125, {1}),              // object 1 (0x12x)
                                  frame(0x355, {2}),              // message 15: 0x3xx
                                  frame(0x3A5, {3}),              // 0x3Ax: object 1 no, 15 yes
                                  frame(0x455, {4}),              // nobody
                                  frame(0x123456AB, {5}, true),   // object 2
                                  frame(0x12345700, {6}, true)};  // nobody
  std::vector<uint8_t> takers;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const int64_t t = static_cast<int64_t>(k) * 1'000'000;
    b.run_until(t);
    s.send(frames[k]);
    b.run_until(t + ns(frames[k]));
    // RXOK for every frame, taken or not.
    EXPECT_EQ(r.chip.read(STATUS) & STATUS_RXOK, STATUS_RXOK);
    r.chip.write(STATUS, 0);
    uint8_t taker = 0;
    for (const uint8_t n : {uint8_t{1}, uint8_t{2}, uint8_t{15}}) {
      if (r.ctrl1(n) & 0x02) {
        EXPECT_EQ(r.stored(n), frames[k]);
        r.release(n);
        taker = n;
      }
    }
    takers.push_back(taker);
  }
  EXPECT_EQ(takers, (std::vector<uint8_t>{1, 15, 15, 0, 2, 0}));
}

TEST(I82527, WarnAndBusOffRaiseStatusChangeInterruptsAtTheirInstants) {
  Bus b;
  Node a(b), r(b);
  a.start(CONTROL_IE | CONTROL_EIE);
  r.start();
  a.setup(1, 0x123, false, true, {0x11, 0x22});
  r.setup(1, 0x123, false, false);
  FaultRule rule;
  rule.fault.error = CanErrorType::bit;
  rule.count = 32;
  b.plan.add(rule);
  a.request(1);
  // Each attempt: the bit error at bit 13 (the IDE bit, sent dominant, seen recessive: LEC 5)
  // is detected at the end of bit 13. With an active flag the cycle is 35 bits: the flag from
  // bit 14, the receivers' stuff error at bit 17 (six dominant bits from the RTR bit on) and
  // their flags to bit 23, the delimiter 24..31, intermission 32..34. The 16th error makes the
  // node error-passive (TEC 128), which adds 8 bits of suspend transmission: 43 bits. From the
  // 17th error on the flag is passive, 45 bits: six recessive bits 14..19 that the receivers
  // see as a stuff error at 19, their flags 20..25, the delimiter 26..33, intermission 34..36
  // and the suspend transmission 37..44.
  const int64_t warn_at = (14 + 11 * 35) * kBit;                 // 12th error: TEC 96
  const int64_t boff_at = (14 + 15 * 35 + 43 + 15 * 45) * kBit;  // 32nd error: TEC 256
  b.run_until(warn_at - 1);
  EXPECT_TRUE(a.interrupts.empty());
  b.run_until(boff_at);
  ASSERT_EQ(a.interrupts.size(), 2u);
  EXPECT_EQ(a.interrupts[0].at.ns(), warn_at);
  EXPECT_EQ(a.interrupts[0].value, INTERRUPT_STATUS);
  EXPECT_EQ(a.interrupts[0].status, STATUS_WARN | LEC_BIT0);
  EXPECT_EQ(a.interrupts[1].at.ns(), boff_at);
  EXPECT_EQ(a.interrupts[1].value, INTERRUPT_STATUS);
  EXPECT_EQ(a.interrupts[1].status, STATUS_BOFF | STATUS_WARN | LEC_BIT0);
  EXPECT_EQ(a.chip.read(CONTROL) & CONTROL_INI, CONTROL_INI);  // bus-off sets INI
  EXPECT_EQ(a.chip.confinement().tec(), 256);  // for the model only: no register shows it
  // Nothing happens until the CPU clears INI at 4 ms; then 128 x 11 recessive bits.
  const int64_t restart = 4'000'000;
  b.run_until(restart);
  EXPECT_EQ(a.interrupts.size(), 2u);
  a.chip.write(CONTROL, CONTROL_IE | CONTROL_EIE);
  const int64_t recovered = restart + 128 * 11 * kBit;
  b.run_until(recovered - 1);
  EXPECT_EQ(a.interrupts.size(), 2u);
  EXPECT_EQ(a.chip.read(STATUS) & STATUS_BOFF, STATUS_BOFF);
  b.run_until(recovered);
  ASSERT_EQ(a.interrupts.size(), 3u);
  EXPECT_EQ(a.interrupts[2].at.ns(), recovered);
  EXPECT_EQ(a.interrupts[2].status, LEC_BIT0);  // WARN and BOFF gone
  EXPECT_EQ(a.chip.confinement().tec(), 0);
  // The request still pending goes out at once.
  const Frame f = frame(0x123, {0x11, 0x22});
  b.run_until(recovered + ns(f));
  EXPECT_EQ(r.stored(1), f);
  EXPECT_EQ(r.ctrl1(1), 0x56);
  EXPECT_EQ(a.chip.read(STATUS), STATUS_TXOK);
  EXPECT_EQ(a.ctrl1(1) & 0x30, 0x10);
}

TEST(I82527, StatusChangeInterruptReportsTheLastErrorCode) {
  Bus b;
  Node a(b);
  a.start(CONTROL_IE | CONTROL_SIE);
  a.setup(1, 0x123, false, true, {0x11, 0x22});
  a.request(1);
  // Alone on the bus: no acknowledgement, an ACK error at the ACK slot.
  const EncodedFrame bits = encode(frame(0x123, {0x11, 0x22}));
  const int64_t ack_at = (bits.field_begin(Field::ack_slot) + 1) * kBit;
  b.run_until(ack_at);
  ASSERT_EQ(a.interrupts.size(), 1u);
  EXPECT_EQ(a.interrupts[0].at.ns(), ack_at);
  EXPECT_EQ(a.interrupts[0].status, LEC_ACK);
  a.chip.write(CONTROL, CONTROL_INI);
}

}  // namespace
}  // namespace canemu::model
