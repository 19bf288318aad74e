// The VCI's LIN control unit and monitors on the firmware model (VCI C++ guide 5.3, 8.4):
// checklist items 133-149 as far as the adapter's firmware decides them.
#include "canemu/firmware_model/adapters/ixxat/lin_line.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace canemu::model::ixxat {
namespace {

struct Fifo : LinMonitorPort {
  explicit Fifo(std::size_t places) : capacity(places) {}
  std::size_t room() const override { return capacity - messages.size(); }
  void put(const LINMSG& msg) override { messages.push_back(msg); }
  std::size_t capacity;
  std::vector<LINMSG> messages;
};

struct Faults : lin::LinFaultSource {
  lin::FrameFaults faults_for(SimTime, uint8_t, lin::LinNodeId) override { return next; }
  lin::FrameFaults next;
};

LININITLINE init(uint8_t mode, uint16_t rate) {
  return LININITLINE{mode, 0, rate};
}

LINMSG data(uint8_t id, std::vector<uint8_t> bytes, bool ecs = true, bool ido = false) {
  LINMSG m{};
  m.uMsgInfo.Bytes.bPid = id;
  m.uMsgInfo.Bytes.bType = LIN_MSGTYPE_DATA;
  m.uMsgInfo.Bytes.bDlen = static_cast<uint8_t>(bytes.size());
  m.uMsgInfo.Bits.ecs = ecs ? 1 : 0;
  m.uMsgInfo.Bits.ido = ido ? 1 : 0;
  std::copy(bytes.begin(), bytes.end(), m.abData);
  return m;
}

LINMSG of_type(uint8_t type) {
  LINMSG m{};
  m.uMsgInfo.Bytes.bType = type;
  return m;
}

// 19200 bit/s: the adapter's microsecond counter `bits` bits after `start` (it shows the
// whole microseconds passed).
uint32_t us_at(int64_t start_ns, uint64_t bits) {
  return static_cast<uint32_t>((start_ns + lin::bits_duration(bits, 19200).ns()) / 1000);
}

class LinLineTest : public ::testing::Test {
 protected:
  LinLineTest() {
    bus.set_fault_source(&faults);
    for (auto* side : {&master, &slave}) {
      auto id = side->open_monitor(false);
      EXPECT_TRUE(id.has_value());
      monitor_ids.push_back(*id);
    }
    EXPECT_EQ(master.init_monitor(monitor_ids[0], &master_fifo), VCI_OK);
    EXPECT_EQ(slave.init_monitor(monitor_ids[1], &slave_fifo), VCI_OK);
    EXPECT_EQ(master.activate(monitor_ids[0]), VCI_OK);
    EXPECT_EQ(slave.activate(monitor_ids[1]), VCI_OK);
  }
  // InitLine on both (it empties the response tables), then `fill` (the tables), then
  // StartLine; the monitors are emptied.
  template <class Fill = void (*)()>
  void bring_up(
      uint8_t extra = 0, Fill fill = [] {}) {
    ASSERT_EQ(master.init_line(init(LIN_OPMODE_MASTER | extra, 19200)), VCI_OK);
    ASSERT_EQ(slave.init_line(init(LIN_OPMODE_SLAVE | extra, 19200)), VCI_OK);
    fill();
    ASSERT_EQ(master.start_line(), VCI_OK);
    ASSERT_EQ(slave.start_line(), VCI_OK);
    master_fifo.messages.clear();
    slave_fifo.messages.clear();
  }
  void run_to(int64_t ns) { scheduler.run_until(SimTime::from_ns(ns)); }

  SimScheduler scheduler;
  lin::LinBus bus{scheduler, lin::Layout{}};
  Faults faults;
  LinLine master{scheduler, bus, Clocks{}, SimTime{}};
  LinLine slave{scheduler, bus, Clocks{}, SimTime{}};
  Fifo master_fifo{64};
  Fifo slave_fifo{64};
  std::vector<MonitorId> monitor_ids;
};

TEST_F(LinLineTest, InitLineChecksTheBitRateAndTheStatusEchoesIt) {  // 134
  EXPECT_EQ(master.init_line(init(LIN_OPMODE_MASTER, 999)), VCI_E_INVALIDARG);
  EXPECT_EQ(master.init_line(init(LIN_OPMODE_MASTER, 20001)), VCI_E_INVALIDARG);
  EXPECT_EQ(master.init_line(init(LIN_OPMODE_MASTER, LIN_BITRATE_AUTO)), VCI_E_INVALIDARG);
  EXPECT_EQ(master.init_line(init(0x04, 19200)), VCI_E_INVALIDARG);
  EXPECT_EQ(master.init_line(init(LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS, 19200)), VCI_OK);
  const LINLINESTATUS s = master.line_status();
  EXPECT_EQ(s.bOpMode, LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  EXPECT_EQ(s.wBitrate, 19200);
  EXPECT_EQ(s.dwStatus, uint32_t{LIN_STATUS_ININIT});
  EXPECT_EQ(slave.init_line(init(LIN_OPMODE_SLAVE, LIN_BITRATE_AUTO)), VCI_OK);
  const LINCAPABILITIES c = master.capabilities();
  EXPECT_EQ(c.dwFeatures, 0x3Fu);
  EXPECT_EQ(c.dwClockFreq, 1'000'000u);
  EXPECT_EQ(c.dwTscDivisor, 1u);
}

TEST_F(LinLineTest, StartNeedsInitAndEachStateChangeIsAnInfoMessage) {  // 135
  EXPECT_EQ(master.start_line(), VCI_E_INVALID_STATE);
  run_to(5'000'000);
  ASSERT_EQ(master.init_line(init(LIN_OPMODE_MASTER, 19200)), VCI_OK);
  ASSERT_EQ(master.start_line(), VCI_OK);
  EXPECT_EQ(master.line_status().dwStatus, 0u);
  ASSERT_EQ(master.stop_line(), VCI_OK);
  ASSERT_EQ(master.reset_line(), VCI_OK);
  ASSERT_EQ(master_fifo.messages.size(), 3u);
  const uint8_t expected[3] = {LIN_INFO_START, LIN_INFO_STOP, LIN_INFO_RESET};
  const uint32_t times[3] = {5000, 0, 0};
  for (int k = 0; k < 3; ++k) {
    const LINMSG& m = master_fifo.messages[k];
    EXPECT_EQ(m.uMsgInfo.Bytes.bType, LIN_MSGTYPE_INFO);
    EXPECT_EQ(m.uMsgInfo.Bytes.bPid, 0xFF);
    EXPECT_EQ(m.abData[0], expected[k]);
    EXPECT_EQ(m.dwTime, times[k]);
  }
}

TEST_F(LinLineTest, AnExclusiveMonitorIsAlone) {  // 137
  LinLine other{scheduler, bus, Clocks{}, SimTime{}};
  auto first = other.open_monitor(true);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(other.open_monitor(false).error(), VCI_E_ACCESSDENIED);
  other.close_monitor(*first);
  ASSERT_TRUE(other.open_monitor(false).has_value());
  EXPECT_EQ(other.open_monitor(true).error(), VCI_E_ACCESSDENIED);
}

TEST_F(LinLineTest, TheSlaveAnswersFromItsTableWithSor) {  // 138, 147
  bring_up(0, [this] {  // the table before the start, as the guide asks
    ASSERT_EQ(slave.write_message(false, data(0x10, {0x11, 0x22})), VCI_OK);
  });
  ASSERT_EQ(master.write_message(true, data(0x10, {}, true, true)), VCI_OK);  // header only
  run_to(lin::bits_duration(64, 19200).ns());
  ASSERT_EQ(master_fifo.messages.size(), 1u);
  ASSERT_EQ(slave_fifo.messages.size(), 1u);
  for (const LINMSG* m : {&master_fifo.messages[0], &slave_fifo.messages[0]}) {
    EXPECT_EQ(m->uMsgInfo.Bytes.bType, LIN_MSGTYPE_DATA);
    EXPECT_EQ(m->uMsgInfo.Bytes.bPid, 0x10);
    EXPECT_EQ(m->uMsgInfo.Bytes.bDlen, 2);
    EXPECT_EQ(m->uMsgInfo.Bits.ecs, 1u);
    EXPECT_EQ(m->abData[0], 0x11);
    EXPECT_EQ(m->abData[1], 0x22);
    EXPECT_EQ(m->dwTime, us_at(0, 64));  // 3333.33 us: 3333
  }
  EXPECT_EQ(master_fifo.messages[0].uMsgInfo.Bits.sor, 0u);
  EXPECT_EQ(slave_fifo.messages[0].uMsgInfo.Bits.sor, 1u);
  // Classic checksum: reported as such.
  ASSERT_EQ(slave.write_message(false, data(0x11, {0x01}, false)), VCI_OK);  // 140: online
  ASSERT_EQ(master.write_message(true, data(0x11, {}, true, true)), VCI_OK);
  run_to(lin::bits_duration(64 + 54, 19200).ns());
  ASSERT_EQ(master_fifo.messages.size(), 2u);
  EXPECT_EQ(master_fifo.messages[1].uMsgInfo.Bits.ecs, 0u);
}

TEST_F(LinLineTest, ResetEmptiesTheTableAndTheMasterReportsNoResponse) {  // 139
  ASSERT_EQ(slave.write_message(false, data(0x10, {0x11})), VCI_OK);
  bring_up(LIN_OPMODE_ERRORS);  // InitLine resets first: the table is empty again
  ASSERT_EQ(master.write_message(true, data(0x10, {}, true, true)), VCI_OK);
  run_to(lin::bits_duration(160, 19200).ns());
  ASSERT_EQ(master_fifo.messages.size(), 1u);
  const LINMSG& m = master_fifo.messages[0];
  EXPECT_EQ(m.uMsgInfo.Bytes.bType, LIN_MSGTYPE_ERROR);
  EXPECT_EQ(m.uMsgInfo.Bytes.bPid, 0xFF);
  EXPECT_EQ(m.abData[0], LIN_ERROR_SLNORE);
  EXPECT_EQ(m.abData[1], 0);  // the status byte: online
  EXPECT_EQ(m.dwTime, us_at(0, 160));
}

TEST_F(LinLineTest, ResponseTableEntriesMustBeDataWithAnIdentifier) {  // 141
  EXPECT_EQ(slave.write_message(false, data(64, {1})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write_message(false, data(0x80, {1})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write_message(false, data(1, {})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write_message(false, of_type(LIN_MSGTYPE_SLEEP)), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write_message(false, data(63, {1, 2, 3, 4, 5, 6, 7, 8})), VCI_OK);
}

TEST_F(LinLineTest, TheMasterSendsAHeaderAloneOrAWholeFrame) {  // 142
  bring_up(LIN_OPMODE_ERRORS);
  ASSERT_EQ(master.write_message(true, data(0x22, {0xA1, 0xB2, 0xC3})), VCI_OK);
  run_to(lin::bits_duration(74, 19200).ns());
  ASSERT_EQ(slave_fifo.messages.size(), 1u);
  EXPECT_EQ(slave_fifo.messages[0].uMsgInfo.Bytes.bDlen, 3);
  EXPECT_EQ(slave_fifo.messages[0].uMsgInfo.Bits.sor, 0u);
  EXPECT_EQ(master_fifo.messages.at(0).uMsgInfo.Bits.sor, 1u);  // it published the response
  EXPECT_EQ(master.write_message(true, data(0x22, {})), VCI_E_INVALIDARG);  // no data, no ido
}

TEST_F(LinLineTest, ASlaveMayOnlyWakeTheBus) {  // 143, 144
  bring_up();
  EXPECT_EQ(slave.write_message(true, data(0x10, {1})), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write_message(true, of_type(LIN_MSGTYPE_SLEEP)), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write_message(true, of_type(LIN_MSGTYPE_INFO)), VCI_E_INVALIDARG);
  EXPECT_EQ(slave.write_message(true, of_type(LIN_MSGTYPE_WAKEUP)), VCI_OK);
  run_to(250'000);
  ASSERT_EQ(master_fifo.messages.size(), 1u);
  EXPECT_EQ(master_fifo.messages[0].uMsgInfo.Bytes.bType, LIN_MSGTYPE_WAKEUP);
  EXPECT_EQ(master_fifo.messages[0].dwTime, 250u);
  EXPECT_TRUE(slave_fifo.messages.empty());
  EXPECT_EQ(master.write_message(true, of_type(LIN_MSGTYPE_SLEEP)), VCI_OK);
  run_to(250'000 + lin::bits_duration(124, 19200).ns());
  ASSERT_EQ(slave_fifo.messages.size(), 1u);
  const LINMSG& sleep = slave_fifo.messages[0];
  EXPECT_EQ(sleep.uMsgInfo.Bytes.bPid, 0x3C);
  EXPECT_EQ(sleep.uMsgInfo.Bytes.bDlen, 8);
  EXPECT_EQ(sleep.abData[0], 0x00);
  EXPECT_EQ(sleep.abData[1], 0xFF);
  EXPECT_EQ(sleep.uMsgInfo.Bits.ecs, 0u);
}

TEST_F(LinLineTest, ASecondSendBeforeTheFirstIsDoneIsRefused) {  // 145
  EXPECT_EQ(master.write_message(true, of_type(LIN_MSGTYPE_WAKEUP)), VCI_E_INVALID_STATE);
  bring_up();
  ASSERT_EQ(master.write_message(true, data(0x01, {1})), VCI_OK);
  EXPECT_EQ(master.write_message(true, data(0x02, {1})), VCI_E_TXQUEUE_FULL);
  run_to(lin::bits_duration(54, 19200).ns());
  EXPECT_EQ(master.write_message(true, data(0x02, {1})), VCI_OK);
}

TEST_F(LinLineTest, ErrorsAreMessagesOnlyWithErrorsMode) {  // 146
  ASSERT_EQ(slave.write_message(false, data(0x10, {1})), VCI_OK);
  bring_up();
  ASSERT_EQ(slave.write_message(false, data(0x10, {1})), VCI_OK);
  faults.next.checksum_error = true;
  master.write_message(true, data(0x10, {}, true, true));
  run_to(lin::bits_duration(54, 19200).ns());
  EXPECT_TRUE(master_fifo.messages.empty());  // no ERRORS mode: nothing
  ASSERT_EQ(master.init_line(init(LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS, 19200)), VCI_OK);
  ASSERT_EQ(master.start_line(), VCI_OK);
  master_fifo.messages.clear();
  const int64_t t = lin::bits_duration(54, 19200).ns();
  master.write_message(true, data(0x10, {}, true, true));
  run_to(t + lin::bits_duration(54, 19200).ns());
  faults.next = {};
  faults.next.parity_error = true;
  ASSERT_EQ(slave.init_line(init(LIN_OPMODE_SLAVE | LIN_OPMODE_ERRORS, 19200)), VCI_OK);
  ASSERT_EQ(slave.start_line(), VCI_OK);
  slave_fifo.messages.clear();
  master.write_message(true, data(0x10, {}, true, true));
  run_to(t + lin::bits_duration(54 + 34, 19200).ns());
  ASSERT_EQ(master_fifo.messages.size(), 1u);
  EXPECT_EQ(master_fifo.messages[0].uMsgInfo.Bytes.bType, LIN_MSGTYPE_ERROR);
  EXPECT_EQ(master_fifo.messages[0].abData[0], LIN_ERROR_CHKSUM);
  EXPECT_EQ(master_fifo.messages[0].dwTime, us_at(t, 54));
  ASSERT_EQ(slave_fifo.messages.size(), 1u);
  EXPECT_EQ(slave_fifo.messages[0].abData[0], LIN_ERROR_PARITY);
  EXPECT_EQ(slave_fifo.messages[0].uMsgInfo.Bytes.bPid, 0xFF);
}

TEST_F(LinLineTest, AFullMonitorMarksTheMessageThatFilledItAndCountsTheLost) {  // 148
  Fifo small{2};
  auto id = slave.open_monitor(false);
  ASSERT_TRUE(id.has_value());
  ASSERT_EQ(slave.init_monitor(*id, &small), VCI_OK);
  ASSERT_EQ(slave.activate(*id), VCI_OK);
  bring_up();  // START fills one place
  int64_t t = 0;
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(master.write_message(true, data(0x05, {static_cast<uint8_t>(k)})), VCI_OK);
    t += lin::bits_duration(54, 19200).ns();
    run_to(t);
  }
  ASSERT_EQ(small.messages.size(), 2u);
  EXPECT_EQ(small.messages[0].uMsgInfo.Bits.ovr, 0u);
  EXPECT_EQ(small.messages[1].uMsgInfo.Bits.ovr, 1u);
  EXPECT_EQ(small.messages[1].abData[0], 0);
  const auto state = slave.monitor_state(*id);
  ASSERT_TRUE(state.has_value());
  EXPECT_TRUE(state->rx_overrun);
  EXPECT_EQ(state->lost, 2u);
  EXPECT_EQ(state->received, 2u);
}

TEST_F(LinLineTest, TheTimeStampCounterOverflowsAfter2To32Microseconds) {  // 149
  bring_up();
  const int64_t wrap = (int64_t{1} << 32) * 1000;
  run_to(wrap - 1);
  EXPECT_TRUE(master_fifo.messages.empty() ||
              master_fifo.messages.back().uMsgInfo.Bytes.bType != LIN_MSGTYPE_TMOVR);
  run_to(wrap);
  ASSERT_FALSE(master_fifo.messages.empty());
  const LINMSG& m = master_fifo.messages.back();
  EXPECT_EQ(m.uMsgInfo.Bytes.bType, LIN_MSGTYPE_TMOVR);
  EXPECT_EQ(m.uMsgInfo.Bytes.bDlen, 1);
  EXPECT_EQ(m.dwTime, 0u);
}

}  // namespace
}  // namespace canemu::model::ixxat
