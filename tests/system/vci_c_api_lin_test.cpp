// The LIN functions of the VCI C API (libvcinpl) against canemud: checklist items 133-149 of
// the VCI digest, with exact time stamps in stepped time; what the C++ API shows alike is in
// vci_lin_behaviour.hpp, run here through this API.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vci_c_lin_support.hpp"
#include "vci_lin_behaviour.hpp"

namespace canemu::testing {
namespace {

TEST(VciCLin, TheLinControllerIsNumberedAfterTheCanControllersAndOpensOnce) {  // 133
  VciDaemon d(kLinAdapters);
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  const VCIDEVICECAPS caps = device_caps(dev);
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
  EXPECT_EQ(texts_of(a.drain()), start_stop_reset(t));
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

INSTANTIATE_TYPED_TEST_SUITE_P(VciCLin, VciLinBehaviour, LinAdapter);

}  // namespace
}  // namespace canemu::testing
