// The LIN functions of the VCI C API (libvcinpl) against canemud: checklist items 133-149 of
// the VCI digest, with exact time stamps in stepped time.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vci_c_lin_support.hpp"

namespace canemu::testing {
namespace {

TEST(VciCLin, TheLinControllerIsNumberedAfterTheCanControllersAndOpensOnce) {  // 133
  VciDaemon d(kLinAdapters);
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  VCIDEVICECAPS caps{};
  ASSERT_EQ(vciDeviceGetCaps(dev, &caps), VCI_OK);
  EXPECT_EQ(caps.BusCtrlCount, 2);
  EXPECT_EQ(caps.BusCtrlTypes[0], VCI_CAN_CTRL(CAN_CTRL_SJA1000));
  EXPECT_EQ(caps.BusCtrlTypes[1], VCI_LIN_CTRL(LIN_CTRL_UNKNOWN));
  HANDLE a = nullptr;
  HANDLE b = nullptr;
  EXPECT_EQ(linControlOpen(dev, 0, &b), VCI_E_INVALIDARG);  // a CAN controller
  EXPECT_EQ(linControlOpen(dev, 2, &b), VCI_E_INVALIDARG);
  EXPECT_EQ(canControlOpen(dev, kLinNo, &b), VCI_E_INVALIDARG);
  ASSERT_EQ(linControlOpen(dev, kLinNo, &a), VCI_OK);
  EXPECT_EQ(linControlOpen(dev, kLinNo, &b), VCI_E_ACCESSDENIED);
  EXPECT_EQ(b, nullptr);
  EXPECT_EQ(linControlClose(a), VCI_OK);
  EXPECT_EQ(linControlClose(a), VCI_E_INVHANDLE);
  ASSERT_EQ(linControlOpen(dev, kLinNo, &b), VCI_OK);
  EXPECT_EQ(linControlClose(b), VCI_OK);
  vciDeviceClose(dev);
}

TEST(VciCLin, InitializeTakesOneToTwentyKbitPerSecond) {  // 134
  VciDaemon d(kLinAdapters);
  LinAdapter a("alpha", LIN_OPMODE_MASTER, false);
  EXPECT_EQ(linControlInitialize(a.control, LIN_OPMODE_MASTER, 999), VCI_E_INVALIDARG);
  EXPECT_EQ(linControlInitialize(a.control, LIN_OPMODE_MASTER, 20001), VCI_E_INVALIDARG);
  EXPECT_EQ(linControlInitialize(a.control, LIN_OPMODE_MASTER, LIN_BITRATE_AUTO),
            VCI_E_INVALIDARG);  // a master sets the rate
  EXPECT_EQ(linControlInitialize(a.control, 0x80, kRate), VCI_E_INVALIDARG);
  ASSERT_EQ(linControlInitialize(a.control, LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS, kRate), VCI_OK);
  LINLINESTATUS s{};
  ASSERT_EQ(linControlGetStatus(a.control, &s), VCI_OK);
  EXPECT_EQ(s.bOpMode, LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  EXPECT_EQ(s.wBitrate, kRate);
  EXPECT_EQ(s.dwStatus, LIN_STATUS_ININIT);
  ASSERT_EQ(linControlStart(a.control, TRUE), VCI_OK);
  ASSERT_EQ(linControlGetStatus(a.control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, 0U);
  LINCAPABILITIES c{};
  ASSERT_EQ(linControlGetCaps(a.control, &c), VCI_OK);
  EXPECT_EQ(c.dwFeatures, 0x3FU);
  EXPECT_EQ(c.dwClockFreq, 1'000'000U);
  EXPECT_EQ(c.dwTscDivisor, 1U);
  ASSERT_EQ(linMonitorGetCaps(a.monitor, &c), VCI_OK);
  EXPECT_EQ(c.dwFeatures, 0x3FU);
}

TEST(VciCLin, StartStopAndResetAreToldToTheMonitors) {  // 135
  VciDaemon d(kLinAdapters);
  LinAdapter a("alpha", LIN_OPMODE_MASTER, false);
  ASSERT_EQ(linControlReset(a.control), VCI_OK);
  EXPECT_EQ(linControlStart(a.control, TRUE), VCI_E_INVALID_STATE);  // not initialized
  a.drain();
  const int64_t t = step_to(1'234'567);
  ASSERT_EQ(linControlInitialize(a.control, LIN_OPMODE_MASTER, kRate), VCI_OK);
  ASSERT_EQ(linControlStart(a.control, TRUE), VCI_OK);
  ASSERT_EQ(linControlStart(a.control, FALSE), VCI_OK);
  ASSERT_EQ(linControlReset(a.control), VCI_OK);
  std::vector<std::string> got;
  for (const LINMSG& m : a.drain()) {
    got.push_back(text_of(m));
  }
  EXPECT_EQ(got, (Texts{event_text(stamp(t), LIN_MSGTYPE_INFO, LIN_INFO_START),
                        event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_STOP),
                        event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_RESET)}));
}

TEST(VciCLin, AMonitorNeedsAFifoAndOneExclusiveMonitorIsAlone) {  // 136, 137
  VciDaemon d(kLinAdapters);
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  HANDLE shared = nullptr;
  HANDLE other = nullptr;
  ASSERT_EQ(linMonitorOpen(dev, kLinNo, FALSE, &shared), VCI_OK);
  EXPECT_EQ(linMonitorInitialize(shared, 0, 1), VCI_E_INVALIDARG);
  LINMSG m{};
  EXPECT_EQ(linMonitorPeekMessage(shared, &m), VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(linMonitorOpen(dev, kLinNo, TRUE, &other), VCI_E_ACCESSDENIED);
  ASSERT_EQ(linMonitorOpen(dev, kLinNo, FALSE, &other), VCI_OK);  // shared ones: many
  ASSERT_EQ(linMonitorClose(other), VCI_OK);
  ASSERT_EQ(linMonitorClose(shared), VCI_OK);
  HANDLE exclusive = nullptr;
  ASSERT_EQ(linMonitorOpen(dev, kLinNo, TRUE, &exclusive), VCI_OK);
  EXPECT_EQ(linMonitorOpen(dev, kLinNo, FALSE, &other), VCI_E_ACCESSDENIED);
  ASSERT_EQ(linMonitorClose(exclusive), VCI_OK);
  ASSERT_EQ(linMonitorOpen(dev, kLinNo, FALSE, &other), VCI_OK);
  ASSERT_EQ(linMonitorInitialize(other, 10, 1), VCI_OK);
  LINMONITORSTATUS s{};
  ASSERT_EQ(linMonitorGetStatus(other, &s), VCI_OK);
  EXPECT_FALSE(s.fActivated);
  EXPECT_FALSE(s.fRxOverrun);
  EXPECT_EQ(s.bRxFifoLoad, 0);
  EXPECT_EQ(s.sLineStatus.dwStatus, LIN_STATUS_ININIT);
  ASSERT_EQ(linMonitorActivate(other, TRUE), VCI_OK);
  ASSERT_EQ(linMonitorGetStatus(other, &s), VCI_OK);
  EXPECT_TRUE(s.fActivated);
  linMonitorClose(other);
  vciDeviceClose(dev);
}

TEST(VciCLin, ASlaveAnswersAHeaderFromItsResponseTable) {  // 138, 142 (ido), 147
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta");
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

TEST(VciCLin, ResetEmptiesTheResponseTable) {  // 139
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  LinAdapter slave("beta");
  ASSERT_EQ(slave.write(false, lin_data(0x10, {0x11, 0x22})), VCI_OK);
  ASSERT_EQ(linControlReset(slave.control), VCI_OK);
  ASSERT_EQ(linControlInitialize(slave.control, LIN_OPMODE_SLAVE, kRate), VCI_OK);
  ASSERT_EQ(linControlStart(slave.control, TRUE), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x10, {}, true, true)), VCI_OK);
  step_to(20'000'000);
  EXPECT_EQ(master.texts(),
            (Texts{event_text(stamp(no_response_at(t0)), LIN_MSGTYPE_ERROR, LIN_ERROR_SLNORE, 0)}));
}

TEST(VciCLin, TheResponseTableChangesWhileOnline) {  // 140
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta");
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

TEST(VciCLin, WriteMessageRefusesWhatTheModeDoesNotAllow) {  // 141, 143
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta");
  EXPECT_EQ(slave.write(false, lin_type(LIN_MSGTYPE_SLEEP)), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(false, lin_data(64, {1})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(false, lin_data(1, {})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(false, lin_data(1, {1, 2, 3, 4, 5, 6, 7, 8, 9})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(true, lin_data(1, {1})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(true, lin_type(LIN_MSGTYPE_SLEEP)), VCI_E_INVALIDARG);
  EXPECT_EQ(master.write(true, lin_type(LIN_MSGTYPE_INFO)), VCI_E_INVALIDARG);
  EXPECT_EQ(linControlWriteMessage(master.control, TRUE, nullptr), VCI_E_INVALIDARG);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(slave.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_OK);
  step_to(1'000'000);
  // The master hears the 250 us pulse at its end.
  EXPECT_EQ(master.texts(), (Texts{event_text(stamp(t0 + 250'000), LIN_MSGTYPE_WAKEUP, 0)}));
  ASSERT_EQ(linControlStart(slave.control, FALSE), VCI_OK);
  EXPECT_EQ(slave.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_E_INVALID_STATE);
}

TEST(VciCLin, AMasterPublishesSleepsAndWakes) {  // 142 (whole frame), 144
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta");
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x22, {0xAA, 0xBB, 0xCC})), VCI_OK);
  const int64_t t1 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_type(LIN_MSGTYPE_SLEEP)), VCI_OK);
  const int64_t t2 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_OK);
  step_to(1'000'000);
  const std::vector<uint8_t> sleep{0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  const uint32_t e0 = stamp(frame_end(t0, 3));
  const uint32_t e1 = stamp(frame_end(t1, 8));
  EXPECT_EQ(slave.texts(), (Texts{frame_text(e0, 0x22, {0xAA, 0xBB, 0xCC}, true, false),
                                  frame_text(e1, 0x3C, sleep, false, false),
                                  event_text(stamp(t2 + 250'000), LIN_MSGTYPE_WAKEUP, 0)}));
  EXPECT_EQ(master.texts(), (Texts{frame_text(e0, 0x22, {0xAA, 0xBB, 0xCC}, true, true),
                                   frame_text(e1, 0x3C, sleep, false, true)}));
}

TEST(VciCLin, WriteMessageNeverWaits) {  // 145
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x01, {1})), VCI_OK);
  EXPECT_EQ(master.write(true, lin_data(0x02, {2})), VCI_E_TXQUEUE_FULL);
  EXPECT_EQ(master.write(true, lin_type(LIN_MSGTYPE_SLEEP)), VCI_E_TXQUEUE_FULL);
  step_to(2'000'000);  // the frame (54 bits, 2.81 ms) is still on the wire
  EXPECT_EQ(master.write(true, lin_data(0x02, {2})), VCI_E_TXQUEUE_FULL);
  step_to(1'000'000);
  EXPECT_EQ(master.write(true, lin_data(0x02, {2})), VCI_OK);
}

TEST(VciCLin, CollidingChecksumsAreAChecksumError) {  // 146
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  LinAdapter beta("beta");
  LinAdapter gamma("gamma");
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
TEST(VciCLin, AParityErrorFromAScenarioIsAnErrorMessageOfTheListeners) {  // 146
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  LinAdapter beta("beta", LIN_OPMODE_SLAVE | LIN_OPMODE_ERRORS);
  LinAdapter gamma("gamma", LIN_OPMODE_SLAVE | LIN_OPMODE_ERRORS);
  ASSERT_EQ(beta.write(false, lin_data(0x20, {0x55})), VCI_OK);
  testing::load_faults(d.daemon,
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

TEST(VciCLin, AFullMonitorMarksTheLastMessageAndTheOverrun) {  // 148
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta", LIN_OPMODE_SLAVE, true,
                   1);  // one page: 240 messages and the ring header
  slave.drain();
  LINMONITORSTATUS s{};
  int frames = 0;
  for (; frames < 300; ++frames) {
    ASSERT_EQ(master.write(true, lin_data(0x01, {static_cast<uint8_t>(frames)})), VCI_OK);
    step_to(3'000'000);
    ASSERT_EQ(linMonitorGetStatus(slave.monitor, &s), VCI_OK);
    if (s.fRxOverrun) {
      break;
    }
  }
  EXPECT_EQ(frames, 240);  // the 241st found no room
  EXPECT_EQ(s.bRxFifoLoad, 100);
  const std::vector<LINMSG> got = slave.drain();
  ASSERT_EQ(got.size(), 240U);
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].abData[0], static_cast<uint8_t>(i));
    EXPECT_EQ(got[i].uMsgInfo.Bits.ovr, i + 1 == got.size() ? 1U : 0U) << i;
  }
  ASSERT_EQ(linMonitorGetStatus(slave.monitor, &s), VCI_OK);
  EXPECT_TRUE(s.fRxOverrun);  // until the monitor is initialized again
  EXPECT_EQ(s.bRxFifoLoad, 0);
}

TEST(VciCLin, TheMicrosecondCounterWrapsWithATimeOverrunMessage) {  // 149
  VciDaemon d(kLinAdapters);
  LinAdapter slave("beta");
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

}  // namespace
}  // namespace canemu::testing
