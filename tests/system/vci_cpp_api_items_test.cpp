// Checklist items of the VCI digest (§7) through the VCI C++ API (libvciapi: vcisdk.h) against
// a running canemud in stepped time, one test per item, with exact time stamps (device ticks of
// 1 us counted from canemud's start): the items that were tested in the firmware model only, and
// the items (or the parts of items) no other API test covered. docs/vci.md, "Checklist
// coverage", maps every item to its tests.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci_cpp_test_support.hpp"
#include "vci_lin_test_support.hpp"
#include "vcisdk.h"

namespace canemu {
namespace {

using testing::Adapter;
using testing::BalSocket;
using testing::Channel;
using testing::cyclic_data;
using testing::drain;
using testing::end_of;
using testing::Event;
using testing::ids_of;
using testing::kData;
using testing::kMode;
using testing::kNominal;
using testing::one_byte;
using testing::open_bal;
using testing::Ref;
using testing::StandAloneFifo;
using testing::step_ns;
using testing::the_one;
using testing::TwoAdapters;
using testing::V2Adapter;
using testing::V2Channel;
using testing::vci_id_named;
using testing::VciDaemon;

// alpha and beta of kTwoAdapters, and gamma beside them: a third node that acknowledges.
const std::string kThreeAdapters = std::string(testing::kTwoAdapters) +
                                   "\n[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\n"
                                   "controllers = [\"can0\"]\n";

// Two CAN FD adapters on an FD bus (500 kbit/s, 2 Mbit/s in the data phase).
const char* const kFdAdapters =
    "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n";

// Puts `m` into `writer` (the caller asserts the result).
HRESULT put(const Ref<IFifoWriter>& writer, CANMSG m) {
  return writer->PutDataEntry(&m);
}

// Simulated time now, in ns.
uint64_t now_ns() {
  UINT64 now = 0;
  UINT8 mode = 0;
  EXPECT_EQ(canemuGetTime(&now, &mode), VCI_OK);
  return now;
}

// A classic frame's bits on the wire (stuff bits included), SOF to the end of EOF.
uint32_t bits_of(uint32_t id, std::vector<uint8_t> data, bool ext = false) {
  return model::encode(*model::Frame::classic(id, data, ext)).length;
}

// The durations (ns) of FD frames on the FD bus of kFdAdapters.
int64_t fd_ns(uint32_t id, std::vector<uint8_t> data, bool brs) {
  const auto nominal = model::ixxat::decode_btp(
      {0, 500000, 14, 2, 1, 0}, model::ixxat::kFdNominalRange, model::ixxat::Phase::nominal);
  const auto fast = model::ixxat::decode_btp({0, 2000000, 8, 2, 1, 0}, model::ixxat::kFdDataRange,
                                             model::ixxat::Phase::data);
  return model::frame_duration(model::encode(*model::Frame::fd_frame(id, data, false, brs)),
                               *nominal, *fast)
      .ns();
}

CANMSG2 msg2(uint32_t id, std::vector<uint8_t> bytes) {
  CANMSG2 m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = *model::length_to_dlc(bytes.size(), bytes.size() > 8) & 0x0FU;
  if (!bytes.empty()) {
    std::memcpy(m.abData, bytes.data(), bytes.size());
  }
  return m;
}

// An entry of the cyclic list: a data frame of `data` every `cycle` ticks.
CANCYCLICTXMSG cyclic(UINT32 id, UINT16 cycle, std::vector<uint8_t> data = {0x11}) {
  CANCYCLICTXMSG m = cyclic_data(id, cycle, static_cast<UINT8>(data.size()));
  std::memcpy(m.abData, data.data(), data.size());
  return m;
}

// Adds `m` to `list` and starts it for `count` sends (0: without end); its index.
UINT32 add_and_start(ICanScheduler* list, CANCYCLICTXMSG m, UINT16 count = 0) {
  UINT32 index = 99;
  EXPECT_EQ(list->AddMessage(&m, &index), VCI_OK);
  EXPECT_EQ(list->StartMessage(index, count), VCI_OK);
  return index;
}

// ---------------------------------------------------------------- channels and control unit

// 56: a channel made while the line is online receives nothing until it is activated, and
// from then on (no INFO START: the line started before).
TEST(VciCppItems, Item56_NewChannelIsInactiveUntilActivate) {
  TwoAdapters bus;
  Channel fresh(bus.alpha.socket.p, 64, 16, false);
  CANCHANSTATUS s{};
  ASSERT_EQ(fresh.channel->GetStatus(&s), VCI_OK);
  EXPECT_FALSE(s.fActivated);
  EXPECT_EQ(s.sLineStatus.dwStatus, 0u);  // the line is online
  ASSERT_EQ(put(bus.beta.writer, one_byte(0x101, 1)), VCI_OK);
  step_ns(1'000'000);
  EXPECT_TRUE(drain(fresh.reader.p, false).empty());
  const auto at_alpha = drain(bus.alpha.reader.p, true);  // the older channel had it
  ASSERT_EQ(at_alpha.size(), 1u);
  EXPECT_EQ(at_alpha[0].dwTime, end_of(0x101, {1}));
  ASSERT_EQ(fresh.channel->Activate(), VCI_OK);
  ASSERT_EQ(fresh.channel->GetStatus(&s), VCI_OK);
  EXPECT_TRUE(s.fActivated);
  ASSERT_EQ(put(bus.beta.writer, one_byte(0x102, 2)), VCI_OK);  // at 1 ms
  step_ns(1'000'000);
  const auto got = the_one(drain(fresh.reader.p, false));
  EXPECT_EQ(got.uMsgInfo.Bytes.bType, CAN_MSGTYPE_DATA);
  EXPECT_EQ(got.dwMsgId, 0x102u);
  EXPECT_EQ(got.dwTime, 1000u + end_of(0x102, {2}));
}

// 57: an active channel gets nothing while its line is not initialized or offline; deactivated,
// it neither receives nor sends (its transmit FIFO waits and goes out once it is active again).
TEST(VciCppItems, Item57_ActiveChannelIsDeafWhileTheLineIsOfflineAndDeactivatedIsMute) {
  VciDaemon d(kThreeAdapters);
  Adapter beta("beta");
  Adapter gamma("gamma");  // acknowledges beta's frames while alpha is off the bus
  const BalSocket<ICanSocket> alpha("alpha", IID_ICanSocket);
  Channel ch(alpha.socket.p, 64, 16, true);
  Ref<ICanControl> control;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
  ASSERT_EQ(put(beta.writer, one_byte(0x101, 1)), VCI_OK);  // the line is not initialized
  step_ns(1'000'000);
  EXPECT_TRUE(drain(ch.reader.p, false).empty());
  CANINITLINE init{kMode, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);  // initialized, offline
  ASSERT_EQ(put(beta.writer, one_byte(0x102, 2)), VCI_OK);
  step_ns(1'000'000);
  EXPECT_TRUE(drain(ch.reader.p, false).empty());
  ASSERT_EQ(control->StartLine(), VCI_OK);  // at 2 ms
  ASSERT_EQ(put(beta.writer, one_byte(0x103, 3)), VCI_OK);
  step_ns(1'000'000);
  auto got = drain(ch.reader.p, false);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 2000u);
  EXPECT_EQ(got[1].dwMsgId, 0x103u);
  EXPECT_EQ(got[1].dwTime, 2000u + end_of(0x103, {3}));
  EXPECT_EQ(ids_of(drain(gamma.reader.p, true)), (std::vector<UINT32>{0x101, 0x102, 0x103}));
  // Deactivated at 3 ms: beta's frame does not come in, its own frame does not go out.
  ASSERT_EQ(ch.channel->Deactivate(), VCI_OK);
  ASSERT_EQ(put(beta.writer, one_byte(0x104, 4)), VCI_OK);
  ASSERT_EQ(put(ch.writer, one_byte(0x201, 5)), VCI_OK);
  step_ns(2'000'000);
  EXPECT_TRUE(drain(ch.reader.p, false).empty());
  got = drain(gamma.reader.p, true);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x104u);
  UINT16 fill = 0;
  ASSERT_EQ(ch.writer->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 1);
  // Active again at 5 ms: the waiting frame goes out at once.
  ASSERT_EQ(ch.channel->Activate(), VCI_OK);
  step_ns(1'000'000);
  got = drain(gamma.reader.p, true);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x201u);
  EXPECT_EQ(got[0].dwTime, 5000u + end_of(0x201, {5}));
}

// 66: StopLine and ResetLine leave what the channel's FIFOs hold: the receive FIFO keeps its
// messages, the transmit FIFO its frames, which go out in order once the line runs again.
TEST(VciCppItems, Item66_StopAndResetLineKeepTheChannelFifos) {
  TwoAdapters bus;
  ASSERT_EQ(put(bus.beta.writer, one_byte(0x123, 1)), VCI_OK);
  step_ns(1'000'000);
  ASSERT_EQ(bus.alpha.control->StopLine(), VCI_OK);  // at 1 ms
  for (UINT32 id : {0x201u, 0x202u}) {
    ASSERT_EQ(put(bus.alpha.writer, one_byte(id, static_cast<UINT8>(id))), VCI_OK);
  }
  step_ns(1'000'000);
  ASSERT_EQ(bus.alpha.control->ResetLine(), VCI_OK);  // at 2 ms
  step_ns(1'000'000);
  UINT16 fill = 0;
  ASSERT_EQ(bus.alpha.writer->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 2);
  const auto got = drain(bus.alpha.reader.p, false);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[1].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].dwTime, end_of(0x123, {1}));
  EXPECT_EQ(got[2].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(got[3].abData[0], CAN_INFO_RESET);
  EXPECT_TRUE(drain(bus.beta.reader.p, true).empty());
  CANINITLINE init{kMode, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(bus.alpha.control->InitLine(&init), VCI_OK);
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);  // at 3 ms
  step_ns(1'000'000);
  const auto sent = drain(bus.beta.reader.p, true);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].dwMsgId, 0x201u);
  EXPECT_EQ(sent[0].dwTime, 3000u + end_of(0x201, {0x01}));
  EXPECT_EQ(sent[1].dwMsgId, 0x202u);
  EXPECT_EQ(sent[1].dwTime, 3000u + end_of(0x201, {0x01}) + 6u + end_of(0x202, {0x02}));
}

// 67: InitLine while online resets the controller: ININIT, offline (no frames, no INFO
// message), the new mode in force until StartLine.
TEST(VciCppItems, Item67_InitLineWhileOnlineLeavesTheLineOffline) {
  VciDaemon d(kThreeAdapters);
  Adapter alpha("alpha");
  Adapter beta("beta");
  Adapter gamma("gamma");
  step_ns(1'000'000);
  CANINITLINE init{CAN_OPMODE_STANDARD, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(alpha.control->InitLine(&init), VCI_OK);
  CANLINESTATUS s = alpha.line_status();
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(s.bOpMode, CAN_OPMODE_STANDARD);
  ASSERT_EQ(put(beta.writer, one_byte(0x123, 1)), VCI_OK);
  step_ns(1'000'000);
  auto got = drain(alpha.reader.p, false);
  ASSERT_EQ(got.size(), 1u);  // the first START only
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 0u);
  EXPECT_EQ(drain(gamma.reader.p, true).size(), 1u);  // the frame was on the bus
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);      // at 2 ms
  ASSERT_EQ(put(beta.writer, one_byte(0x124, 2)), VCI_OK);
  step_ns(1'000'000);
  got = drain(alpha.reader.p, false);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(got[0].dwTime, 2000u);
  EXPECT_EQ(got[1].dwMsgId, 0x124u);
  EXPECT_EQ(got[1].dwTime, 2000u + end_of(0x124, {2}));
}

// 68: the control unit released while a channel is open: the line keeps running, receiving and
// sending; opened again, it shows the running line.
TEST(VciCppItems, Item68_ReleasingTheControlUnitLeavesTheLineRunning) {
  TwoAdapters bus;
  step_ns(1'000'000);
  EXPECT_EQ(bus.alpha.control->Release(), 0u);
  bus.alpha.control.p = nullptr;
  CANLINESTATUS s{};
  ASSERT_EQ(bus.alpha.socket->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus, 0u);  // online, no ININIT
  EXPECT_EQ(s.bOpMode, kMode);
  ASSERT_EQ(put(bus.beta.writer, one_byte(0x123, 1)), VCI_OK);  // at 1 ms
  step_ns(1'000'000);
  auto got = drain(bus.alpha.reader.p, false);
  ASSERT_EQ(got.size(), 2u);  // the START and the frame: no STOP or RESET
  EXPECT_EQ(got[1].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].dwTime, 1000u + end_of(0x123, {1}));
  ASSERT_EQ(put(bus.alpha.writer, one_byte(0x124, 2)), VCI_OK);  // at 2 ms
  step_ns(1'000'000);
  got = drain(bus.beta.reader.p, true);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x124u);
  EXPECT_EQ(got[0].dwTime, 2000u + end_of(0x124, {2}));
  Ref<ICanControl> again;
  ASSERT_EQ(bus.alpha.bal->OpenSocket(0, IID_ICanControl, again.pv()), VCI_OK);
  ASSERT_EQ(again->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus, 0u);
  step_ns(1'000'000);
  EXPECT_TRUE(drain(bus.alpha.reader.p, false).empty());
}

// 69: a channel that is initialized but not active gets no INFO message, neither at StartLine
// nor at StopLine or ResetLine, and none later when it is activated.
TEST(VciCppItems, Item69_InactiveChannelsGetNoInfoMessages) {
  VciDaemon d;
  const BalSocket<ICanSocket> alpha("alpha", IID_ICanSocket);
  Ref<ICanChannel> active;
  Ref<ICanChannel> inactive;
  Ref<IFifoReader> active_reader;
  Ref<IFifoReader> inactive_reader;
  for (auto* c : {&active, &inactive}) {
    ASSERT_EQ(alpha.socket->CreateChannel(FALSE, c->out()), VCI_OK);
    ASSERT_EQ((*c)->Initialize(64, 16), VCI_OK);
  }
  ASSERT_EQ(active->GetReader(active_reader.out()), VCI_OK);
  ASSERT_EQ(inactive->GetReader(inactive_reader.out()), VCI_OK);
  ASSERT_EQ(active->Activate(), VCI_OK);
  Ref<ICanControl> control;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
  CANINITLINE init{kMode, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  ASSERT_EQ(control->StartLine(), VCI_OK);
  step_ns(1'000'000);
  ASSERT_EQ(control->StopLine(), VCI_OK);
  ASSERT_EQ(control->ResetLine(), VCI_OK);
  step_ns(1'000'000);
  const auto infos = drain(active_reader.p, false);
  ASSERT_EQ(infos.size(), 3u);
  EXPECT_EQ(infos[0].abData[0], CAN_INFO_START);
  EXPECT_EQ(infos[1].abData[0], CAN_INFO_STOP);
  EXPECT_EQ(infos[2].abData[0], CAN_INFO_RESET);
  UINT16 fill = 1;
  ASSERT_EQ(inactive_reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  ASSERT_EQ(inactive->Activate(), VCI_OK);  // nothing is kept for it
  step_ns(1'000'000);
  ASSERT_EQ(inactive_reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  ASSERT_EQ(control->StartLine(), VCI_OK);  // at 3 ms: both active now
  step_ns(1'000'000);
  for (IFifoReader* r : {active_reader.p, inactive_reader.p}) {
    const auto got = drain(r, false);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].abData[0], CAN_INFO_START);
    EXPECT_EQ(got[0].dwTime, 3000u);
  }
}

// 71: two channels of one controller with frames waiting take turns on the bus; neither
// starves, and the one with more frames sends its rest at the end.
TEST(VciCppItems, Item71_TwoChannelsTransmitInTurn) {
  TwoAdapters bus;
  const Channel second(bus.alpha.socket.p, 64, 16, true);
  for (UINT32 id : {0x101u, 0x102u, 0x103u, 0x104u}) {
    ASSERT_EQ(put(bus.alpha.writer, one_byte(id, 1)), VCI_OK);
  }
  for (UINT32 id : {0x201u, 0x202u}) {
    ASSERT_EQ(put(second.writer, one_byte(id, 2)), VCI_OK);
  }
  step_ns(5'000'000);
  const auto got = drain(bus.beta.reader.p, true);
  ASSERT_EQ(ids_of(got), (std::vector<UINT32>{0x101, 0x201, 0x102, 0x202, 0x103, 0x104}));
  UINT32 end = 0;  // back to back: each starts 3 bits (6 us) after the previous one ended
  for (std::size_t k = 0; k < got.size(); ++k) {
    end += (k == 0 ? 0u : 6u) + 2u * bits_of(got[k].dwMsgId, {got[k].abData[0]});
    EXPECT_EQ(got[k].dwTime, end) << k;
  }
}

// 72: transmit messages that are not data (INFO, ERROR, STATUS, TIMEOVR) are taken from the FIFO
// and dropped: they take no bus time and never appear on the bus.
TEST(VciCppItems, Item72_NonDataTransmitMessagesAreDropped) {
  TwoAdapters bus;
  for (UINT8 type : {UINT8{CAN_MSGTYPE_INFO}, UINT8{CAN_MSGTYPE_ERROR}, UINT8{CAN_MSGTYPE_STATUS},
                     UINT8{CAN_MSGTYPE_TIMEOVR}}) {
    CANMSG junk = one_byte(0x100 + type, type);
    junk.uMsgInfo.Bytes.bType = type;
    ASSERT_EQ(bus.alpha.writer->PutDataEntry(&junk), VCI_OK);
  }
  ASSERT_EQ(put(bus.alpha.writer, one_byte(0x123, 0x5A)), VCI_OK);
  step_ns(2'000'000);
  const auto got = drain(bus.beta.reader.p, false);
  ASSERT_EQ(got.size(), 2u);  // beta's START and the data frame
  EXPECT_EQ(got[1].uMsgInfo.Bytes.bType, CAN_MSGTYPE_DATA);
  EXPECT_EQ(got[1].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].dwTime, end_of(0x123, {0x5A}));  // first on the bus, at t = 0
  UINT16 fill = 1;
  ASSERT_EQ(bus.alpha.writer->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  // Nothing else came from alpha, and alpha's line is fine.
  CANLINESTATUS s = bus.alpha.line_status();
  EXPECT_EQ(s.dwStatus, 0u);
}

// 74: edl and fdr frames are dropped when the controller was not initialized for them: on an
// SJA1000 (no EXTDATA at all), and on an FD controller initialized with EXTDATA but without
// FASTDATA (fdr dropped, edl sent without bit-rate switch) or classic (edl dropped).
TEST(VciCppItems, Item74_FdFramesNeedTheirExtendedModes) {
  {
    VciDaemon d;
    Adapter alpha("alpha");
    Adapter beta("beta");
    CANMSG edl = one_byte(0x101, 1);
    edl.uMsgInfo.Bits.edl = 1;
    CANMSG fdr = one_byte(0x102, 2);
    fdr.uMsgInfo.Bits.fdr = 1;
    CANMSG plain = one_byte(0x103, 3);
    for (CANMSG* m : {&edl, &fdr, &plain}) {
      ASSERT_EQ(alpha.writer->PutDataEntry(m), VCI_OK);
    }
    step_ns(2'000'000);
    const auto got = drain(beta.reader.p, true);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].dwMsgId, 0x103u);
    EXPECT_EQ(got[0].dwTime, end_of(0x103, {3}));
  }
  VciDaemon d(kFdAdapters);
  V2Adapter alpha("alpha", CAN_EXMODE_EXTDATA);
  V2Adapter beta("beta", CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  const std::vector<uint8_t> twelve{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  CANMSG2 fast = msg2(0x201, twelve);
  fast.uMsgInfo.Bits.edl = 1;
  fast.uMsgInfo.Bits.fdr = 1;
  CANMSG2 slow = msg2(0x202, twelve);
  slow.uMsgInfo.Bits.edl = 1;
  alpha.post(fast);
  alpha.post(slow);
  step_ns(2'000'000);
  auto got = drain<CANMSG2>(beta.reader.p, true);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x202u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 0u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.dlc, 9u);
  EXPECT_EQ(std::memcmp(got[0].abData, twelve.data(), twelve.size()), 0);
  EXPECT_EQ(got[0].dwTime, static_cast<UINT32>(fd_ns(0x202, twelve, false) / 1000));
  // Classic: no FD frame at all.
  ASSERT_EQ(alpha.control->ResetLine(), VCI_OK);
  alpha.init(CAN_EXMODE_DISABLED);
  ASSERT_EQ(alpha.control->StartLine(), VCI_OK);  // at 2 ms
  CANMSG2 fd = msg2(0x203, {3});
  fd.uMsgInfo.Bits.edl = 1;
  alpha.post(fd);
  alpha.post(msg2(0x204, {4}));
  step_ns(2'000'000);
  got = drain<CANMSG2>(beta.reader.p, true);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x204u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 0u);
  EXPECT_EQ(got[0].dwTime, 2000u + end_of(0x204, {4}));
}

// 75: rtr means nothing on an FD frame (edl, or fdr alone): a data frame with its bytes goes
// out; without edl and fdr the same message is a remote frame.
TEST(VciCppItems, Item75_RtrIsIgnoredOnFdFrames) {
  VciDaemon d(kFdAdapters);
  V2Adapter alpha("alpha", CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  V2Adapter beta("beta", CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  CANMSG2 a = msg2(0x301, {1, 2});
  a.uMsgInfo.Bits.edl = 1;
  a.uMsgInfo.Bits.rtr = 1;
  CANMSG2 b = msg2(0x302, {7});
  b.uMsgInfo.Bits.fdr = 1;
  b.uMsgInfo.Bits.rtr = 1;
  CANMSG2 c = msg2(0x303, {});
  c.uMsgInfo.Bits.dlc = 2;
  c.uMsgInfo.Bits.rtr = 1;
  alpha.post(a);
  alpha.post(b);
  alpha.post(c);
  step_ns(2'000'000);
  const auto got = drain<CANMSG2>(beta.reader.p, true);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].dwMsgId, 0x301u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 0u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.rtr, 0u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.dlc, 2u);
  EXPECT_EQ(got[0].abData[0], 1);
  EXPECT_EQ(got[0].abData[1], 2);
  EXPECT_EQ(got[1].dwMsgId, 0x302u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.rtr, 0u);
  EXPECT_EQ(got[1].abData[0], 7);
  EXPECT_EQ(got[2].dwMsgId, 0x303u);
  EXPECT_EQ(got[2].uMsgInfo.Bits.edl, 0u);
  EXPECT_EQ(got[2].uMsgInfo.Bits.rtr, 1u);
  EXPECT_EQ(got[2].uMsgInfo.Bits.dlc, 2u);
  // Back to back, 3 nominal bits (6 us) apart: the data frames' durations prove their bytes.
  const int64_t end_a = fd_ns(0x301, {1, 2}, false);
  const int64_t end_b = end_a + 6'000 + fd_ns(0x302, {7}, true);
  model::FrameSpec spec;
  spec.id = 0x303;
  spec.remote = true;
  spec.dlc = 2;
  const auto remote = *model::Frame::create(spec);
  const int64_t end_c = end_b + 6'000 + 2'000 * model::encode(remote).length;
  EXPECT_EQ(got[0].dwTime, static_cast<UINT32>(end_a / 1000));
  EXPECT_EQ(got[1].dwTime, static_cast<UINT32>(end_b / 1000));
  EXPECT_EQ(got[2].dwTime, static_cast<UINT32>(end_c / 1000));
}

// 77: receive time stamps count at dwClockFreq / dwTscDivisor (v1) and dwTscClkFreq /
// dwTscDivisor (v2) ticks per second: frames 250 ms and 1 s apart differ by exactly that.
TEST(VciCppItems, Item77_TimeStampsCountAtTheCapabilitiesRate) {
  TwoAdapters bus;
  V2Channel ch2(bus.alpha.bal.p);
  ASSERT_NO_FATAL_FAILURE(ch2.activate_with(64, 0, CAN_FILTER_PASS));
  CANCAPABILITIES caps{};
  ASSERT_EQ(bus.alpha.socket->GetCapabilities(&caps), VCI_OK);
  CANCAPABILITIES2 caps2{};
  ASSERT_EQ(ch2.socket->GetCapabilities(&caps2), VCI_OK);
  ASSERT_GT(caps.dwTscDivisor, 0u);
  ASSERT_GT(caps2.dwTscDivisor, 0u);
  const uint64_t v1_per_s = caps.dwClockFreq / caps.dwTscDivisor;
  const uint64_t v2_per_s = caps2.dwTscClkFreq / caps2.dwTscDivisor;
  EXPECT_EQ(v1_per_s, 1'000'000u);
  EXPECT_EQ(v2_per_s, 1'000'000u);
  const uint64_t at[] = {0, 250'000'000, 1'250'000'000};  // ns
  uint64_t t = 0;
  for (uint64_t when : at) {
    if (when > t) {
      step_ns(when - t);
      t = when;
    }
    ASSERT_EQ(put(bus.beta.writer, one_byte(0x123, 1)), VCI_OK);
  }
  step_ns(1'000'000);
  const auto v1 = drain(bus.alpha.reader.p, true);
  const auto v2 = drain<CANMSG2>(ch2.reader.p, true);
  ASSERT_EQ(v1.size(), 3u);
  ASSERT_EQ(v2.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const uint64_t end_ns = at[k] + 2'000u * bits_of(0x123, {1});
    EXPECT_EQ(v1[k].dwTime, end_ns * v1_per_s / 1'000'000'000) << k;
    EXPECT_EQ(v2[k].dwTime, end_ns * v2_per_s / 1'000'000'000) << k;
  }
  EXPECT_EQ(v1[1].dwTime - v1[0].dwTime, v1_per_s / 4);
  EXPECT_EQ(v1[2].dwTime - v1[1].dwTime, v1_per_s);
  EXPECT_EQ(v2[2].dwTime - v2[1].dwTime, v2_per_s);
}

// 92: the echo of an srr frame comes only after the frame went through: a single-shot frame
// that loses arbitration is never echoed; a normal one is echoed once its retry succeeded,
// at the end of that retry.
TEST(VciCppItems, Item92_AnEchoFollowsOnlyASuccessfulTransmission) {
  TwoAdapters bus;
  step_ns(1'000'000);
  drain(bus.alpha.reader.p, false);
  CANMSG zero = one_byte(0x000, 0);  // identifier 0 wins
  CANMSG lost = one_byte(0x123, 1);
  lost.uMsgInfo.Bits.srr = 1;
  lost.uMsgInfo.Bits.ssm = 1;
  ASSERT_EQ(bus.beta.writer->PutDataEntry(&zero), VCI_OK);  // both at 1 ms
  ASSERT_EQ(bus.alpha.writer->PutDataEntry(&lost), VCI_OK);
  step_ns(5'000'000);
  auto got = drain(bus.alpha.reader.p, true);
  ASSERT_EQ(got.size(), 1u);  // beta's frame, no echo
  EXPECT_EQ(got[0].dwMsgId, 0u);
  EXPECT_EQ(got[0].dwTime, 1000u + end_of(0x000, {0}));
  EXPECT_TRUE(drain(bus.beta.reader.p, true).empty());
  // Again at 6 ms without ssm: the frame loses, is retried after beta's frame and echoed then.
  CANMSG retried = lost;
  retried.uMsgInfo.Bits.ssm = 0;
  ASSERT_EQ(bus.beta.writer->PutDataEntry(&zero), VCI_OK);
  ASSERT_EQ(bus.alpha.writer->PutDataEntry(&retried), VCI_OK);
  step_ns(5'000'000);
  got = drain(bus.alpha.reader.p, true);
  ASSERT_EQ(got.size(), 2u);
  const UINT32 retry_end = 6000u + end_of(0x000, {0}) + 6u + end_of(0x123, {1});
  EXPECT_EQ(got[0].dwMsgId, 0u);
  EXPECT_EQ(got[1].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(got[1].dwTime, retry_end);
  const auto at_beta = the_one(drain(bus.beta.reader.p, true));
  EXPECT_EQ(at_beta.dwTime, retry_end);
}

// ---------------------------------------------------------------- filters

// 105: a frame the control unit's filter blocks reaches no channel, not even a v2 channel in
// PASS mode; what the control unit passes reaches both with its afc.
TEST(VciCppItems, Item105_ControlUnitFilterBlocksEvenPassChannels) {
  VciDaemon d;
  Adapter beta("beta");
  const BalSocket<ICanSocket> alpha("alpha", IID_ICanSocket);
  const Channel v1(alpha.socket.p, 64, 0, true);
  V2Channel pass(alpha.bal.p);
  ASSERT_NO_FATAL_FAILURE(pass.activate_with(64, 0, CAN_FILTER_PASS));
  Ref<ICanControl> control;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
  CANINITLINE init{kMode, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  ASSERT_EQ(control->SetAccFilter(CAN_FILTER_STD, 0x200, 0xFF9), VCI_OK);  // 0x100..0x103
  ASSERT_EQ(control->StartLine(), VCI_OK);
  for (UINT32 id : {0x200u, 0x101u, 0x104u}) {
    ASSERT_EQ(put(beta.writer, one_byte(id, 1)), VCI_OK);
  }
  step_ns(2'000'000);
  const UINT32 end = end_of(0x200, {1}) + 6u + end_of(0x101, {1});
  const auto a = drain(v1.reader.p, true);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].dwMsgId, 0x101u);
  EXPECT_EQ(a[0].dwTime, end);
  EXPECT_EQ(a[0].uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_1);
  const auto b = drain<CANMSG2>(pass.reader.p, true);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].dwMsgId, 0x101u);
  EXPECT_EQ(b[0].dwTime, end);
}

// ---------------------------------------------------------------- transmission

// 112: a single-shot frame gets one attempt: lost arbitration or a missing acknowledge, and it
// is given up, never to appear on the bus later; the next frame goes normally.
TEST(VciCppItems, Item112_SingleShotFramesAreNotRetried) {
  VciDaemon d;
  Adapter alpha("alpha");
  CANMSG alone = one_byte(0x123, 1);
  alone.uMsgInfo.Bits.ssm = 1;
  ASSERT_EQ(alpha.writer->PutDataEntry(&alone), VCI_OK);  // at 0, nobody to acknowledge
  step_ns(10'000'000);
  auto errors = drain(alpha.reader.p, false);
  ASSERT_EQ(errors.size(), 2u);  // START and one ACK error
  EXPECT_EQ(errors[1].uMsgInfo.Bytes.bType, CAN_MSGTYPE_ERROR);
  EXPECT_EQ(errors[1].abData[0], CAN_ERROR_ACK);
  // At the end of the ACK slot, the 9th bit from the frame's end (then ACK delimiter, EOF).
  EXPECT_EQ(errors[1].dwTime, 2u * (bits_of(0x123, {1}) - 8));
  UINT16 tec = 0;
  ASSERT_EQ(canemuGetControllerState(alpha.control.p, nullptr, &tec, nullptr, nullptr), VCI_OK);
  EXPECT_EQ(tec, 8);
  Adapter beta("beta");  // at 10 ms
  step_ns(10'000'000);
  EXPECT_TRUE(drain(beta.reader.p, true).empty());
  // Lost arbitration at 20 ms against identifier 0.
  drain(alpha.reader.p, false);
  CANMSG zero = one_byte(0x000, 0);
  CANMSG loser = one_byte(0x124, 2);
  loser.uMsgInfo.Bits.ssm = 1;
  ASSERT_EQ(beta.writer->PutDataEntry(&zero), VCI_OK);
  ASSERT_EQ(alpha.writer->PutDataEntry(&loser), VCI_OK);
  step_ns(10'000'000);
  EXPECT_TRUE(drain(beta.reader.p, true).empty());
  const auto at_alpha = drain(alpha.reader.p, false);
  ASSERT_EQ(at_alpha.size(), 1u);  // beta's frame; no error
  EXPECT_EQ(at_alpha[0].dwMsgId, 0u);
  EXPECT_EQ(at_alpha[0].dwTime, 20'000u + end_of(0x000, {0}));
  CANMSG next = one_byte(0x125, 3);
  ASSERT_EQ(alpha.writer->PutDataEntry(&next), VCI_OK);  // at 30 ms
  step_ns(1'000'000);
  const auto got = the_one(drain(beta.reader.p, true));
  EXPECT_EQ(got.dwMsgId, 0x125u);
  EXPECT_EQ(got.dwTime, 30'000u + end_of(0x125, {3}));
}

// ---------------------------------------------------------------- bit timing

// 114: each BTR pair of the table runs its line at its rate: a frame between two adapters
// initialized with the pair takes exactly its bits at that rate, and the line status echoes
// the pair.
TEST(VciCppItems, Item114_BtrPairsOfTheTableGiveTheirRates) {
  TwoAdapters bus;
  for (const testing::BtrRate& r : testing::kBtrTable) {
    const uint64_t bit_ns = 1'000'000'000 / r.bps;
    for (Adapter* a : {&bus.alpha, &bus.beta}) {
      ASSERT_NO_FATAL_FAILURE(a->reinit(r.btr0, r.btr1));
      ASSERT_EQ(a->control->StartLine(), VCI_OK);
    }
    CANLINESTATUS s{};
    ASSERT_EQ(bus.alpha.control->GetLineStatus(&s), VCI_OK);
    EXPECT_EQ(s.bBtReg0, r.btr0);
    EXPECT_EQ(s.bBtReg1, r.btr1);
    drain(bus.alpha.reader.p, false);
    const uint64_t start = now_ns();
    ASSERT_EQ(put(bus.beta.writer, one_byte(0x555, 0xAA)), VCI_OK);
    step_ns(50'000'000);
    const auto got = drain(bus.alpha.reader.p, false);
    ASSERT_EQ(got.size(), 1u) << bit_ns;
    EXPECT_EQ(got[0].dwMsgId, 0x555u);
    EXPECT_EQ(got[0].dwTime, (start + bits_of(0x555, {0xAA}) * bit_ns) / 1000) << bit_ns;
  }
}

// 117: raw CANBTP values outside the capability ranges (sSdrRangeMin/Max, sFdrRangeMin/Max) are
// refused by InitLine, values at the limits are taken.
TEST(VciCppItems, Item117_RawTimingOutsideTheRangesIsRefused) {
  VciDaemon d(kFdAdapters);
  const BalSocket<ICanSocket2> alpha("alpha", IID_ICanSocket2);
  CANCAPABILITIES2 caps{};
  ASSERT_EQ(alpha.socket->GetCapabilities(&caps), VCI_OK);
  Ref<ICanControl2> control;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanControl2, control.pv()), VCI_OK);
  const CANBTP sdr{CAN_BTMODE_RAW, 10, 13, 2, 1, 0};  // 80 MHz / 10 / 16 quanta: 500 kbit/s
  const CANBTP fdr{CAN_BTMODE_RAW, 4, 7, 2, 1, 0};    // 80 MHz / 4 / 10 quanta: 2 Mbit/s
  auto init_with = [&](CANBTP n, CANBTP f) {
    CANINITLINE2 init{};
    init.bOpMode = kMode;
    init.bExMode = CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA;
    init.bSFMode = CAN_FILTER_PASS;
    init.bEFMode = CAN_FILTER_PASS;
    init.sBtpSdr = n;
    init.sBtpFdr = f;
    return control->InitLine(&init);
  };
  ASSERT_EQ(init_with(sdr, fdr), VCI_OK);
  CANLINESTATUS2 s{};
  ASSERT_EQ(control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(std::memcmp(&s.sBtpSdr, &sdr, sizeof sdr), 0);  // as given
  EXPECT_EQ(std::memcmp(&s.sBtpFdr, &fdr, sizeof fdr), 0);
  struct Case {
    const char* what;
    CANBTP n;
    CANBTP f;
  };
  auto with = [](CANBTP b, UINT32 bps, UINT16 ts1, UINT16 ts2) {
    b.dwBPS = bps;
    b.wTS1 = ts1;
    b.wTS2 = ts2;
    return b;
  };
  const CANBTP& smin = caps.sSdrRangeMin;
  const CANBTP& smax = caps.sSdrRangeMax;
  const CANBTP& fmax = caps.sFdrRangeMax;
  const Case outside[] = {
      {"sdr prescaler above", with(sdr, smax.dwBPS + 1, sdr.wTS1, sdr.wTS2), fdr},
      {"sdr prescaler below", with(sdr, smin.dwBPS - 1, sdr.wTS1, sdr.wTS2), fdr},
      {"sdr ts1 above", with(sdr, sdr.dwBPS, smax.wTS1 + 1, sdr.wTS2), fdr},
      {"sdr ts2 above", with(sdr, sdr.dwBPS, sdr.wTS1, smax.wTS2 + 1), fdr},
      {"sdr ts2 below", with(sdr, sdr.dwBPS, sdr.wTS1, smin.wTS2 - 1), fdr},
      {"fdr prescaler above", sdr, with(fdr, fmax.dwBPS + 1, fdr.wTS1, fdr.wTS2)},
      {"fdr ts1 above", sdr, with(fdr, fdr.dwBPS, fmax.wTS1 + 1, fdr.wTS2)},
      {"fdr ts2 above", sdr, with(fdr, fdr.dwBPS, fdr.wTS1, fmax.wTS2 + 1)},
  };
  for (const Case& c : outside) {
    EXPECT_EQ(init_with(c.n, c.f), VCI_E_INVALIDARG) << c.what;
  }
  // At the limits.
  EXPECT_EQ(init_with(with(sdr, smax.dwBPS, smax.wTS1, smax.wTS2), fdr), VCI_OK);
  EXPECT_EQ(init_with(sdr, with(fdr, fmax.dwBPS, fmax.wTS1, fmax.wTS2)), VCI_OK);
  EXPECT_EQ(init_with(with(sdr, smin.dwBPS, sdr.wTS1, sdr.wTS2), fdr), VCI_OK);
}

// 116 with bit/s timings the clock does not make as they are (issue 34): ICanControl2::InitLine
// takes the nearest timing (docs/vci.md, "Bit timing in bit/s form") and GetLineStatus shows
// it; the line exchanges FD frames with the rate switch with one on the exact presets.
TEST(VciCppItems, Item116_InitLineTakesTheNearestTimingOfABitPerSecondCanbtp) {
  VciDaemon d(kFdAdapters);
  V2Adapter beta("beta", CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(vci_id_named("alpha"), bal));
  V2Channel ch2(bal.p);
  ASSERT_NO_FATAL_FAILURE(ch2.activate_with(64, 16, CAN_FILTER_PASS));
  Ref<ICanControl2> control;
  ASSERT_EQ(ch2.channel->GetControl(control.out()), VCI_OK);
  CANINITLINE2 init{};
  init.bOpMode = kMode;
  init.bExMode = CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA;
  init.bSFMode = CAN_FILTER_PASS;
  init.bEFMode = CAN_FILTER_PASS;
  init.sBtpSdr = CANBTP{0, 500000, 80, 20, 20, 0};          // 80 % in steps of 1 %
  init.sBtpFdr = CANBTP{0, 2000000, 1600, 400, 400, 1600};  // python-can's 2 Mbit/s preset
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  CANLINESTATUS2 s{};
  ASSERT_EQ(control->GetLineStatus(&s), VCI_OK);
  // 80 quanta of 2 clocks (80 MHz), SJW 16; 40 data quanta of one clock, SJW 8, TDO 32.
  const CANBTP nominal{0, 500000, 64, 16, 16, 0};
  const CANBTP data{0, 2000000, 32, 8, 8, 32};
  EXPECT_EQ(std::memcmp(&s.sBtpSdr, &nominal, sizeof nominal), 0);
  EXPECT_EQ(std::memcmp(&s.sBtpFdr, &data, sizeof data), 0);
  ASSERT_EQ(control->StartLine(), VCI_OK);
  drain<CANMSG2>(ch2.reader.p, false);
  drain<CANMSG2>(beta.reader.p, false);
  CANMSG2 m = msg2(0x1A5, std::vector<uint8_t>(20, 0x3C));  // 20 bytes: DLC 11
  m.uMsgInfo.Bits.edl = 1;
  m.uMsgInfo.Bits.fdr = 1;
  ASSERT_EQ(ch2.writer->PutDataEntry(&m), VCI_OK);
  step_ns(1'000'000);
  CANMSG2 got = the_one(drain<CANMSG2>(beta.reader.p, true));
  EXPECT_EQ(got.dwMsgId, 0x1A5u);
  EXPECT_EQ(got.uMsgInfo.Bits.dlc, 11u);
  EXPECT_EQ(got.uMsgInfo.Bits.fdr, 1u);
  m.dwMsgId = 0x5A1;
  beta.post(m);
  step_ns(1'000'000);
  got = the_one(drain<CANMSG2>(ch2.reader.p, true));
  EXPECT_EQ(got.dwMsgId, 0x5A1u);
  EXPECT_EQ(got.uMsgInfo.Bits.fdr, 1u);
}

// Issue 34: through the C++ API's FIFO writer a data message whose identifier does not fit its
// format is refused too: PutDataEntry, and ReleaseWrite of written entries (nothing is handed
// over; the program may correct the entry and release again).
TEST(VciCppItems, IdentifiersThatDoNotFitTheirFormatAreRefusedByTheWriter) {
  TwoAdapters bus;
  step_ns(1'000'000);
  drain(bus.beta.reader.p, false);
  CANMSG standard = one_byte(0x800, 0x11);
  EXPECT_EQ(bus.alpha.writer->PutDataEntry(&standard), VCI_E_INVALIDARG);
  char text[256];
  VciFormatError(VCI_E_INVALIDARG, text, sizeof text);
  EXPECT_STREQ(text,
               "invalid argument (identifier 0x800 does not fit 11 bits (ext = 0: at most 0x7FF); "
               "the message was not queued)");
  CANMSG extended = one_byte(0x20000000, 0x22);
  extended.uMsgInfo.Bits.ext = 1;
  EXPECT_EQ(bus.alpha.writer->PutDataEntry(&extended), VCI_E_INVALIDARG);
  PVOID space = nullptr;
  UINT16 count = 0;
  ASSERT_EQ(bus.alpha.writer->AcquireWrite(&space, &count), VCI_OK);
  ASSERT_GE(count, 2);
  auto* entries = static_cast<CANMSG*>(space);
  entries[0] = one_byte(0x123, 0x33);
  entries[1] = extended;
  EXPECT_EQ(bus.alpha.writer->ReleaseWrite(2), VCI_E_INVALIDARG);
  UINT16 fill = 99;
  ASSERT_EQ(bus.alpha.writer->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  entries[1].dwMsgId = 0x1FFFFFFF;  // corrected: the largest 29-bit identifier
  EXPECT_EQ(bus.alpha.writer->ReleaseWrite(2), VCI_OK);
  step_ns(1'000'000);
  const auto got = drain(bus.beta.reader.p, true);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].dwMsgId, 0x123u);
  EXPECT_EQ(got[1].dwMsgId, 0x1FFFFFFFu);
  EXPECT_EQ(got[1].uMsgInfo.Bits.ext, 1u);
}

// ---------------------------------------------------------------- cyclic transmit list

// 125: entries started at different times while the task is stopped all count their cycle from
// the Resume: each sends first one cycle after it.
TEST(VciCppItems, Item125_ResumeStartsEveryStartedEntryInTheSameTick) {
  TwoAdapters bus;
  const Ref<ICanScheduler> list = bus.alpha.scheduler();
  const UINT16 cycles[] = {4, 6, 10};
  for (UINT32 k = 0; k < 3; ++k) {
    CANCYCLICTXMSG m = cyclic(0x100 + k, cycles[k]);
    UINT32 index = 99;
    ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
    EXPECT_EQ(index, k);
    ASSERT_EQ(list->StartMessage(index, 0), VCI_OK);  // at 0, 2 and 4 ms
    step_ns(2'000'000);
  }
  step_ns(1'000'000);
  EXPECT_TRUE(drain(bus.beta.reader.p, true).empty());
  ASSERT_EQ(list->Resume(), VCI_OK);  // at 7 ms
  step_ns(11'000'000);
  const auto got = drain(bus.beta.reader.p, true);
  // Ticks 4 (0x100), 6 (0x101), 8 (0x100), 10 (0x102) after the resume.
  ASSERT_EQ(ids_of(got), (std::vector<UINT32>{0x100, 0x101, 0x100, 0x102}));
  const UINT32 ticks[] = {4, 6, 8, 10};
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].dwTime, 7'000u + 1'000u * ticks[k] + end_of(got[k].dwMsgId, {0x11})) << k;
  }
}

// 127: an entry sends every wCycleTime ticks; when two are due in one tick the older goes and
// the other goes one tick later, keeping its rhythm.
TEST(VciCppItems, Item127_EntriesKeepTheirCycleWithinOneTickOnCollisions) {
  TwoAdapters bus;
  const Ref<ICanScheduler> list = bus.alpha.scheduler();
  for (auto [id, cycle] : {std::pair<UINT32, UINT16>{0x100, 2}, {0x200, 3}}) {
    add_and_start(list.p, cyclic(id, cycle));
  }
  ASSERT_EQ(list->Resume(), VCI_OK);  // at 0
  step_ns(13'500'000);
  ASSERT_EQ(list->Suspend(), VCI_OK);
  std::vector<UINT32> a;
  std::vector<UINT32> b;
  for (const CANMSG& m : drain(bus.beta.reader.p, true)) {
    const UINT32 tick = (m.dwTime - end_of(m.dwMsgId, {0x11})) / 1000;
    EXPECT_EQ((m.dwTime - end_of(m.dwMsgId, {0x11})) % 1000, 0u);  // at the tick exactly
    (m.dwMsgId == 0x100 ? a : b).push_back(tick);
  }
  EXPECT_EQ(a, (std::vector<UINT32>{2, 4, 6, 8, 10, 12}));
  // Due at 3, 6, 9, 12: 6 and 12 went to the older entry.
  EXPECT_EQ(b, (std::vector<UINT32>{3, 7, 9, 13}));
}

// 129: INC_8 counts a byte up with 255 -> 0, INC_16 the little-endian word at bByteIndex with
// the carry into the high byte and 65535 -> 0; the count applies after each frame.
TEST(VciCppItems, Item129_ByteAndWordIncrementsWrap) {
  TwoAdapters bus;
  const Ref<ICanScheduler> list = bus.alpha.scheduler();
  CANCYCLICTXMSG byte = cyclic(0x100, 4, {0xAA, 0xFE, 0xBB});
  byte.bIncrMode = CAN_CTXMSG_INC_8;
  byte.bByteIndex = 1;
  CANCYCLICTXMSG word = cyclic(0x200, 4, {0xAA, 0xFE, 0xFF, 0xBB});
  word.bIncrMode = CAN_CTXMSG_INC_16;
  word.bByteIndex = 1;
  CANCYCLICTXMSG carry = cyclic(0x300, 4, {0xFF, 0x12});
  carry.bIncrMode = CAN_CTXMSG_INC_16;
  carry.bByteIndex = 0;
  for (const CANCYCLICTXMSG& m : {byte, word, carry}) {
    add_and_start(list.p, m, 3);
  }
  ASSERT_EQ(list->Resume(), VCI_OK);
  step_ns(20'000'000);
  std::vector<std::vector<uint8_t>> bytes, words, carries;
  for (const CANMSG& m : drain(bus.beta.reader.p, true)) {
    const std::vector<uint8_t> v(m.abData, m.abData + m.uMsgInfo.Bits.dlc);
    (m.dwMsgId == 0x100 ? bytes : m.dwMsgId == 0x200 ? words : carries).push_back(v);
  }
  using B = std::vector<std::vector<uint8_t>>;
  EXPECT_EQ(bytes, (B{{0xAA, 0xFE, 0xBB}, {0xAA, 0xFF, 0xBB}, {0xAA, 0x00, 0xBB}}));
  EXPECT_EQ(words,
            (B{{0xAA, 0xFE, 0xFF, 0xBB}, {0xAA, 0xFF, 0xFF, 0xBB}, {0xAA, 0x00, 0x00, 0xBB}}));
  EXPECT_EQ(carries, (B{{0xFF, 0x12}, {0x00, 0x13}, {0x01, 0x13}}));
}

// 130: Suspend stops every entry (none sends while suspended), Resume goes on, each counting its
// cycle from the Resume; Reset empties the list and stops the task.
TEST(VciCppItems, Item130_SuspendResumeAndResetTheList) {
  TwoAdapters bus;
  const Ref<ICanScheduler> list = bus.alpha.scheduler();
  const UINT32 index = add_and_start(list.p, cyclic(0x100, 2));
  ASSERT_EQ(list->Resume(), VCI_OK);  // at 0
  step_ns(5'000'000);
  ASSERT_EQ(list->Suspend(), VCI_OK);  // at 5 ms
  CANSCHEDULERSTATUS s{};
  ASSERT_EQ(list->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(s.abMsgStat[index], CAN_CTXMSG_STAT_BUSY);
  step_ns(6'000'000);
  ASSERT_EQ(list->Resume(), VCI_OK);  // at 11 ms
  step_ns(4'500'000);
  std::vector<UINT32> times;
  for (const CANMSG& f : drain(bus.beta.reader.p, true)) {
    times.push_back(f.dwTime - end_of(0x100, {0x11}));
  }
  EXPECT_EQ(times, (std::vector<UINT32>{2'000, 4'000, 13'000, 15'000}));
  ASSERT_EQ(list->Reset(), VCI_OK);
  ASSERT_EQ(list->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  for (UINT8 stat : s.abMsgStat) {
    EXPECT_EQ(stat, CAN_CTXMSG_STAT_EMPTY);
  }
  EXPECT_EQ(list->StartMessage(index, 0), VCI_E_INVALID_INDEX);
  ASSERT_EQ(list->Resume(), VCI_OK);
  step_ns(10'000'000);
  EXPECT_TRUE(drain(bus.beta.reader.p, true).empty());
}

// ---------------------------------------------------------------- items with no other API test

// 1: VciInitialize succeeds, and the rest of the API works after it.
TEST(VciCppItems, Item01_VciInitializeSucceedsAndTheApiWorksAfterIt) {
  VciDaemon d;
  EXPECT_EQ(VciInitialize(), VCI_OK);
  EXPECT_EQ(VciInitialize(), VCI_OK);  // again: harmless
  EXPECT_EQ(vci_id_named("beta"), 2);
}

// 2: without canemud VciGetDeviceManager fails and leaves NULL behind.
TEST(VciCppItems, Item02_WithoutCanemudTheDeviceManagerIsNull) {
  EXPECT_EQ(canemuConnect("/nonexistent/canemud.sock"), VCI_E_DISCONNECTED);
  IVciDeviceManager* manager = reinterpret_cast<IVciDeviceManager*>(&manager);  // not NULL
  EXPECT_EQ(VciGetDeviceManager(&manager), VCI_E_DISCONNECTED);
  EXPECT_EQ(manager, nullptr);
  canemuConnect(nullptr);
  VciDaemon d;
  Ref<IVciDeviceManager> ok;
  ASSERT_EQ(VciGetDeviceManager(ok.out()), VCI_OK);
  EXPECT_NE(ok.p, nullptr);
}

// 11: a hardware ID nobody has opens nothing and leaves NULL behind.
TEST(VciCppItems, Item11_AnUnknownHardwareIdOpensNothing) {
  VciDaemon d;
  Adapter alpha("alpha");
  VCIDEVICEINFO info{};
  VCIDEVICEINFO found{};
  ASSERT_NO_FATAL_FAILURE(testing::query_by_hwid(alpha.device.p, &info, &found));
  EXPECT_EQ(std::memcmp(&found, &info, sizeof info), 0);
  GUID unknown = info.UniqueHardwareId.AsGuid;
  unknown.Data4[7] ^= 0x5A;
  IVciDevice* none = alpha.device.p;
  EXPECT_EQ(VciQueryDeviceByHwid(unknown, &none), VCI_E_NO_MORE_ITEMS);
  EXPECT_EQ(none, nullptr);
}

// 12: by class, instance 0 is the first adapter of the list.
TEST(VciCppItems, Item12_ClassInstanceZeroIsTheFirstInListOrder) {
  VciDaemon d;
  Adapter beta("beta");
  VCIDEVICEINFO info{};
  ASSERT_EQ(beta.device->GetDeviceInfo(&info), VCI_OK);
  Ref<IVciDevice> first;
  ASSERT_EQ(VciQueryDeviceByClass(info.DeviceClass, 0, first.out()), VCI_OK);
  VCIDEVICEINFO found{};
  ASSERT_EQ(first->GetDeviceInfo(&found), VCI_OK);
  EXPECT_STREQ(found.Description, "USB-to-CAN (canemu alpha)");
  EXPECT_EQ(found.VciObjectId.AsInt64, 1);
}

// 16: the device opens its BAL as IBalObject or IUnknown, nothing else; a refusal leaves NULL.
TEST(VciCppItems, Item16_OpenComponentGivesOnlyTheBal) {
  VciDaemon d;
  Adapter alpha("alpha");
  Ref<IBalObject> bal;
  EXPECT_EQ(alpha.device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
  Ref<IUnknown> unknown;
  EXPECT_EQ(alpha.device->OpenComponent(CLSID_VCIBAL, IID_IUnknown, unknown.pv()), VCI_OK);
  PVOID none = &none;
  EXPECT_EQ(alpha.device->OpenComponent(CLSID_VCIBAL, IID_ICanSocket, &none), VCI_E_NOINTERFACE);
  EXPECT_EQ(none, nullptr);
  none = &none;
  EXPECT_EQ(alpha.device->OpenComponent(IID_ICanSocket, IID_IBalObject, &none), VCI_E_INVALIDARG);
  EXPECT_EQ(none, nullptr);
}

// 18, 19: the BAL's sockets are the device's controllers, CAN and LIN, in the same order; a bus
// number past them opens nothing.
TEST(VciCppItems, Item18_BalFeaturesMatchTheDeviceCaps) {
  VciDaemon d(testing::kLinAdapters);
  Ref<IVciDeviceManager> manager;
  ASSERT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  VCIID id{};
  id.AsInt64 = vci_id_named("alpha");
  Ref<IVciDevice> device;
  ASSERT_EQ(manager->OpenDevice(id, device.out()), VCI_OK);
  VCIDEVICECAPS caps{};
  ASSERT_EQ(device->GetDeviceCaps(&caps), VCI_OK);
  Ref<IBalObject> bal;
  ASSERT_EQ(device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
  BALFEATURES features{};
  ASSERT_EQ(bal->GetFeatures(&features), VCI_OK);
  ASSERT_EQ(caps.BusCtrlCount, 2);
  EXPECT_EQ(features.BusSocketCount, caps.BusCtrlCount);
  EXPECT_EQ(caps.BusCtrlTypes[0], (VCI_BUS_CAN << 8) | CAN_CTRL_SJA1000);
  EXPECT_EQ(caps.BusCtrlTypes[1] >> 8, VCI_BUS_LIN);
  for (UINT16 k = 0; k < caps.BusCtrlCount; ++k) {
    EXPECT_EQ(features.BusSocketType[k], caps.BusCtrlTypes[k]) << k;
  }
  PVOID none = &none;
  EXPECT_EQ(bal->OpenSocket(2, IID_ICanSocket, &none), VCI_E_INVALIDARG);
  EXPECT_EQ(none, nullptr);
}

// 24: VciGetVersion fills all eight fields.
TEST(VciCppItems, Item24_VersionFillsEveryField) {
  VCIVERSIONINFO v;
  std::memset(&v, 0xEE, sizeof v);
  ASSERT_EQ(VciGetVersion(&v), VCI_OK);
  EXPECT_EQ(v.VciMajorVersion, 4u);
  EXPECT_EQ(v.VciMinorVersion, 0u);
  EXPECT_EQ(v.VciRevNumber, 0u);
  for (UINT32 field :
       {v.VciBuildNumber, v.OsMajorVersion, v.OsMinorVersion, v.OsBuildNumber, v.OsPlatformId}) {
    EXPECT_NE(field, 0xEEEEEEEEu);
  }
  EXPECT_EQ(VciGetVersion(nullptr), VCI_E_INVALIDARG);
}

// 32: AcquireRead gives the contiguous part only: after the ring wrapped, the elements up to its
// end, then the rest from its start.
TEST(VciCppItems, Item32_AcquireReadStopsAtTheEndOfTheRing) {
  VciDaemon d;
  StandAloneFifo fifo(16, 8);
  UINT16 capacity = 0;
  ASSERT_EQ(fifo.reader->GetCapacity(&capacity), VCI_OK);
  uint8_t e[8] = {};
  for (UINT16 k = 0; k + 2 < capacity; ++k) {  // up to two before the end, read again
    ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
    ASSERT_EQ(fifo.reader->GetDataEntry(nullptr), VCI_OK);
  }
  for (uint8_t k = 1; k <= 5; ++k) {
    e[0] = k;
    ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  }
  PVOID p = nullptr;
  UINT16 n = 0;
  ASSERT_EQ(fifo.reader->AcquireRead(&p, &n), VCI_OK);
  ASSERT_EQ(n, 2);
  EXPECT_EQ(static_cast<uint8_t*>(p)[0], 1);
  EXPECT_EQ(static_cast<uint8_t*>(p)[8], 2);
  ASSERT_EQ(fifo.reader->ReleaseRead(2), VCI_OK);
  ASSERT_EQ(fifo.reader->AcquireRead(&p, &n), VCI_OK);
  ASSERT_EQ(n, 3);
  EXPECT_EQ(static_cast<uint8_t*>(p)[0], 3);
  EXPECT_EQ(static_cast<uint8_t*>(p)[16], 5);
}

// 40: the reader's event comes with the write that brings the fill to the threshold, not
// before.
TEST(VciCppItems, Item40_TheReaderEventComesWithTheWriteThatReachesTheThreshold) {
  VciDaemon d;
  StandAloneFifo fifo(16, 8);
  const Event event;
  ASSERT_EQ(fifo.reader->SetThreshold(3), VCI_OK);
  ASSERT_EQ(fifo.reader->AssignEvent(event), VCI_OK);
  uint8_t e[8] = {};
  ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(event, 0), WAIT_TIMEOUT);
  ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);
  fifo.reader->AssignEvent(nullptr);
}

// 43: AssignEvent(NULL) takes the event away: writes signal nothing any more.
TEST(VciCppItems, Item43_AssignEventNullRemovesTheEvent) {
  VciDaemon d;
  StandAloneFifo fifo(16, 8);
  const Event removed;
  const Event later;
  ASSERT_EQ(fifo.reader->SetThreshold(1), VCI_OK);
  ASSERT_EQ(fifo.reader->AssignEvent(removed), VCI_OK);
  ASSERT_EQ(fifo.reader->AssignEvent(nullptr), VCI_OK);
  uint8_t e[8] = {};
  ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  // Signals come in order: once `later` has its signal, `removed` would have had its own.
  ASSERT_EQ(fifo.reader->GetDataEntry(nullptr), VCI_OK);
  ASSERT_EQ(fifo.reader->AssignEvent(later), VCI_OK);
  ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(later, 5000), WAIT_OBJECT_0);
  EXPECT_EQ(WaitForSingleObject(removed, 0), WAIT_TIMEOUT);
  fifo.reader->AssignEvent(nullptr);
}

// 49: the v1 and v2 capabilities of a socket agree; the FD features are there on the FD
// controller only.
TEST(VciCppItems, Item49_V1AndV2CapabilitiesAgree) {
  for (const char* config : {testing::kTwoAdapters, kFdAdapters}) {
    VciDaemon d(config);
    Ref<IBalObject> bal;
    ASSERT_NO_FATAL_FAILURE(open_bal(vci_id_named("alpha"), bal));
    Ref<ICanSocket> v1;
    ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, v1.pv()), VCI_OK);
    Ref<ICanSocket2> v2;
    ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket2, v2.pv()), VCI_OK);
    CANCAPABILITIES c1{};
    ASSERT_EQ(v1->GetCapabilities(&c1), VCI_OK);
    CANCAPABILITIES2 c2{};
    ASSERT_EQ(v2->GetCapabilities(&c2), VCI_OK);
    const bool fd = config == kFdAdapters;
    EXPECT_EQ(c1.wCtrlType, fd ? CAN_CTRL_IFICFD : CAN_CTRL_SJA1000);
    EXPECT_EQ(c2.wCtrlType, c1.wCtrlType);
    EXPECT_EQ(c2.wBusCoupling, c1.wBusCoupling);
    const UINT32 fd_bits = CAN_FEATURE_EXTDATA | CAN_FEATURE_FASTDATA;
    EXPECT_EQ(c2.dwFeatures, c1.dwFeatures);
    EXPECT_EQ(c2.dwFeatures & fd_bits, fd ? fd_bits : 0u);
    EXPECT_EQ(c2.dwTscClkFreq / c2.dwTscDivisor, c1.dwClockFreq / c1.dwTscDivisor);
    EXPECT_EQ(c2.dwCmsMaxTicks, c1.dwCmsMaxTicks);
    EXPECT_EQ(c2.dwDtxMaxTicks, c1.dwDtxMaxTicks);
  }
}

// 53, 54: a v2 channel needs a receive FIFO; before Initialize it has no reader or writer,
// after it their elements are CANMSG2 (v1: CANMSG).
TEST(VciCppItems, Item53_V2InitializeNeedsAReceiveFifoAndHandsOutCanmsg2) {
  VciDaemon d;
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(vci_id_named("alpha"), bal));
  V2Channel ch2(bal.p);
  Ref<IFifoWriter> writer2;
  EXPECT_EQ(ch2.channel->GetWriter(writer2.out()), VCI_E_NOT_INITIALIZED);
  EXPECT_EQ(ch2.channel->Initialize(0, 16, 0, CAN_FILTER_PASS), VCI_E_INVALIDARG);
  ASSERT_EQ(ch2.channel->Initialize(16, 16, 0, CAN_FILTER_PASS), VCI_OK);
  Ref<IFifoReader> reader2;
  ASSERT_EQ(ch2.channel->GetReader(reader2.out()), VCI_OK);
  ASSERT_EQ(ch2.channel->GetWriter(writer2.out()), VCI_OK);
  UINT16 size = 0;
  ASSERT_EQ(reader2->GetEntrySize(&size), VCI_OK);
  EXPECT_EQ(size, sizeof(CANMSG2));
  ASSERT_EQ(writer2->GetEntrySize(&size), VCI_OK);
  EXPECT_EQ(size, sizeof(CANMSG2));
  Ref<ICanSocket> socket;
  ASSERT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
  Ref<ICanChannel> channel;
  ASSERT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
  Ref<IFifoWriter> writer;
  EXPECT_EQ(channel->GetWriter(writer.out()), VCI_E_NOT_INITIALIZED);
  ASSERT_EQ(channel->Initialize(16, 0), VCI_OK);                    // no transmit FIFO
  EXPECT_EQ(channel->GetWriter(writer.out()), VCI_E_ACCESSDENIED);  // so no writer
  ASSERT_EQ(channel->Initialize(16, 16), VCI_OK);
  ASSERT_EQ(channel->GetWriter(writer.out()), VCI_OK);
  ASSERT_EQ(writer->GetEntrySize(&size), VCI_OK);
  EXPECT_EQ(size, sizeof(CANMSG));
}

// The 11-bit data frames of `ids` from beta, 1 ms of bus time, and what alpha's channel got.
std::vector<CANMSG> exchange(Adapter& alpha, Adapter& beta, std::vector<UINT32> ids) {
  drain(alpha.reader.p, false);
  for (UINT32 id : ids) {
    CANMSG m = one_byte(id, 1);
    EXPECT_EQ(beta.writer->PutDataEntry(&m), VCI_OK);
  }
  step_ns(2'000'000);
  return drain(alpha.reader.p, true);
}

// 64: StopLine: INFO STOP with time 0, the controller offline (ININIT), and the filters as
// they were.
TEST(VciCppItems, Item64_StopLineKeepsTheFilters) {
  TwoAdapters bus;
  ASSERT_NO_FATAL_FAILURE(bus.alpha.reinit(CAN_BT0_500KB, CAN_BT1_500KB));
  ASSERT_EQ(bus.alpha.control->SetAccFilter(CAN_FILTER_STD, 0x200, 0xFF9), VCI_OK);  // 0x100..0x103
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  EXPECT_EQ(ids_of(exchange(bus.alpha, bus.beta, {0x100, 0x104})), std::vector<UINT32>{0x100});
  step_ns(1'000'000);
  ASSERT_EQ(bus.alpha.control->StopLine(), VCI_OK);
  CANLINESTATUS s = bus.alpha.line_status();
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  const auto stop = the_one(drain(bus.alpha.reader.p, false));
  EXPECT_EQ(stop.abData[0], CAN_INFO_STOP);
  EXPECT_EQ(stop.dwTime, 0u);
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  EXPECT_EQ(ids_of(exchange(bus.alpha, bus.beta, {0x101, 0x104})), std::vector<UINT32>{0x101});
}

// 65: ResetLine: INFO RESET with time 0, the controller not initialized, and the ID lists empty
// (the v1 control unit's 29-bit list of 2048 values has room again).
TEST(VciCppItems, Item65_ResetLineEmptiesTheFilterLists) {
  TwoAdapters bus;
  ASSERT_EQ(bus.alpha.control->StopLine(), VCI_OK);
  ASSERT_EQ(bus.alpha.control->AddFilterIds(CAN_FILTER_EXT, 0, 0x3FFFF800), VCI_OK);  // 2048 values
  EXPECT_EQ(bus.alpha.control->AddFilterIds(CAN_FILTER_EXT, 0x1000, 0x3FFFFFFF), VCI_E_OUTOFMEMORY);
  ASSERT_EQ(bus.alpha.control->SetAccFilter(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE),
            VCI_OK);
  ASSERT_EQ(bus.alpha.control->AddFilterIds(CAN_FILTER_STD, 0x123 << 1, 0xFFF), VCI_OK);
  step_ns(1'000'000);
  ASSERT_EQ(bus.alpha.control->ResetLine(), VCI_OK);
  CANLINESTATUS s = bus.alpha.line_status();
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  const auto infos = drain(bus.alpha.reader.p, false);
  ASSERT_EQ(infos.size(), 3u);  // START, STOP, RESET
  EXPECT_EQ(infos[2].abData[0], CAN_INFO_RESET);
  EXPECT_EQ(infos[2].dwTime, 0u);
  EXPECT_EQ(bus.alpha.control->StartLine(), VCI_E_INVALID_STATE);  // not initialized
  EXPECT_EQ(bus.alpha.control->AddFilterIds(CAN_FILTER_EXT, 0x1000, 0x3FFFFFFF), VCI_OK);  // room
  // The 11-bit list lost 0x123: with the acceptance filter closed, nothing passes.
  CANINITLINE init{kMode, 0, CAN_BT0_500KB, CAN_BT1_500KB};
  ASSERT_EQ(bus.alpha.control->InitLine(&init), VCI_OK);
  ASSERT_EQ(bus.alpha.control->SetAccFilter(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE),
            VCI_OK);
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  EXPECT_TRUE(exchange(bus.alpha, bus.beta, {0x123}).empty());
}

// 73: the dlc of an FD frame counts 12, 16, 20, 24, 32, 48, 64 bytes for 9..15, on the wire
// (the frames' durations) and at the receiver.
TEST(VciCppItems, Item73_TheFdDlcTable) {
  VciDaemon d(kFdAdapters);
  V2Adapter alpha("alpha", CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  V2Adapter beta("beta", CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA);
  const std::size_t lengths[] = {12, 16, 20, 24, 32, 48, 64};
  for (UINT8 dlc = 9; dlc <= 15; ++dlc) {
    CANMSG2 m = msg2(0x400 + dlc, {});
    m.uMsgInfo.Bits.edl = 1;
    m.uMsgInfo.Bits.dlc = dlc & 0x0FU;
    for (std::size_t k = 0; k < 64; ++k) {
      m.abData[k] = static_cast<UINT8>(dlc + k);
    }
    alpha.post(m);
  }
  step_ns(5'000'000);
  const auto got = drain<CANMSG2>(beta.reader.p, true);
  ASSERT_EQ(got.size(), 7u);
  int64_t end = -6'000;
  for (std::size_t k = 0; k < 7; ++k) {
    const UINT8 dlc = static_cast<UINT8>(9 + k);
    std::vector<uint8_t> bytes(lengths[k]);
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      bytes[i] = static_cast<uint8_t>(dlc + i);
    }
    end += 6'000 + fd_ns(0x400u + dlc, bytes, false);
    EXPECT_EQ(got[k].uMsgInfo.Bits.dlc, dlc);
    EXPECT_EQ(std::memcmp(got[k].abData, bytes.data(), bytes.size()), 0) << k;
    EXPECT_EQ(got[k].dwTime, static_cast<UINT32>(end / 1000)) << k;
  }
}

// 85: bTxFifoLoad is the transmit FIFO's fill in percent (with the line stopped, what is posted
// stays), bRxFifoLoad the receive FIFO's.
TEST(VciCppItems, Item85_FifoLoadsAreTheFillInPercent) {
  VciDaemon d;
  Adapter alpha("alpha");
  ASSERT_EQ(alpha.control->StopLine(), VCI_OK);
  UINT16 tx_capacity = 0;
  ASSERT_EQ(alpha.writer->GetCapacity(&tx_capacity), VCI_OK);
  UINT16 rx_capacity = 0;
  ASSERT_EQ(alpha.reader->GetCapacity(&rx_capacity), VCI_OK);
  const UINT16 posted = tx_capacity / 2;
  for (UINT16 k = 0; k < posted; ++k) {
    ASSERT_EQ(put(alpha.writer, one_byte(0x100, 1)), VCI_OK);
  }
  step_ns(1'000'000);
  CANCHANSTATUS s{};
  ASSERT_EQ(alpha.channel->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.bTxFifoLoad, posted * 100 / tx_capacity);
  EXPECT_EQ(s.bRxFifoLoad, 2 * 100 / rx_capacity);  // START and STOP
}

// 91: a frame sent with srr = 0 is seen by no v2 channel of the controller, SRRA or not.
TEST(VciCppItems, Item91_WithoutSrrNoV2ChannelSeesTheFrame) {
  TwoAdapters bus;
  V2Channel srra(bus.alpha.bal.p);
  ASSERT_NO_FATAL_FAILURE(srra.activate_with(64, 16, CAN_FILTER_PASS | CAN_FILTER_SRRA));
  CANMSG plain = one_byte(0x321, 1);  // from the v1 channel
  ASSERT_EQ(bus.alpha.writer->PutDataEntry(&plain), VCI_OK);
  CANMSG2 own = msg2(0x322, {2});  // from the v2 channel itself
  ASSERT_EQ(srra.writer->PutDataEntry(&own), VCI_OK);
  CANMSG echoed = one_byte(0x323, 3);  // with srr: the SRRA channel sees it
  echoed.uMsgInfo.Bits.srr = 1;
  ASSERT_EQ(bus.alpha.writer->PutDataEntry(&echoed), VCI_OK);
  step_ns(2'000'000);
  const auto got = the_one(drain<CANMSG2>(srra.reader.p, true));
  EXPECT_EQ(got.dwMsgId, 0x323u);
  EXPECT_EQ(got.uMsgInfo.Bits.srr, 0u);
  EXPECT_EQ(drain(bus.beta.reader.p, true).size(), 3u);  // all three were on the bus
}

// 93: the v1 control unit's filters work in INCL mode: seen through ICanControl2 once the v1
// interface is released (the line keeps running).
TEST(VciCppItems, Item93_TheV1ControlUnitFiltersInInclMode) {
  VciDaemon d;
  Adapter alpha("alpha");
  alpha.control->Release();
  alpha.control.p = nullptr;
  Ref<ICanControl2> control2;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanControl2, control2.pv()), VCI_OK);
  for (UINT8 w : {UINT8{CAN_FILTER_STD}, UINT8{CAN_FILTER_EXT}}) {
    UINT8 mode = 0;
    ASSERT_EQ(control2->GetFilterMode(w, &mode), VCI_OK);
    EXPECT_EQ(mode, CAN_FILTER_INCL);
  }
}

// 97: AddFilterIds with a pattern enters every identifier that matches it, RemFilterIds with
// the same pattern takes them all out again.
TEST(VciCppItems, Item97_FilterIdsByPattern) {
  TwoAdapters bus;
  ASSERT_NO_FATAL_FAILURE(bus.alpha.stop_with_list_only(CAN_FILTER_STD));
  ASSERT_EQ(bus.alpha.control->AddFilterIds(CAN_FILTER_STD, 0x200, 0xFF9), VCI_OK);  // 0x100..0x103
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  const auto got = exchange(bus.alpha, bus.beta, {0x0FF, 0x100, 0x101, 0x102, 0x103, 0x104});
  EXPECT_EQ(ids_of(got), (std::vector<UINT32>{0x100, 0x101, 0x102, 0x103}));
  for (const CANMSG& m : got) {
    EXPECT_EQ(m.uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_2);
  }
  ASSERT_EQ(bus.alpha.control->StopLine(), VCI_OK);
  ASSERT_EQ(bus.alpha.control->RemFilterIds(CAN_FILTER_STD, 0x200, 0xFF9), VCI_OK);
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  EXPECT_TRUE(exchange(bus.alpha, bus.beta, {0x100, 0x101, 0x102, 0x103}).empty());
}

// 98: with CODE_ALL / MASK_ALL the acceptance filter passes every identifier, whatever the list
// holds.
TEST(VciCppItems, Item98_CodeAllMaskAllPassesEverything) {
  TwoAdapters bus;
  ASSERT_NO_FATAL_FAILURE(bus.alpha.stop_and_pass_only(CAN_FILTER_STD, 0x123));
  ASSERT_EQ(bus.alpha.control->SetAccFilter(CAN_FILTER_STD, CAN_ACC_CODE_ALL, CAN_ACC_MASK_ALL),
            VCI_OK);
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  const auto got = exchange(bus.alpha, bus.beta, {0x000, 0x123, 0x7FF});
  EXPECT_EQ(ids_of(got), (std::vector<UINT32>{0x000, 0x123, 0x7FF}));
  for (const CANMSG& m : got) {
    EXPECT_EQ(m.uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_1);
  }
}

// 102: a v2 channel in LOCK mode gets no data frame, but the ERROR and STATUS messages do come.
TEST(VciCppItems, Item102_LockStillPassesErrorAndStatusMessages) {
  VciDaemon d;
  Adapter alpha("alpha");
  V2Channel lock(alpha.bal.p);
  ASSERT_NO_FATAL_FAILURE(lock.activate_with(256, 0, CAN_FILTER_LOCK));
  ASSERT_EQ(put(alpha.writer, one_byte(0x10, 1)), VCI_OK);  // alone: ACK errors, then ERRLIM
  step_ns(10'000'000);
  const auto v1 = drain(alpha.reader.p, false);
  const auto got = drain<CANMSG2>(lock.reader.p, false);
  ASSERT_EQ(got.size() + 1, v1.size());  // all of it but the START, which came before
  std::size_t errors = 0;
  std::size_t statuses = 0;
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_NE(got[k].uMsgInfo.Bytes.bType, CAN_MSGTYPE_DATA);
    EXPECT_EQ(got[k].uMsgInfo.Bytes.bType, v1[k + 1].uMsgInfo.Bytes.bType);
    EXPECT_EQ(got[k].dwTime, v1[k + 1].dwTime);
    errors += got[k].uMsgInfo.Bytes.bType == CAN_MSGTYPE_ERROR ? 1 : 0;
    statuses += got[k].uMsgInfo.Bytes.bType == CAN_MSGTYPE_STATUS ? 1 : 0;
  }
  EXPECT_GT(errors, 16u);
  EXPECT_EQ(statuses, 1u);
  Adapter beta("beta");  // now alpha's frame goes, and beta's data too: neither passes LOCK
  ASSERT_EQ(put(beta.writer, one_byte(0x20, 2)), VCI_OK);
  step_ns(10'000'000);
  EXPECT_EQ(drain(alpha.reader.p, true).size(), 1u);
  EXPECT_TRUE(drain<CANMSG2>(lock.reader.p, true).empty());
}

// 104: INFO, ERROR and STATUS messages carry afc = CAN_ACCEPT_ALWAYS; data frames the filter
// they passed.
TEST(VciCppItems, Item104_NonDataMessagesCarryAfcAlways) {
  VciDaemon d;
  Adapter alpha("alpha");
  ASSERT_EQ(put(alpha.writer, one_byte(0x10, 1)), VCI_OK);
  step_ns(10'000'000);
  Adapter beta("beta");
  step_ns(1'000'000);
  std::vector<UINT8> types;
  for (const CANMSG& x : drain(beta.reader.p, false)) {
    EXPECT_EQ(x.uMsgInfo.Bits.afc,
              x.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA ? CAN_ACCEPT_FILTER_1 : CAN_ACCEPT_ALWAYS);
  }
  for (const CANMSG& x : drain(alpha.reader.p, false)) {
    if (x.uMsgInfo.Bytes.bType != CAN_MSGTYPE_DATA) {
      EXPECT_EQ(x.uMsgInfo.Bits.afc, CAN_ACCEPT_ALWAYS) << int{x.uMsgInfo.Bytes.bType};
      if (types.empty() || types.back() != x.uMsgInfo.Bytes.bType) {
        types.push_back(x.uMsgInfo.Bytes.bType);
      }
    }
  }
  EXPECT_EQ(types, (std::vector<UINT8>{CAN_MSGTYPE_INFO, CAN_MSGTYPE_ERROR, CAN_MSGTYPE_STATUS,
                                       CAN_MSGTYPE_ERROR}));
}

// 107: SetFilterMode hands back the previous mode, or nothing when given NULL.
TEST(VciCppItems, Item107_SetFilterModeGivesThePreviousModeOrNothing) {
  VciDaemon d;
  Ref<IBalObject> bal;
  ASSERT_NO_FATAL_FAILURE(open_bal(vci_id_named("alpha"), bal));
  V2Channel ch2(bal.p);
  ASSERT_EQ(ch2.channel->Initialize(16, 0, 16, CAN_FILTER_INCL), VCI_OK);
  ASSERT_EQ(ch2.channel->SetFilterMode(CAN_FILTER_STD, CAN_FILTER_EXCL, nullptr), VCI_OK);
  UINT8 previous = 0;
  ASSERT_EQ(ch2.channel->SetFilterMode(CAN_FILTER_STD, CAN_FILTER_LOCK, &previous), VCI_OK);
  EXPECT_EQ(previous, CAN_FILTER_EXCL);
  UINT8 mode = 0;
  ASSERT_EQ(ch2.channel->GetFilterMode(CAN_FILTER_STD, &mode), VCI_OK);
  EXPECT_EQ(mode, CAN_FILTER_LOCK);
  ASSERT_EQ(ch2.channel->GetFilterMode(CAN_FILTER_EXT, &mode), VCI_OK);
  EXPECT_EQ(mode, CAN_FILTER_INCL);  // the other width unchanged
}

// 113: a high-priority message overtakes the other channel's waiting frames, never the frames
// ahead of it in its own FIFO.
TEST(VciCppItems, Item113_HighPriorityNeverOvertakesItsOwnFifo) {
  TwoAdapters bus;
  const Channel second(bus.alpha.socket.p, 64, 16, true);
  ASSERT_EQ(bus.alpha.control->StopLine(), VCI_OK);  // everything waits in the FIFOs
  for (UINT32 id : {0x301u, 0x302u}) {
    ASSERT_EQ(put(bus.alpha.writer, one_byte(id, 1)), VCI_OK);
  }
  CANMSG urgent = one_byte(0x303, 1);
  urgent.uMsgInfo.Bits.hpm = 1;
  ASSERT_EQ(bus.alpha.writer->PutDataEntry(&urgent), VCI_OK);
  for (UINT32 id : {0x401u, 0x402u}) {
    ASSERT_EQ(put(second.writer, one_byte(id, 1)), VCI_OK);
  }
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  step_ns(5'000'000);
  EXPECT_EQ(ids_of(drain(bus.beta.reader.p, true)),
            (std::vector<UINT32>{0x301, 0x401, 0x302, 0x303, 0x402}));
}

// 115: controllers at different rates do not hear each other: beta at 250 kbit/s gets no
// acknowledge from alpha at 500 kbit/s, and alpha receives no frame.
TEST(VciCppItems, Item115_DifferentRatesDoNotConnect) {
  TwoAdapters bus;
  ASSERT_NO_FATAL_FAILURE(bus.beta.reinit(CAN_BT0_250KB, CAN_BT1_250KB));
  ASSERT_EQ(bus.beta.control->StartLine(), VCI_OK);
  drain(bus.beta.reader.p, false);
  ASSERT_EQ(put(bus.beta.writer, one_byte(0x123, 1)), VCI_OK);
  step_ns(20'000'000);
  EXPECT_TRUE(drain(bus.alpha.reader.p, true).empty());
  std::size_t errors = 0;
  for (const CANMSG& x : drain(bus.beta.reader.p, false)) {
    errors += x.uMsgInfo.Bytes.bType == CAN_MSGTYPE_ERROR ? 1 : 0;
  }
  EXPECT_GT(errors, 16u);
}

// 120: AUTOBAUD is a feature of the emulated adapters; InitLine with it ignores the BTR fields
// (here those of about 4 kbit/s) and, started, the line listens for the rate (CAN_STATUS_ININIT)
// until traffic shows it (VciBehaviour.AnAutobaudLineFindsTheRateOfTheTrafficAndReceivesFromThen:
// the rate adopted and the frames from then on, with exact time stamps).
TEST(VciCppItems, Item120_AutobaudIsAFeatureAndIgnoresTheBtrFields) {
  VciDaemon d;
  const BalSocket<ICanSocket> alpha("alpha", IID_ICanSocket);
  CANCAPABILITIES caps{};
  ASSERT_EQ(alpha.socket->GetCapabilities(&caps), VCI_OK);
  EXPECT_EQ(caps.dwFeatures & CAN_FEATURE_AUTOBAUD, static_cast<UINT32>(CAN_FEATURE_AUTOBAUD));
  Ref<ICanControl> control;
  ASSERT_EQ(alpha.bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
  CANINITLINE init{CAN_OPMODE_STANDARD | CAN_OPMODE_AUTOBAUD, 0, 0xFF, 0xFF};
  ASSERT_EQ(control->InitLine(&init), VCI_OK);
  ASSERT_EQ(control->StartLine(), VCI_OK);
  CANLINESTATUS s{};
  ASSERT_EQ(control->GetLineStatus(&s), VCI_OK);
  EXPECT_EQ(s.dwStatus & CAN_STATUS_ININIT, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(s.bOpMode & CAN_OPMODE_AUTOBAUD, CAN_OPMODE_AUTOBAUD);
}

// 123: a cycle of 0 is refused; the longest cycle (dwCmsMaxTicks, 65535: the most a 16-bit
// wCycleTime holds) is taken.
TEST(VciCppItems, Item123_CycleTimeZeroIsRefusedTheMaximumTaken) {
  VciDaemon d;
  Adapter alpha("alpha");
  CANCAPABILITIES caps{};
  ASSERT_EQ(alpha.socket->GetCapabilities(&caps), VCI_OK);
  EXPECT_EQ(caps.dwCmsMaxTicks, 65535u);
  const Ref<ICanScheduler> list = alpha.scheduler();
  CANCYCLICTXMSG m = cyclic(0x100, 0);
  UINT32 index = 0;
  EXPECT_EQ(list->AddMessage(&m, &index), VCI_E_INVALIDARG);
  EXPECT_EQ(index, 0xFFFFFFFFu);
  m.wCycleTime = static_cast<UINT16>(caps.dwCmsMaxTicks);
  ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
  EXPECT_EQ(index, 0u);
}

// 128: INC_ID on a 29-bit identifier wraps from 2^29 - 1 to 0.
TEST(VciCppItems, Item128_IncIdWrapsAt2To29) {
  TwoAdapters bus;
  const Ref<ICanScheduler> list = bus.alpha.scheduler();
  CANCYCLICTXMSG m = cyclic(0x1FFFFFFE, 2);
  m.uMsgInfo.Bits.ext = 1;
  m.bIncrMode = CAN_CTXMSG_INC_ID;
  add_and_start(list.p, m, 3);
  ASSERT_EQ(list->Resume(), VCI_OK);
  step_ns(10'000'000);
  const auto got = drain(bus.beta.reader.p, true);
  EXPECT_EQ(ids_of(got), (std::vector<UINT32>{0x1FFFFFFE, 0x1FFFFFFF, 0}));
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].uMsgInfo.Bits.ext, 1u);
    EXPECT_EQ(got[k].dwTime, 2'000u * (k + 1) + end_of(got[k].dwMsgId, {0x11}, true)) << k;
  }
}

// 131: a removed entry reads EMPTY, and its index is refused until something is added there.
TEST(VciCppItems, Item131_ARemovedEntryIsEmptyAndItsIndexRefused) {
  VciDaemon d;
  Adapter alpha("alpha");
  const Ref<ICanScheduler> list = alpha.scheduler();
  CANCYCLICTXMSG m = cyclic(0x100, 10);
  UINT32 index = 0;
  ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
  ASSERT_EQ(list->AddMessage(&m, &index), VCI_OK);
  ASSERT_EQ(index, 1u);
  ASSERT_EQ(list->StartMessage(1, 0), VCI_OK);
  ASSERT_EQ(list->RemMessage(1), VCI_OK);
  CANSCHEDULERSTATUS s{};
  ASSERT_EQ(list->GetStatus(&s), VCI_OK);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_DONE);
  EXPECT_EQ(s.abMsgStat[1], CAN_CTXMSG_STAT_EMPTY);
  EXPECT_EQ(list->StartMessage(1, 0), VCI_E_INVALID_INDEX);
  EXPECT_EQ(list->StopMessage(1), VCI_E_INVALID_INDEX);
  EXPECT_EQ(list->RemMessage(1), VCI_E_INVALID_INDEX);
}

// 90: a v2 channel with SRRA gets the other channels' srr frames through its own filter, srr
// cleared.
TEST(VciCppItems, Item90_SrraEchoesPassTheChannelsFilter) {
  TwoAdapters bus;
  V2Channel srra(bus.alpha.bal.p);
  ASSERT_EQ(srra.channel->Initialize(64, 0, 16, CAN_FILTER_INCL | CAN_FILTER_SRRA), VCI_OK);
  ASSERT_EQ(srra.channel->SetAccFilter(CAN_FILTER_STD, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE),
            VCI_OK);
  ASSERT_EQ(srra.channel->AddFilterIds(CAN_FILTER_STD, 0x321 << 1, 0xFFF), VCI_OK);
  Ref<IFifoReader> reader;
  ASSERT_EQ(srra.channel->GetReader(reader.out()), VCI_OK);
  ASSERT_EQ(srra.channel->Activate(), VCI_OK);
  for (UINT32 id : {0x321u, 0x322u}) {
    CANMSG m = one_byte(id, 1);
    m.uMsgInfo.Bits.srr = 1;
    ASSERT_EQ(bus.alpha.writer->PutDataEntry(&m), VCI_OK);
  }
  step_ns(2'000'000);
  const auto got = the_one(drain<CANMSG2>(reader.p, true));
  EXPECT_EQ(got.dwMsgId, 0x321u);
  EXPECT_EQ(got.uMsgInfo.Bits.srr, 0u);
  EXPECT_EQ(got.uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_2);
  EXPECT_EQ(got.dwTime, end_of(0x321, {1}));
  EXPECT_EQ(ids_of(drain(bus.alpha.reader.p, true)), (std::vector<UINT32>{0x321, 0x322}));  // v1
}

// 100: a 29-bit identifier with the full mask 0x3FFFFFFF selects one (identifier, RTR) pair:
// not the remote frame of that identifier, not its neighbour.
TEST(VciCppItems, Item100_AFullMaskSelectsOneIdentifierAndRtrPair) {
  TwoAdapters bus;
  ASSERT_NO_FATAL_FAILURE(bus.alpha.stop_and_pass_only(CAN_FILTER_EXT, 0x1234567));
  ASSERT_EQ(bus.alpha.control->StartLine(), VCI_OK);
  drain(bus.alpha.reader.p, false);
  CANMSG data = one_byte(0x1234567, 1);
  data.uMsgInfo.Bits.ext = 1;
  CANMSG remote = data;
  remote.uMsgInfo.Bits.rtr = 1;
  CANMSG next = data;
  next.dwMsgId = 0x1234568;
  for (CANMSG* m : {&remote, &next, &data}) {
    ASSERT_EQ(bus.beta.writer->PutDataEntry(m), VCI_OK);
  }
  step_ns(2'000'000);
  const auto got = the_one(drain(bus.alpha.reader.p, true));
  EXPECT_EQ(got.dwMsgId, 0x1234567u);
  EXPECT_EQ(got.uMsgInfo.Bits.rtr, 0u);
  EXPECT_EQ(got.uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_2);
}

// 121: while one program holds a controller's cyclic list, another program's open is refused.
TEST(VciCppItems, Item121_AnotherProgramCannotOpenAHeldScheduler) {
  VciDaemon d;
  Adapter alpha("alpha");
  const Ref<ICanScheduler> list = alpha.scheduler();
  ASSERT_NO_FATAL_FAILURE(testing::with_alpha_bal_in_another_program(d, [](IBalObject* bal) {
    PVOID other = &other;
    if (bal->OpenSocket(0, IID_ICanScheduler, &other) != VCI_E_ACCESSDENIED || other != nullptr) {
      return 12;
    }
    other = &other;
    if (bal->OpenSocket(0, IID_ICanScheduler2, &other) != VCI_E_ACCESSDENIED) {
      return 13;
    }
    return 0;
  }));
}

}  // namespace
}  // namespace canemu
