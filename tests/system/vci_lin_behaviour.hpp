// The LIN behaviours of checklist items 138-149 that the VCI C API (libvcinpl) and the C++ API
// (libvciapi) show alike: one suite, instantiated by each API's test program with its
// LinAdapter (an adapter's LIN controller opened through that API: write, write_null, stop,
// drain, texts).
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vci_lin_test_support.hpp"

namespace canemu::testing {

using Texts = std::vector<std::string>;

// The data of the go-to-sleep command (diagnostic frame 3Ch).
inline const std::vector<uint8_t> kSleepData{0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};

// When the go-to-sleep command and the wake-up pulse went out (ns).
struct SleepAndWake {
  int64_t sleep;
  int64_t wake;
};

// 10 ms on, `master` sends the go-to-sleep command; 10 ms later `waker` sends a wake-up pulse,
// and time runs 1 ms past it.
template <class Lin>
SleepAndWake sleep_then_wake(Lin& master, Lin& waker) {
  SleepAndWake at{step_to(10'000'000), 0};
  EXPECT_EQ(master.write(true, lin_type(LIN_MSGTYPE_SLEEP)), VCI_OK);
  at.wake = step_to(10'000'000);
  EXPECT_EQ(waker.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_OK);
  step_to(1'000'000);
  return at;
}

// A write that is refused: to the transmit side (`send`) or the response table, and what.
struct RefusedWrite {
  bool send;
  LINMSG msg;
};

// `lin` refuses each of `writes` with VCI_E_INVALIDARG.
template <class Lin>
void expect_refused(Lin& lin, const std::vector<RefusedWrite>& writes) {
  for (std::size_t k = 0; k < writes.size(); ++k) {
    EXPECT_EQ(lin.write(writes[k].send, writes[k].msg), VCI_E_INVALIDARG) << "write " << k;
  }
}

// What a slave's WriteMessage refuses: a sleep command into its response table, an identifier
// past 3Fh, no data or more than 8 bytes, and anything sent at once but a wake-up pulse.
inline const std::vector<RefusedWrite> kSlaveRefusesBadFrames{
    {false, lin_type(LIN_MSGTYPE_SLEEP)},
    {false, lin_data(64, {1})},
    {false, lin_data(1, {})},
    {false, lin_data(1, {1, 2, 3, 4, 5, 6, 7, 8, 9})},
    {true, lin_data(1, {1})},
    {true, lin_type(LIN_MSGTYPE_SLEEP)}};

// More that a slave's WriteMessage refuses: a wake-up pulse into its response table, identifier
// 40h, and a frame or a sleep command sent at once (only a master sends those).
inline const std::vector<RefusedWrite> kSlaveRefusesWhatOnlyAMasterSends{
    {false, lin_type(LIN_MSGTYPE_WAKEUP)},
    {false, lin_data(0x40, {1})},
    {true, lin_data(0x01, {1})},
    {true, lin_type(LIN_MSGTYPE_SLEEP)}};

// Every test runs on its own canemud with the LIN adapters of kLinAdapters.
template <class Adapter>
class VciLinBehaviour : public ::testing::Test {
 protected:
  VciDaemon d{kLinAdapters};
};
TYPED_TEST_SUITE_P(VciLinBehaviour);

TYPED_TEST_P(VciLinBehaviour, ASlaveAnswersAHeaderFromItsResponseTable) {  // 138, 142 (ido), 147
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER);
  Lin slave("beta");
  ASSERT_EQ(slave.write(false, lin_data(0x10, {0x11, 0x22}, true)), VCI_OK);
  ASSERT_EQ(slave.write(false, lin_data(0x11, {0x33}, false)), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x10, {}, true, true)), VCI_OK);
  const int64_t t1 = step_to(9'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x11, {}, true, true)), VCI_OK);
  step_to(9'000'000);
  const uint32_t e0 = stamp(frame_end(t0, 2));
  const uint32_t e1 = stamp(frame_end(t1, 1));
  EXPECT_EQ(e0, 1000U + 3333U);  // 64 bits at 19200 bit/s: 3333333 ns
  EXPECT_EQ(master.texts(), (Texts{frame_text(e0, 0x10, {0x11, 0x22}, true, false),
                                   frame_text(e1, 0x11, {0x33}, false, false)}));
  EXPECT_EQ(slave.texts(), (Texts{frame_text(e0, 0x10, {0x11, 0x22}, true, true),
                                  frame_text(e1, 0x11, {0x33}, false, true)}));
}

TYPED_TEST_P(VciLinBehaviour, TheResponseTableChangesWhileOnline) {  // 140
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER);
  Lin slave("beta");
  ASSERT_EQ(slave.write(false, lin_data(0x05, {0x01})), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x05, {}, true, true)), VCI_OK);
  const int64_t t1 = step_to(5'000'000);
  ASSERT_EQ(slave.write(false, lin_data(0x05, {0x02, 0x03})), VCI_OK);
  ASSERT_EQ(master.write(true, lin_data(0x05, {}, true, true)), VCI_OK);
  step_to(5'000'000);
  EXPECT_EQ(master.texts(),
            (Texts{frame_text(stamp(frame_end(t0, 1)), 0x05, {0x01}, true, false),
                   frame_text(stamp(frame_end(t1, 2)), 0x05, {0x02, 0x03}, true, false)}));
}

TYPED_TEST_P(VciLinBehaviour, AMasterPublishesSleepsAndWakes) {  // 142 (whole frame), 144
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER);
  Lin slave("beta");
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x22, {0xAA, 0xBB, 0xCC})), VCI_OK);
  const SleepAndWake at = sleep_then_wake(master, master);
  const uint32_t e0 = stamp(frame_end(t0, 3));
  const uint32_t e1 = stamp(frame_end(at.sleep, 8));
  EXPECT_EQ(slave.texts(), (Texts{frame_text(e0, 0x22, {0xAA, 0xBB, 0xCC}, true, false),
                                  frame_text(e1, 0x3C, kSleepData, false, false),
                                  event_text(stamp(at.wake + 250'000), LIN_MSGTYPE_WAKEUP, 0)}));
  EXPECT_EQ(master.texts(), (Texts{frame_text(e0, 0x22, {0xAA, 0xBB, 0xCC}, true, true),
                                   frame_text(e1, 0x3C, kSleepData, false, true)}));
}

TYPED_TEST_P(VciLinBehaviour, WriteMessageNeverWaits) {  // 145
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER);
  step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x01, {1})), VCI_OK);
  EXPECT_EQ(master.write(true, lin_data(0x02, {2})), VCI_E_TXQUEUE_FULL);
  EXPECT_EQ(master.write(true, lin_type(LIN_MSGTYPE_SLEEP)), VCI_E_TXQUEUE_FULL);
  step_to(2'000'000);  // the frame (54 bits, 2.81 ms) is still on the wire
  EXPECT_EQ(master.write(true, lin_data(0x02, {2})), VCI_E_TXQUEUE_FULL);
  step_to(1'000'000);
  EXPECT_EQ(master.write(true, lin_data(0x02, {2})), VCI_OK);
}

TYPED_TEST_P(VciLinBehaviour, CollidingChecksumsAreAChecksumError) {  // 146
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  Lin beta("beta");
  Lin gamma("gamma");
  // Same data, other checksum kinds: the wire carries the AND of the two checksums, which is
  // neither (so the listeners see a checksum error).
  const uint8_t classic = checksum_of({0x20});
  const uint8_t enhanced = checksum_of({0x20}, pid_of(0x20));
  ASSERT_NE(classic & enhanced, classic);
  ASSERT_NE(classic & enhanced, enhanced);
  ASSERT_EQ(beta.write(false, lin_data(0x20, {0x20}, true)), VCI_OK);
  ASSERT_EQ(gamma.write(false, lin_data(0x20, {0x20}, false)), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x20, {}, true, true)), VCI_OK);
  step_to(10'000'000);
  EXPECT_EQ(master.texts(),
            (Texts{event_text(stamp(frame_end(t0, 1)), LIN_MSGTYPE_ERROR, LIN_ERROR_CHKSUM, 0)}));
}

// A parity error a scenario puts on one header of 20h: every listener reports it at the end of
// the header and the responder stays silent (the commander reads back what it sent and sees
// nothing); the next header, past the fault's count, is answered.
TYPED_TEST_P(VciLinBehaviour, AParityErrorFromAScenarioIsAnErrorMessageOfTheListeners) {  // 146
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  Lin beta("beta", LIN_OPMODE_SLAVE | LIN_OPMODE_ERRORS);
  Lin gamma("gamma", LIN_OPMODE_SLAVE | LIN_OPMODE_ERRORS);
  ASSERT_EQ(beta.write(false, lin_data(0x20, {0x55})), VCI_OK);
  testing::load_faults(this->d.daemon,
                       "[[fault]]\nat = \"0s\"\nbus = \"lin0\"\neffect = \"lin_parity_error\"\n"
                       "match = { id = 0x20 }\ncount = 1\n");
  master.drain();
  beta.drain();
  gamma.drain();
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x20, {}, true, true)), VCI_OK);
  const int64_t t1 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x20, {}, true, true)), VCI_OK);
  step_to(10'000'000);
  const Texts parity{event_text(stamp(after_bits(t0, 34)), LIN_MSGTYPE_ERROR, LIN_ERROR_PARITY, 0)};
  const std::string answered = frame_text(stamp(frame_end(t1, 1)), 0x20, {0x55}, true, false);
  EXPECT_EQ(gamma.texts(), (Texts{parity[0], answered}));
  // The responder's own response is marked as its own; the commander's is not.
  EXPECT_EQ(beta.texts(),
            (Texts{parity[0], frame_text(stamp(frame_end(t1, 1)), 0x20, {0x55}, true, true)}));
  EXPECT_EQ(master.texts(), (Texts{answered}));
}

TYPED_TEST_P(VciLinBehaviour, TheMicrosecondCounterWrapsWithATimeOverrunMessage) {  // 149
  using Lin = TypeParam;
  Lin slave("beta");
  slave.drain();
  step_to(4'294'967'296'000 - 1'000);  // 1 ms before 2^32 us
  EXPECT_TRUE(slave.drain().empty());
  step_to(2'000);
  const std::vector<LINMSG> got = slave.drain();
  ASSERT_EQ(got.size(), 1U);
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bType, LIN_MSGTYPE_TMOVR);
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bPid, 0xFF);
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bDlen, 1);
  EXPECT_EQ(got[0].dwTime, 0U);
}

TYPED_TEST_P(VciLinBehaviour, TimeStampsWrapAfterTwoToThe32Microseconds) {  // 149
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER);
  Lin slave("beta");
  slave.drain();
  const int64_t t0 = step_to(4'294'967'296'000 - 2'000'000);      // 2 ms before the wrap
  ASSERT_EQ(master.write(true, lin_data(0x07, {0x77})), VCI_OK);  // 54 bits: ends 2.81 ms later
  step_to(5'000'000);
  const std::vector<LINMSG> got = slave.drain();
  ASSERT_EQ(got.size(), 2U);
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bType, LIN_MSGTYPE_TMOVR);
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bDlen, 1);
  EXPECT_EQ(got[0].dwTime, 0U);
  EXPECT_EQ(text_of(got[1]),
            frame_text(static_cast<uint32_t>(stamp(frame_end(t0, 1)) & 0xFFFFFFFFU), 0x07, {0x77},
                       true, false));
  EXPECT_EQ(got[1].dwTime, 812U);  // 2812 us after t0, 812 us after the wrap
}

TYPED_TEST_P(VciLinBehaviour, WriteMessageRefusesWhatTheModeDoesNotAllow) {  // 141, 143
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER);
  Lin slave("beta");
  expect_refused(slave, kSlaveRefusesBadFrames);
  EXPECT_EQ(master.write(true, lin_type(LIN_MSGTYPE_INFO)), VCI_E_INVALIDARG);
  EXPECT_EQ(master.write_null(true), VCI_E_INVALIDARG);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(slave.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_OK);
  step_to(1'000'000);
  // The master hears the 250 us pulse at its end.
  EXPECT_EQ(master.texts(), (Texts{event_text(stamp(t0 + 250'000), LIN_MSGTYPE_WAKEUP, 0)}));
  ASSERT_EQ(slave.stop(), VCI_OK);
  EXPECT_EQ(slave.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_E_INVALID_STATE);
}

TYPED_TEST_P(VciLinBehaviour, WriteMessageFollowsTheModeAndNeverWaits) {  // 141, 142, 143, 144, 145
  using Lin = TypeParam;
  Lin master("alpha", LIN_OPMODE_MASTER);
  Lin slave("beta");
  expect_refused(slave, kSlaveRefusesWhatOnlyAMasterSends);
  EXPECT_EQ(master.write_null(true), VCI_E_INVALIDARG);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x3B, {1, 2, 3, 4, 5, 6, 7, 8})), VCI_OK);
  EXPECT_EQ(master.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_E_TXQUEUE_FULL);
  const SleepAndWake at = sleep_then_wake(master, slave);
  EXPECT_EQ(master.texts(),
            (Texts{frame_text(stamp(frame_end(t0, 8)), 0x3B, {1, 2, 3, 4, 5, 6, 7, 8}, true, true),
                   frame_text(stamp(frame_end(at.sleep, 8)), 0x3C, kSleepData, false, true),
                   event_text(stamp(at.wake + 250'000), LIN_MSGTYPE_WAKEUP, 0)}));
  EXPECT_EQ(slave.texts(),
            (Texts{frame_text(stamp(frame_end(t0, 8)), 0x3B, {1, 2, 3, 4, 5, 6, 7, 8}, true, false),
                   frame_text(stamp(frame_end(at.sleep, 8)), 0x3C, kSleepData, false, false)}));
}

REGISTER_TYPED_TEST_SUITE_P(VciLinBehaviour, WriteMessageRefusesWhatTheModeDoesNotAllow,
                            WriteMessageFollowsTheModeAndNeverWaits,
                            ASlaveAnswersAHeaderFromItsResponseTable,
                            TheResponseTableChangesWhileOnline, AMasterPublishesSleepsAndWakes,
                            WriteMessageNeverWaits, CollidingChecksumsAreAChecksumError,
                            AParityErrorFromAScenarioIsAnErrorMessageOfTheListeners,
                            TheMicrosecondCounterWrapsWithATimeOverrunMessage,
                            TimeStampsWrapAfterTwoToThe32Microseconds);

}  // namespace canemu::testing
