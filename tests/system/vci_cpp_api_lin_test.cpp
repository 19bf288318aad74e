// The LIN interfaces of the VCI C++ API (libvciapi: ILinSocket, ILinControl, ILinMonitor)
// against canemud: checklist items 133-149 of the VCI digest, with exact time stamps in
// stepped time.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vci_cpp_test_support.hpp"
#include "vci_lin_behaviour.hpp"
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
  HRESULT write_null(bool send) const { return control->WriteMessage(send, nullptr); }
  HRESULT stop() const { return control->StopLine(); }
};

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
  EXPECT_EQ(texts_of(a.drain()), start_stop_reset(t));
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

INSTANTIATE_TYPED_TEST_SUITE_P(VciCppLin, VciLinBehaviour, LinAdapter);

}  // namespace
}  // namespace canemu::testing
