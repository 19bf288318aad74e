// The LIN interfaces of the VCI C++ API (libvciapi: ILinSocket, ILinControl, ILinMonitor)
// against canemud: checklist items 133-149 of the VCI digest, with exact time stamps in
// stepped time.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vci_cpp_test_support.hpp"
#include "vci_lin_test_support.hpp"

namespace canemu::testing {
namespace {

// The BAL of the adapter named `name`.
void bal_of(const std::string& name, Ref<IBalObject>& bal) {
  const INT64 id = vci_id_named(name);
  ASSERT_NE(id, 0) << "no adapter " << name;
  open_bal(id, bal);
}

// An adapter's LIN controller opened the way the guide describes: socket, monitor (FIFO
// `fifo`, active) and its reader, control unit initialized with `mode` at 19200 bit/s and
// started.
struct LinAdapter {
  Ref<IBalObject> bal;
  Ref<ILinSocket> socket;
  Ref<ILinMonitor> monitor;
  Ref<IFifoReader> reader;
  Ref<ILinControl> control;
  explicit LinAdapter(const std::string& name, UINT8 mode = LIN_OPMODE_SLAVE, bool start = true,
                      UINT16 fifo = 64) {
    bal_of(name, bal);
    EXPECT_EQ(bal->OpenSocket(kLinNo, IID_ILinSocket, socket.pv()), VCI_OK);
    EXPECT_EQ(socket->CreateMonitor(FALSE, monitor.out()), VCI_OK);
    EXPECT_EQ(monitor->Initialize(fifo), VCI_OK);
    EXPECT_EQ(monitor->GetReader(reader.out()), VCI_OK);
    EXPECT_EQ(monitor->Activate(), VCI_OK);
    EXPECT_EQ(bal->OpenSocket(kLinNo, IID_ILinControl, control.pv()), VCI_OK);
    LININITLINE init{mode, 0, static_cast<UINT16>(kRate)};
    EXPECT_EQ(control->InitLine(&init), VCI_OK);
    if (start) {
      EXPECT_EQ(control->StartLine(), VCI_OK);
    }
  }
  std::vector<LINMSG> drain() const {
    return drain_with([this](LINMSG& m) { return reader->GetDataEntry(&m) == VCI_OK; });
  }
  std::vector<std::string> texts() const { return texts_but_start(drain()); }
  HRESULT write(bool send, LINMSG m) const { return control->WriteMessage(send, &m); }
};

using Texts = std::vector<std::string>;

TEST(VciCppLin, SocketsAndTheControlUnitOpenOnTheLinBusNumberOnly) {  // 133
  VciDaemon d(kLinAdapters);
  Ref<IBalObject> bal;
  bal_of("alpha", bal);
  BALFEATURES f{};
  ASSERT_EQ(bal->GetFeatures(&f), VCI_OK);
  EXPECT_EQ(f.BusSocketCount, 2);
  EXPECT_EQ(f.BusSocketType[1], VCI_LIN_CTRL(LIN_CTRL_UNKNOWN));
  Ref<ILinSocket> socket;
  ASSERT_EQ(bal->OpenSocket(kLinNo, IID_ILinSocket, socket.pv()), VCI_OK);
  BALSOCKETINFO info{};
  ASSERT_EQ(socket->GetSocketInfo(&info), VCI_OK);
  EXPECT_EQ(info.BusNo, kLinNo);
  EXPECT_EQ(info.Type, VCI_LIN_CTRL(LIN_CTRL_UNKNOWN));
  LINCAPABILITIES caps{};
  ASSERT_EQ(socket->GetCapabilities(&caps), VCI_OK);
  EXPECT_EQ(caps.dwFeatures, 0x3FU);
  EXPECT_EQ(caps.dwClockFreq, 1'000'000U);
  EXPECT_EQ(caps.dwTscDivisor, 1U);
  Ref<ICanSocket> can;
  EXPECT_EQ(bal->OpenSocket(kLinNo, IID_ICanSocket, can.pv()), VCI_E_NOINTERFACE);
  Ref<ILinSocket> wrong;
  EXPECT_EQ(bal->OpenSocket(0, IID_ILinSocket, wrong.pv()), VCI_E_NOINTERFACE);
  EXPECT_EQ(wrong.p, nullptr);
  Ref<ILinControl> first;
  Ref<ILinControl> second;
  ASSERT_EQ(bal->OpenSocket(kLinNo, IID_ILinControl, first.pv()), VCI_OK);
  EXPECT_EQ(bal->OpenSocket(kLinNo, IID_ILinControl, second.pv()), VCI_E_ACCESSDENIED);
  EXPECT_EQ(second.p, nullptr);
}

TEST(VciCppLin, InitLineTakesOneToTwentyKbitPerSecondAndStartsAfterIt) {  // 134, 135
  VciDaemon d(kLinAdapters);
  LinAdapter a("alpha", LIN_OPMODE_MASTER, false);
  LININITLINE bad{LIN_OPMODE_MASTER, 0, 999};
  EXPECT_EQ(a.control->InitLine(&bad), VCI_E_INVALIDARG);
  bad.wBitrate = 20001;
  EXPECT_EQ(a.control->InitLine(&bad), VCI_E_INVALIDARG);
  bad.wBitrate = kRate;
  bad.bReserved = 1;
  EXPECT_EQ(a.control->InitLine(&bad), VCI_E_INVALIDARG);
  ASSERT_EQ(a.control->ResetLine(), VCI_OK);
  EXPECT_EQ(a.control->StartLine(), VCI_E_INVALID_STATE);
  a.drain();
  const int64_t t = step_to(7'654'321);
  LININITLINE init{LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS, 0, 19200};
  ASSERT_EQ(a.control->InitLine(&init), VCI_OK);
  LINLINESTATUS s{};
  ASSERT_EQ(a.socket->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.bOpMode, LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  EXPECT_EQ(s.wBitrate, 19200);
  EXPECT_EQ(s.dwStatus, LIN_STATUS_ININIT);
  ASSERT_EQ(a.control->StartLine(), VCI_OK);
  ASSERT_EQ(a.control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus, 0U);
  ASSERT_EQ(a.control->StopLine(), VCI_OK);
  ASSERT_EQ(a.control->ResetLine(), VCI_OK);
  std::vector<std::string> got;
  for (const LINMSG& m : a.drain()) {
    got.push_back(text_of(m));
  }
  EXPECT_EQ(got, (Texts{event_text(stamp(t), LIN_MSGTYPE_INFO, LIN_INFO_START),
                        event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_STOP),
                        event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_RESET)}));
}

TEST(VciCppLin, MonitorsHoldLinmsgsAndAnExclusiveOneIsAlone) {  // 136, 137
  VciDaemon d(kLinAdapters);
  Ref<IBalObject> bal;
  bal_of("alpha", bal);
  Ref<ILinSocket> socket;
  ASSERT_EQ(bal->OpenSocket(kLinNo, IID_ILinSocket, socket.pv()), VCI_OK);
  Ref<ILinMonitor> shared;
  ASSERT_EQ(socket->CreateMonitor(FALSE, shared.out()), VCI_OK);
  EXPECT_EQ(shared->Initialize(0), VCI_E_INVALIDARG);
  Ref<IFifoReader> none;
  EXPECT_EQ(shared->GetReader(none.out()), VCI_E_NOT_INITIALIZED);
  ASSERT_EQ(shared->Initialize(300), VCI_OK);
  Ref<IFifoReader> reader;
  ASSERT_EQ(shared->GetReader(reader.out()), VCI_OK);
  UINT16 size = 0;
  ASSERT_EQ(reader->GetEntrySize(&size), VCI_OK);
  EXPECT_EQ(size, sizeof(LINMSG));
  EXPECT_EQ(size, 16);
  UINT16 capacity = 0;
  ASSERT_EQ(reader->GetCapacity(&capacity), VCI_OK);
  EXPECT_EQ(capacity, 240 + 256);  // at least 300: two pages
  Ref<ILinMonitor> exclusive;
  EXPECT_EQ(socket->CreateMonitor(TRUE, exclusive.out()), VCI_E_ACCESSDENIED);
  EXPECT_EQ(exclusive.p, nullptr);
  Ref<ILinMonitor> another;
  ASSERT_EQ(socket->CreateMonitor(FALSE, another.out()), VCI_OK);
  another->Release();
  another.p = nullptr;
  reader->Release();
  reader.p = nullptr;
  shared->Release();
  shared.p = nullptr;
  ASSERT_EQ(socket->CreateMonitor(TRUE, exclusive.out()), VCI_OK);
  EXPECT_EQ(socket->CreateMonitor(FALSE, another.out()), VCI_E_ACCESSDENIED);
  LINMONITORSTATUS s{};
  ASSERT_EQ(exclusive->GetStatus(&s), VCI_OK);
  EXPECT_FALSE(s.fActivated);
  ASSERT_EQ(exclusive->Initialize(1), VCI_OK);
  ASSERT_EQ(exclusive->Activate(), VCI_OK);
  ASSERT_EQ(exclusive->GetStatus(&s), VCI_OK);
  EXPECT_TRUE(s.fActivated);
  ASSERT_EQ(exclusive->Deactivate(), VCI_OK);
  ASSERT_EQ(exclusive->GetStatus(&s), VCI_OK);
  EXPECT_FALSE(s.fActivated);
}

TEST(VciCppLin, ASlaveAnswersFromItsTableUntilResetLineEmptiesIt) {  // 138, 139, 140, 142, 147
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  LinAdapter slave("beta");
  ASSERT_EQ(slave.write(false, lin_data(0x10, {0x11, 0x22}, true)), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x10, {}, true, true)), VCI_OK);
  const int64_t t1 = step_to(10'000'000);
  ASSERT_EQ(slave.write(false, lin_data(0x10, {0x33}, false)), VCI_OK);  // online
  ASSERT_EQ(master.write(true, lin_data(0x10, {}, true, true)), VCI_OK);
  step_to(10'000'000);
  ASSERT_EQ(slave.control->ResetLine(), VCI_OK);
  LININITLINE init{LIN_OPMODE_SLAVE, 0, static_cast<UINT16>(kRate)};
  ASSERT_EQ(slave.control->InitLine(&init), VCI_OK);
  ASSERT_EQ(slave.control->StartLine(), VCI_OK);
  slave.drain();
  const int64_t t2 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x10, {}, true, true)), VCI_OK);
  step_to(20'000'000);
  const uint32_t e0 = stamp(frame_end(t0, 2));
  const uint32_t e1 = stamp(frame_end(t1, 1));
  EXPECT_EQ(master.texts(),
            (Texts{frame_text(e0, 0x10, {0x11, 0x22}, true, false),
                   frame_text(e1, 0x10, {0x33}, false, false),
                   event_text(stamp(no_response_at(t2)), LIN_MSGTYPE_ERROR, LIN_ERROR_SLNORE, 0)}));
}

TEST(VciCppLin, WriteMessageFollowsTheModeAndNeverWaits) {  // 141, 142, 143, 144, 145
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta");
  EXPECT_EQ(slave.write(false, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(false, lin_data(0x40, {1})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(true, lin_data(0x01, {1})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write(true, lin_type(LIN_MSGTYPE_SLEEP)), VCI_E_INVALIDARG);
  EXPECT_EQ(master.control->WriteMessage(TRUE, nullptr), VCI_E_INVALIDARG);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x3B, {1, 2, 3, 4, 5, 6, 7, 8})), VCI_OK);
  EXPECT_EQ(master.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_E_TXQUEUE_FULL);
  const int64_t t1 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_type(LIN_MSGTYPE_SLEEP)), VCI_OK);
  const int64_t t2 = step_to(10'000'000);
  ASSERT_EQ(slave.write(true, lin_type(LIN_MSGTYPE_WAKEUP)), VCI_OK);
  step_to(1'000'000);
  const std::vector<uint8_t> sleep{0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  EXPECT_EQ(master.texts(),
            (Texts{frame_text(stamp(frame_end(t0, 8)), 0x3B, {1, 2, 3, 4, 5, 6, 7, 8}, true, true),
                   frame_text(stamp(frame_end(t1, 8)), 0x3C, sleep, false, true),
                   event_text(stamp(t2 + 250'000), LIN_MSGTYPE_WAKEUP, 0)}));
  EXPECT_EQ(slave.texts(),
            (Texts{frame_text(stamp(frame_end(t0, 8)), 0x3B, {1, 2, 3, 4, 5, 6, 7, 8}, true, false),
                   frame_text(stamp(frame_end(t1, 8)), 0x3C, sleep, false, false)}));
}

TEST(VciCppLin, CollidingChecksumsAreAChecksumErrorMessage) {  // 146
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  LinAdapter beta("beta");
  LinAdapter gamma("gamma");
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
TEST(VciCppLin, AParityErrorFromAScenarioIsAnErrorMessageOfTheListeners) {  // 146
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

TEST(VciCppLin, AFullMonitorMarksItsLastMessage) {  // 148
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta", LIN_OPMODE_SLAVE, true, 1);
  UINT16 capacity = 0;
  ASSERT_EQ(slave.reader->GetCapacity(&capacity), VCI_OK);
  slave.drain();
  for (int i = 0; i <= capacity; ++i) {  // one more than fits
    ASSERT_EQ(master.write(true, lin_data(0x02, {static_cast<uint8_t>(i)})), VCI_OK);
    step_to(3'000'000);
  }
  LINMONITORSTATUS s{};
  ASSERT_EQ(slave.monitor->GetStatus(&s), VCI_OK);
  EXPECT_TRUE(s.fRxOverrun);
  EXPECT_EQ(s.bRxFifoLoad, 100);
  const std::vector<LINMSG> got = slave.drain();
  ASSERT_EQ(got.size(), capacity);
  EXPECT_EQ(got.back().abData[0], static_cast<uint8_t>(capacity - 1));
  EXPECT_EQ(got.back().uMsgInfo.Bits.ovr, 1U);
  EXPECT_EQ(got[capacity - 2].uMsgInfo.Bits.ovr, 0U);
}

TEST(VciCppLin, TimeStampsWrapAfterTwoToThe32Microseconds) {  // 149
  VciDaemon d(kLinAdapters);
  LinAdapter master("alpha", LIN_OPMODE_MASTER);
  LinAdapter slave("beta");
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

}  // namespace
}  // namespace canemu::testing
