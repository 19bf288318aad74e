// Checklist items of the VCI digest (§7) through the VCI "2" C API (libvcinpl2: CANMSG2,
// CANBTP) against a running canemud in stepped time, with exact time stamps; and the
// functions of vcinpl2.h that no other test of libvcinpl2 calls.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <cwchar>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci2_c_test_support.hpp"
#include "vci_lin_test_support.hpp"

namespace canemu {
namespace {

using testing::btp;
using testing::ControlUnit;
using testing::cyclic_data;
using testing::CyclicList;
using testing::drain;
using testing::end_of;
using testing::FdAdapter;
using testing::id_of;
using testing::ids_of;
using testing::kData;
using testing::kFd;
using testing::kMode;
using testing::kNominal;
using testing::msg;
using testing::SimClock;
using testing::VciDaemon;

// kFdAdapters and a third FD adapter, for listening.
const std::string kAdapters =
    testing::kFdAdapters +
    "\n[[device]]\nname = \"delta\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n";

UINT32 fd_end(uint32_t start_us, uint32_t id, std::vector<uint8_t> bytes, bool brs = false) {
  return end_of(start_us, *model::Frame::fd_frame(id, bytes, false, brs));
}
UINT32 classic_end(uint32_t start_us, uint32_t id, std::vector<uint8_t> bytes) {
  return end_of(start_us, *model::Frame::classic(id, bytes, false));
}

// ---------------------------------------------------------------- functions

// What vcinpl_general.h declares behaves in libvcinpl2 as in libvcinpl.
TEST(Vci2CFunctions, TheGeneralFunctionsAreThoseOfLibvcinpl) {
  EXPECT_EQ(vciInitialize(), VCI_OK);
  char narrow[VCI_MAX_ERRSTRLEN];
  ASSERT_NO_FATAL_FAILURE(testing::expect_wide_error_text_is_the_narrow_one(narrow));
  char caption[] = "two";
  ::testing::internal::CaptureStderr();
  vciDisplayErrorA(nullptr, caption, VCI_E_TIMEOUT);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), std::string("two: ") + narrow + "\n");
  wchar_t wide_caption[] = L"two";
  ::testing::internal::CaptureStderr();
  vciDisplayErrorW(nullptr, wide_caption, VCI_E_TIMEOUT);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), std::string("two: ") + narrow + "\n");

  char bad[] = "0123456789ABCDEG";
  ASSERT_NO_FATAL_FAILURE(testing::expect_luid_round_trip(vciLuidToCharA, vciCharToLuidA, bad));

  char gtext[39];
  wchar_t gwide[39];
  ASSERT_NO_FATAL_FAILURE(testing::expect_guid_text_both_ways(gtext, gwide));
  GUID gback{};
  EXPECT_EQ(vciCharToGuidA(nullptr, &gback), VCI_E_INVALIDARG);

  HANDLE e = nullptr;
  ASSERT_EQ(vciEventCreate(FALSE, FALSE, &e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);
  ASSERT_EQ(vciEventSignal(e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);  // auto reset
  ASSERT_EQ(vciEventSignal(e), VCI_OK);
  ASSERT_EQ(vciEventReset(e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);
  EXPECT_EQ(vciEventDelete(e), VCI_OK);
  EXPECT_EQ(vciEventSignal(e), VCI_E_INVHANDLE);
}

TEST(Vci2CFunctions, DevicesAreEnumeratedFoundAndDescribed) {
  VciDaemon d(kAdapters);
  EXPECT_EQ(vciInitialize(), VCI_OK);
  HANDLE e = nullptr;
  ASSERT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
  VCIDEVICEINFO first{};
  VCIDEVICEINFO info{};
  ASSERT_EQ(vciEnumDeviceNext(e, &first), VCI_OK);
  int count = 1;
  while (vciEnumDeviceNext(e, &info) == VCI_OK) {
    ++count;
  }
  EXPECT_EQ(count, 4);
  ASSERT_EQ(vciEnumDeviceReset(e), VCI_OK);
  ASSERT_EQ(vciEnumDeviceNext(e, &info), VCI_OK);
  EXPECT_EQ(std::memcmp(&info, &first, sizeof info), 0);
  EXPECT_EQ(vciEnumDeviceWaitEvent(e, 0), VCI_E_TIMEOUT);  // nothing changed
  EXPECT_EQ(vciEnumDeviceClose(e), VCI_OK);
  EXPECT_EQ(vciEnumDeviceReset(e), VCI_E_INVHANDLE);
  EXPECT_STREQ(first.Description, "USB-to-CAN FD (canemu alpha)");
  VCIID id{};
  ASSERT_EQ(vciFindDeviceByHwid(first.UniqueHardwareId.AsGuid, &id), VCI_OK);
  EXPECT_EQ(id.AsInt64, first.VciObjectId.AsInt64);
  // The FD adapters are one class: alpha, beta, delta (gamma is another).
  ASSERT_EQ(vciFindDeviceByClass(first.DeviceClass, 0, &id), VCI_OK);
  EXPECT_EQ(id.AsInt64, id_of("alpha").AsInt64);
  ASSERT_EQ(vciFindDeviceByClass(first.DeviceClass, 2, &id), VCI_OK);
  EXPECT_EQ(id.AsInt64, id_of("delta").AsInt64);
  EXPECT_EQ(vciFindDeviceByClass(first.DeviceClass, 3, &id), VCI_E_NO_MORE_ITEMS);
  ::unsetenv("CANEMU_VCI_DEVICE");
  ASSERT_EQ(vciSelectDeviceDlg(nullptr, &id), VCI_OK);
  EXPECT_EQ(id.AsInt64, first.VciObjectId.AsInt64);
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  VCIDEVICECAPS caps = testing::device_caps(dev);
  EXPECT_EQ(caps.BusCtrlCount, 1);
  EXPECT_EQ(caps.BusCtrlTypes[0], VCI_CAN_CTRL(CAN_CTRL_IFICFD));
  EXPECT_EQ(vciDeviceClose(dev), VCI_OK);
  ASSERT_EQ(vciDeviceOpen(id_of("gamma"), &dev), VCI_OK);
  caps = testing::device_caps(dev);
  EXPECT_EQ(caps.BusCtrlTypes[0], VCI_CAN_CTRL(CAN_CTRL_SJA1000));
  EXPECT_EQ(vciDeviceGetCaps(dev, nullptr), VCI_E_INVALIDARG);
  EXPECT_EQ(vciDeviceClose(dev), VCI_OK);
}

// A v2 channel's calls with CANMSG2: capabilities and status, the multi-message calls, the
// blocking reads and sends, the FIFO events.
TEST(Vci2CFunctions, TheChannelCallsMoveCanmsg2) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha", false);
  FdAdapter beta("beta");
  CANCAPABILITIES2 caps{};
  CANCAPABILITIES2 of_control{};
  ASSERT_EQ(canChannelGetCaps(alpha.channel, &caps), VCI_OK);
  ASSERT_EQ(canControlGetCaps(alpha.control, &of_control), VCI_OK);
  EXPECT_EQ(std::memcmp(&caps, &of_control, sizeof caps), 0);
  EXPECT_EQ(caps.wCtrlType, CAN_CTRL_IFICFD);
  EXPECT_EQ(canChannelGetCaps(alpha.control, &caps), VCI_E_INVHANDLE);
  CANCHANSTATUS2 s{};
  ASSERT_EQ(canChannelGetStatus(alpha.channel, &s), VCI_OK);
  EXPECT_TRUE(s.fActivated);
  EXPECT_FALSE(s.fRxOverrun);
  EXPECT_EQ(s.bRxFifoLoad, 0);
  EXPECT_EQ(s.sLineStatus.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  EXPECT_EQ(s.sLineStatus.sBtpFdr.dwBPS, 2'000'000u);
  EXPECT_EQ(canChannelWaitTxEvent(alpha.channel, 0), VCI_OK);  // an empty FIFO has room
  std::vector<CANMSG2> out{msg(0x101, {1}, true, true), msg(0x102, {2}), msg(0x103, {3})};
  UINT32 done = 0;
  ASSERT_EQ(canChannelPostMsgMult(alpha.channel, out.data(), 2, &done), VCI_OK);
  EXPECT_EQ(done, 2u);
  ASSERT_EQ(canChannelSendMsgMult(alpha.channel, 100, &out[2], 1, &done), VCI_OK);
  EXPECT_EQ(done, 1u);
  beta.post(msg(0x0FF, std::vector<uint8_t>(12, 0xA5), true, true));
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  SimClock clock;
  clock.to(2'000'000);
  EXPECT_EQ(canChannelWaitTxEvent(alpha.channel, 0), VCI_OK);  // canemud took them
  EXPECT_EQ(canChannelWaitRxEvent(alpha.channel, 0), VCI_OK);
  EXPECT_EQ(canChannelWaitRxEvent(alpha.channel, 0), VCI_E_TIMEOUT);
  // alpha: INFO START and beta's frame (it won the arbitration against 0x101 at t = 0).
  CANMSG2 m{};
  ASSERT_EQ(canChannelReadMessage(alpha.channel, 100, &m), VCI_OK);
  EXPECT_EQ(m.uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
  CANMSG2 in[4] = {};
  ASSERT_EQ(canChannelReadMsgMult(alpha.channel, 100, in, 4, &done), VCI_OK);
  ASSERT_EQ(done, 1u);
  EXPECT_EQ(in[0].dwMsgId, 0x0FFu);
  EXPECT_EQ(in[0].uMsgInfo.Bits.dlc, 9u);
  EXPECT_EQ(in[0].abData[11], 0xA5);
  const UINT32 first_end =
      end_of(0, *model::Frame::fd_frame(0x0FF, std::vector<uint8_t>(12, 0xA5), false, true));
  EXPECT_EQ(in[0].dwTime, first_end);
  EXPECT_EQ(canChannelReadMessage(alpha.channel, 0, &m), VCI_E_TIMEOUT);  // nothing within 0 ms
  // beta: INFO START, then alpha's three after its own.
  ASSERT_EQ(canChannelPeekMsgMult(beta.channel, in, 4, &done), VCI_OK);
  ASSERT_EQ(done, 4u);
  EXPECT_EQ(in[0].uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
  EXPECT_EQ(ids_of(std::vector<CANMSG2>(in + 1, in + 4)),
            (std::vector<uint32_t>{0x101, 0x102, 0x103}));
  const UINT32 second_end = fd_end(first_end + 6, 0x101, {1}, true);
  EXPECT_EQ(in[1].dwTime, second_end);
  EXPECT_EQ(in[1].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(in[2].dwTime, classic_end(second_end + 6, 0x102, {2}));
  EXPECT_EQ(canChannelPeekMsgMult(beta.channel, in, 4, &done), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(done, 0u);
  // A blocking read gives up after its time, counted in simulated time.
  HRESULT hr = VCI_E_UNEXPECTED;
  testing::step_while([&] {
    CANMSG2 x;
    hr = canChannelReadMessage(beta.channel, 5, &x);
  });
  EXPECT_EQ(hr, VCI_E_TIMEOUT);
}

// Channel filter lists: RemFilterIds takes back what AddFilterIds added.
TEST(Vci2CFunctions, RemFilterIdsTakesIdsOffAChannelsList) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha", false);
  FdAdapter beta("beta");
  HANDLE ch = nullptr;
  ASSERT_EQ(canChannelOpen(alpha.device, 0, FALSE, &ch), VCI_OK);
  ASSERT_EQ(canChannelInitialize(ch, 64, 1, 0, 0, 16, CAN_FILTER_INCL), VCI_OK);
  ASSERT_EQ(canChannelSetAccFilter(ch, FALSE, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE), VCI_OK);
  ASSERT_EQ(canChannelAddFilterIds(ch, FALSE, 0x120 << 1, 0xFF9), VCI_OK);  // 0x120..0x123
  ASSERT_EQ(canChannelRemFilterIds(ch, FALSE, 0x122 << 1, 0xFFF), VCI_OK);
  ASSERT_EQ(canChannelActivate(ch, TRUE), VCI_OK);
  EXPECT_EQ(canChannelRemFilterIds(ch, FALSE, 0x121 << 1, 0xFFF), VCI_E_INVALID_STATE);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  for (uint32_t id = 0x11F; id <= 0x124; ++id) {
    beta.post(msg(id, {}));
  }
  SimClock clock;
  clock.to(2'000'000);
  EXPECT_EQ(ids_of(drain(ch)), (std::vector<uint32_t>{0x120, 0x121, 0x123}));
  EXPECT_EQ(drain(alpha.channel).size(), 6u);
  canChannelClose(ch);
}

// Traffic of 500 kbit/s / 2 Mbit/s on the FD bus; delta tries a table and finds the second
// entry. The call blocks while simulated time runs, so another thread steps it.
TEST(Vci2CFunctions, DetectBitrateFindsTheEntryOfTheTraffic) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha");
  FdAdapter beta("beta");
  const CyclicList list(alpha.device);
  list.send_without_end(cyclic_data<CANCYCLICTXMSG2>(0x2A0, 1, 1));
  const ControlUnit delta("delta");
  CANBTP sdr[] = {btp(250000, 30, 2), kNominal};
  CANBTP fdr[] = {btp(1000000, 18, 2), kData};
  UINT32 found = 99;
  EXPECT_EQ(canControlDetectBitrate(delta.control, kMode, kFd, 100, 0, sdr, fdr, &found),
            VCI_E_INVALIDARG);
  HRESULT hr = VCI_E_UNEXPECTED;
  testing::step_while(
      [&] { hr = canControlDetectBitrate(delta.control, kMode, kFd, 100, 2, sdr, fdr, &found); });
  EXPECT_EQ(hr, VCI_OK);
  EXPECT_EQ(found, 1u);
}

// ---------------------------------------------------------------- checklist items

TEST(Vci2CItems, Item56_NewChannelIsInactiveUntilActivate) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha", true, kFd, false);
  FdAdapter beta("beta");
  SimClock clock;
  beta.post(msg(0x123, {1, 2, 3}, true, true));
  clock.to(1'000'000);
  CANCHANSTATUS2 s{};
  ASSERT_EQ(canChannelGetStatus(alpha.channel, &s), VCI_OK);
  EXPECT_FALSE(s.fActivated);
  EXPECT_EQ(s.sLineStatus.dwStatus, 0u);
  EXPECT_TRUE(drain(alpha.channel, false).empty());
  ASSERT_EQ(canChannelActivate(alpha.channel, TRUE), VCI_OK);
  beta.post(msg(0x124, {4}, true, true));
  clock.to(2'000'000);
  const auto got = drain(alpha.channel, false);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x124u);
  EXPECT_EQ(got[0].dwTime, fd_end(1000, 0x124, {4}, true));
}

// Without EXTDATA an edl frame is dropped; without FASTDATA an fdr frame is; what the modes
// allow goes out.
TEST(Vci2CItems, Item74_FdFramesAreDroppedWithoutTheirExtendedModes) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha", true, CAN_EXMODE_EXTDATA);
  FdAdapter beta("beta", true, CAN_EXMODE_EXTDATA);
  alpha.post(msg(0x101, {1, 2, 3}, true, true));  // fdr: no FASTDATA
  CANMSG2 fdr_alone = msg(0x102, {1});
  fdr_alone.uMsgInfo.Bits.fdr = 1;
  alpha.post(fdr_alone);
  alpha.post(msg(0x103, std::vector<uint8_t>(12, 7), true));  // edl without fdr: allowed
  alpha.post(msg(0x104, {4}));
  SimClock clock;
  clock.to(2'000'000);
  auto got = drain(beta.channel);
  ASSERT_EQ(ids_of(got), (std::vector<uint32_t>{0x103, 0x104}));
  // An FD frame without the rate switch: all of it at the nominal rate.
  const UINT32 first = end_of(0, *model::Frame::fd_frame(0x103, std::vector<uint8_t>(12, 7)));
  EXPECT_EQ(got[0].dwTime, first);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 0u);
  EXPECT_EQ(got[1].dwTime, classic_end(first + 6, 0x104, {4}));
  // Classic lines on both: edl frames are dropped too.
  for (const FdAdapter* a : {&alpha, &beta}) {
    ASSERT_EQ(canControlReset(a->control), VCI_OK);
    a->init(CAN_EXMODE_DISABLED);
    ASSERT_EQ(canControlStart(a->control, TRUE), VCI_OK);
  }
  alpha.post(msg(0x201, std::vector<uint8_t>(12, 7), true));
  alpha.post(msg(0x202, {2}));
  clock.to(4'000'000);
  got = drain(beta.channel);
  ASSERT_EQ(ids_of(got), (std::vector<uint32_t>{0x202}));
  EXPECT_EQ(got[0].dwTime, classic_end(2000, 0x202, {2}));
}

TEST(Vci2CItems, Item75_RtrIsIgnoredWhenEdlOrFdrIsSet) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha");
  FdAdapter beta("beta");
  CANMSG2 edl = msg(0x101, {1, 2, 3}, true);
  edl.uMsgInfo.Bits.rtr = 1;
  CANMSG2 fdr = msg(0x102, {4, 5}, true, true);
  fdr.uMsgInfo.Bits.edl = 0;  // fdr alone asks for an FD frame with the rate switch
  fdr.uMsgInfo.Bits.rtr = 1;
  alpha.post(edl);
  alpha.post(fdr);
  SimClock clock;
  clock.to(2'000'000);
  const auto got = drain(beta.channel);
  ASSERT_EQ(got.size(), 2u);
  const UINT32 first = fd_end(0, 0x101, {1, 2, 3});
  EXPECT_EQ(got[0].dwMsgId, 0x101u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.rtr, 0u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.dlc, 3u);
  EXPECT_EQ(got[0].abData[2], 3);
  EXPECT_EQ(got[0].dwTime, first);
  EXPECT_EQ(got[1].dwMsgId, 0x102u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.rtr, 0u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(got[1].abData[1], 5);
  EXPECT_EQ(got[1].dwTime, fd_end(first + 6, 0x102, {4, 5}, true));
}

// One tick is 1 / (dwTscClkFreq / dwTscDivisor) s.
TEST(Vci2CItems, Item77_TimeStampsCountDwTscClkFreqOverDwTscDivisorTicksPerSecond) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha");
  FdAdapter beta("beta");
  CANCAPABILITIES2 caps{};
  ASSERT_EQ(canChannelGetCaps(alpha.channel, &caps), VCI_OK);
  const uint64_t per_second = caps.dwTscClkFreq / caps.dwTscDivisor;
  EXPECT_EQ(per_second, 1'000'000u);
  SimClock clock;
  beta.post(msg(0x123, {1}));
  clock.to(1'000'000'000);
  beta.post(msg(0x123, {1}));
  clock.to(2'000'000'000);
  const auto got = drain(alpha.channel);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].dwTime, classic_end(0, 0x123, {1}));
  EXPECT_EQ(got[1].dwTime - got[0].dwTime, per_second);
}

// The control unit's list passes 0x123 only; a PASS channel sees no more than that.
TEST(Vci2CItems, Item105_AFrameTheControlUnitFilterBlocksReachesNoChannel) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha", false);
  FdAdapter beta("beta");
  ASSERT_EQ(canControlSetAccFilter(alpha.control, FALSE, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE),
            VCI_OK);
  ASSERT_EQ(canControlAddFilterIds(alpha.control, FALSE, 0x120 << 1, 0xFF9), VCI_OK);
  ASSERT_EQ(canControlRemFilterIds(alpha.control, FALSE, 0x121 << 1, 0xFFF), VCI_OK);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  EXPECT_EQ(canControlAddFilterIds(alpha.control, FALSE, 0x124 << 1, 0xFFF), VCI_E_INVALID_STATE);
  for (uint32_t id = 0x11F; id <= 0x124; ++id) {
    beta.post(msg(id, {}));
  }
  SimClock clock;
  clock.to(2'000'000);
  const auto got = drain(alpha.channel);
  EXPECT_EQ(ids_of(got), (std::vector<uint32_t>{0x120, 0x122, 0x123}));
  for (const CANMSG2& m : got) {
    EXPECT_EQ(m.uMsgInfo.Bits.afc, CAN_ACCEPT_FILTER_2);
  }
}

// `b` with its `field` set to `value`.
template <class Field, class Value>
CANBTP with(CANBTP b, Field CANBTP::*field, Value value) {
  b.*field = static_cast<Field>(value);
  return b;
}

// Raw CANBTP values are checked against the capability ranges of each phase.
TEST(Vci2CItems, Item117_RawTimingOutsideTheCapabilityRangesIsRejected) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha", false);
  CANCAPABILITIES2 caps{};
  ASSERT_EQ(canControlGetCaps(alpha.control, &caps), VCI_OK);
  EXPECT_EQ(caps.sSdrRangeMin.dwBPS, 1u);
  EXPECT_EQ(caps.sSdrRangeMax.dwBPS, 1024u);
  EXPECT_EQ(caps.sSdrRangeMax.wTS1, 256);
  EXPECT_EQ(caps.sSdrRangeMin.wTS2, 2);
  EXPECT_EQ(caps.sFdrRangeMax.wTS1, 32);
  auto init = [&](CANBTP n, CANBTP f) {
    return canControlInitialize(alpha.control, kMode, kFd, CAN_FILTER_INCL, CAN_FILTER_INCL, 2048,
                                2048, &n, &f);
  };
  // 500 kbit/s as raw values: prescaler 10, 1 + 13 + 2 quanta; 2 Mbit/s: 4, 1 + 7 + 2.
  const CANBTP nominal{CAN_BTMODE_RAW, 10, 13, 2, 1, 0};
  const CANBTP data{CAN_BTMODE_RAW, 4, 7, 2, 1, 0};
  EXPECT_EQ(init(nominal, data), VCI_OK);
  CANLINESTATUS2 s{};
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  EXPECT_EQ(s.sBtpSdr.dwBPS, 10u);
  EXPECT_EQ(s.sBtpFdr.wTS1, 7);
  // One value past its range at a time, in either phase: refused.
  const struct {
    CANBTP nominal;
    CANBTP data;
  } refused[] = {
      {with(nominal, &CANBTP::dwBPS, caps.sSdrRangeMax.dwBPS + 1), data},
      {with(nominal, &CANBTP::wTS1, caps.sSdrRangeMax.wTS1 + 1), data},
      {with(nominal, &CANBTP::wTS2, caps.sSdrRangeMin.wTS2 - 1), data},
      {nominal, with(data, &CANBTP::wTS1, caps.sFdrRangeMax.wTS1 + 1)},
      {nominal, with(data, &CANBTP::dwBPS, caps.sFdrRangeMax.dwBPS + 1)},
  };
  for (std::size_t k = 0; k < std::size(refused); ++k) {
    EXPECT_EQ(init(refused[k].nominal, refused[k].data), VCI_E_INVALIDARG) << "case " << k;
  }
  // At the edges of the ranges it is taken.
  CANBTP n = nominal;
  n.wTS1 = caps.sSdrRangeMax.wTS1;
  n.wTS2 = caps.sSdrRangeMax.wTS2;
  EXPECT_EQ(init(n, data), VCI_OK);
}

// 116 with bit/s timings the clock does not make as they are (issue 34): the controller takes
// the nearest timing it has (docs/vci.md, "Bit timing in bit/s form"), the line status shows
// it, and such a line talks to one initialized with the exact presets. python-can's ixxat
// presets for 500 kbit/s / 2 Mbit/s, the guide's 8/2 example, and 80/20.
TEST(Vci2CItems, Item116_BitPerSecondTimingsTakeTheNearestTimingAndShowIt) {
  VciDaemon d(kAdapters);
  const CANBTP pc_nominal{0, 500000, 6400, 1600, 1600, 0};
  const CANBTP pc_data{0, 2000000, 1600, 400, 400, 1600};
  testing::Line alpha("alpha", kMode, kFd, pc_nominal, pc_data);
  FdAdapter beta("beta");
  CANLINESTATUS2 s{};
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  // 160 quanta of one 80 MHz clock (80 %), and 40 in the data phase; SJW and TDO in quanta.
  const CANBTP shown_nominal{0, 500000, 128, 32, 32, 0};
  const CANBTP shown_data{0, 2000000, 32, 8, 8, 32};
  EXPECT_EQ(std::memcmp(&s.sBtpSdr, &shown_nominal, sizeof(CANBTP)), 0)
      << s.sBtpSdr.dwBPS << " " << s.sBtpSdr.wTS1 << "/" << s.sBtpSdr.wTS2 << " " << s.sBtpSdr.wSJW;
  EXPECT_EQ(std::memcmp(&s.sBtpFdr, &shown_data, sizeof(CANBTP)), 0)
      << s.sBtpFdr.dwBPS << " " << s.sBtpFdr.wTS1 << "/" << s.sBtpFdr.wTS2 << " " << s.sBtpFdr.wSJW
      << " " << s.sBtpFdr.wTDO;
  // FD frames with the rate switch both ways, at the same instants as between exact presets.
  std::vector<uint8_t> twelve{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  SimClock clock;
  alpha.post(msg(0x123, twelve, true, true));
  clock.to(2'000'000);
  auto got = drain(beta.channel);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x123u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(std::memcmp(got[0].abData, twelve.data(), twelve.size()), 0);
  EXPECT_EQ(got[0].dwTime, fd_end(0, 0x123, twelve, true));
  beta.post(msg(0x321, twelve, true, true));
  clock.to(4'000'000);
  got = drain(alpha.channel);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x321u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(got[0].dwTime, fd_end(2000, 0x321, twelve, true));

  // The guide's 8/2 at 500 kbit/s on the FD controller: 10 quanta of 16 clocks, as asked.
  CANBTP guide{0, 500000, 8, 2, 1, 0};
  ASSERT_EQ(testing::init_classic(alpha.control, guide), VCI_OK);
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  EXPECT_EQ(std::memcmp(&s.sBtpSdr, &guide, sizeof(CANBTP)), 0);
  // 80/20 with SJW 20: 80 quanta of 2 clocks, SJW 16.
  CANBTP eighty{0, 500000, 80, 20, 20, 0};
  ASSERT_EQ(testing::init_classic(alpha.control, eighty), VCI_OK);
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  const CANBTP eighty_shown{0, 500000, 64, 16, 16, 0};
  EXPECT_EQ(std::memcmp(&s.sBtpSdr, &eighty_shown, sizeof(CANBTP)), 0);

  // The SJA1000 (8 MHz, 16 clocks a bit at 500 kbit/s): 8/2 becomes 13/3 (81.25 %), SJW 2.
  const testing::ControlUnit gamma("gamma");
  ASSERT_EQ(testing::init_classic(gamma.control, guide), VCI_OK);
  ASSERT_EQ(canControlGetStatus(gamma.control, &s), VCI_OK);
  const CANBTP sja_shown{0, 500000, 13, 3, 2, 0};
  EXPECT_EQ(std::memcmp(&s.sBtpSdr, &sja_shown, sizeof(CANBTP)), 0)
      << s.sBtpSdr.dwBPS << " " << s.sBtpSdr.wTS1 << "/" << s.sBtpSdr.wTS2 << " " << s.sBtpSdr.wSJW;
  // A rate the clock cannot come within 0.5 % of is still refused: 4 kbit/s (the slowest is
  // 8 MHz / (64 x 25) = 5 kbit/s).
  CANBTP slow{0, 4000, 14, 2, 1, 0};
  EXPECT_EQ(testing::init_classic(gamma.control, slow), VCI_E_INVALIDARG);
}

// Issue 34: a data message whose identifier does not fit its format (above 7FFh standard,
// above 29 bits extended) is refused by the library when it is posted, VCI_E_INVALIDARG with
// vciFormatError naming it, and nothing is queued (docs/vci.md); the largest identifiers of
// each format go out.
TEST(Vci2CItems, IdentifiersThatDoNotFitTheirFormatAreRefusedWhenPosted) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha");
  FdAdapter beta("beta");
  CANMSG2 standard = msg(0x800, {0x11});
  EXPECT_EQ(canChannelPostMessage(alpha.channel, &standard), VCI_E_INVALIDARG);
  char text[VCI_MAX_ERRSTRLEN];
  vciFormatError(VCI_E_INVALIDARG, text, sizeof text);
  EXPECT_STREQ(text,
               "invalid argument (identifier 0x800 does not fit 11 bits (ext = 0: at most 0x7FF); "
               "the message was not queued)");
  CANMSG2 extended = msg(0x20000000, {0x22});
  extended.uMsgInfo.Bits.ext = 1;
  EXPECT_EQ(canChannelPostMessage(alpha.channel, &extended), VCI_E_INVALIDARG);
  EXPECT_EQ(canChannelSendMessage(alpha.channel, 100, &extended), VCI_E_INVALIDARG);
  // PostMsgMult queues what comes before the first refused message, and says how many.
  CANMSG2 batch[3] = {msg(0x7FF, {0x33}), msg(0xFFFFFFFF, {0x44}), msg(0x100, {0x55})};
  batch[0].uMsgInfo.Bits.ext = 0;
  UINT32 done = 99;
  EXPECT_EQ(canChannelPostMsgMult(alpha.channel, batch, 3, &done), VCI_OK);
  EXPECT_EQ(done, 1u);
  EXPECT_EQ(canChannelPostMsgMult(alpha.channel, batch + 1, 2, &done), VCI_E_INVALIDARG);
  EXPECT_EQ(done, 0u);
  CANMSG2 largest = msg(0x1FFFFFFF, {0x66});
  largest.uMsgInfo.Bits.ext = 1;
  EXPECT_EQ(canChannelPostMessage(alpha.channel, &largest), VCI_OK);
  SimClock clock;
  clock.to(2'000'000);
  const auto got = drain(beta.channel);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].dwMsgId, 0x7FFu);
  EXPECT_EQ(got[0].uMsgInfo.Bits.ext, 0u);
  EXPECT_EQ(got[1].dwMsgId, 0x1FFFFFFFu);
  EXPECT_EQ(got[1].uMsgInfo.Bits.ext, 1u);
  // Only data messages carry an identifier that must fit.
  CANMSG2 error_type = msg(0xFFFFFFFF, {});
  error_type.uMsgInfo.Bytes.bType = CAN_MSGTYPE_ERROR;
  EXPECT_EQ(canChannelPostMessage(alpha.channel, &error_type), VCI_OK);
}

// The v2 cyclic list: its status carries the line's, FD frames go out, Suspend stops it,
// Resume continues, StopMessage keeps an entry, Reset empties the list.
TEST(Vci2CItems, Item130_SuspendStopsResumeContinuesAndResetEmptiesTheList) {
  VciDaemon d(kAdapters);
  FdAdapter alpha("alpha");
  FdAdapter beta("beta");
  const CyclicList list(alpha.device);
  CANCAPABILITIES2 caps{};
  ASSERT_EQ(canSchedulerGetCaps(list, &caps), VCI_OK);
  ASSERT_EQ(caps.dwCmsClkFreq / caps.dwCmsDivisor, 1000u);  // ticks of 1 ms
  CANCYCLICTXMSG2 m = cyclic_data<CANCYCLICTXMSG2>(0x100, 2);
  m.uMsgInfo.Bits.edl = 1;
  m.uMsgInfo.Bits.fdr = 1;
  m.uMsgInfo.Bits.dlc = 9;  // 12 bytes
  std::memset(m.abData, 0x5A, 12);
  UINT32 index = 99;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  EXPECT_EQ(index, 0u);
  m.dwMsgId = 0x200;
  ASSERT_EQ(canSchedulerAddMessage(list, &m, &index), VCI_OK);
  EXPECT_EQ(index, 1u);
  ASSERT_EQ(canSchedulerRemMessage(list, 1), VCI_OK);
  EXPECT_EQ(canSchedulerStartMessage(list, 1, 0), VCI_E_INVALID_INDEX);
  ASSERT_EQ(canSchedulerStartMessage(list, 0, 0), VCI_OK);
  CANSCHEDULERSTATUS2 s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_BUSY);
  EXPECT_EQ(s.abMsgStat[1], CAN_CTXMSG_STAT_EMPTY);
  EXPECT_EQ(s.sLineStatus.dwStatus, 0u);
  EXPECT_EQ(s.sLineStatus.sBtpFdr.dwBPS, 2'000'000u);
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  SimClock clock;
  clock.to(5'000'000);
  ASSERT_EQ(canSchedulerActivate(list, FALSE), VCI_OK);
  s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_BUSY);
  clock.to(11'000'000);
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  clock.to(15'500'000);
  ASSERT_EQ(canSchedulerStopMessage(list, 0), VCI_OK);
  s = list.status();
  EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_RUNNING);
  EXPECT_EQ(s.abMsgStat[0], CAN_CTXMSG_STAT_DONE);
  clock.to(20'000'000);
  list.expect_reset_empties_it();
  ASSERT_EQ(canSchedulerActivate(list, TRUE), VCI_OK);
  clock.to(30'000'000);
  const auto got = drain(beta.channel);
  std::vector<UINT32> times;
  for (const CANMSG2& f : got) {
    times.push_back(f.dwTime);
    EXPECT_EQ(f.uMsgInfo.Bits.fdr, 1u);
    EXPECT_EQ(f.abData[11], 0x5A);
  }
  const auto frame = model::Frame::fd_frame(0x100, std::vector<uint8_t>(12, 0x5A), false, true);
  std::vector<UINT32> want;
  for (uint32_t ms : {2, 4, 13, 15}) {
    want.push_back(end_of(ms * 1000, *frame));
  }
  EXPECT_EQ(times, want);
}

// ---------------------------------------------------------------- LIN

// The LIN calls of libvcinpl2 not used elsewhere: capabilities, status, reset, single reads.
TEST(Vci2CLin, CapabilitiesStatusResetAndSingleReads) {
  using namespace testing;
  VciDaemon d(kLinAdapters);
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  HANDLE control = nullptr;
  HANDLE monitor = nullptr;
  ASSERT_EQ(linControlOpen(dev, kLinNo, &control), VCI_OK);
  ASSERT_EQ(linMonitorOpen(dev, kLinNo, FALSE, &monitor), VCI_OK);
  ASSERT_EQ(linMonitorInitialize(monitor, 16, 1), VCI_OK);
  ASSERT_EQ(linMonitorActivate(monitor, TRUE), VCI_OK);
  LINCAPABILITIES caps{};
  ASSERT_EQ(linControlGetCaps(control, &caps), VCI_OK);
  EXPECT_EQ(caps.dwFeatures, 0x3Fu);
  EXPECT_EQ(caps.dwClockFreq, 1'000'000u);
  EXPECT_EQ(caps.dwTscDivisor, 1u);
  LINCAPABILITIES of_monitor{};
  ASSERT_EQ(linMonitorGetCaps(monitor, &of_monitor), VCI_OK);
  EXPECT_EQ(std::memcmp(&caps, &of_monitor, sizeof caps), 0);
  ASSERT_EQ(linControlInitialize(control, LIN_OPMODE_MASTER, kRate), VCI_OK);
  LINLINESTATUS s{};
  ASSERT_EQ(linControlGetStatus(control, &s), VCI_OK);
  EXPECT_EQ(s.bOpMode, LIN_OPMODE_MASTER);
  EXPECT_EQ(s.wBitrate, kRate);
  EXPECT_EQ(s.dwStatus, LIN_STATUS_ININIT);
  SimClock clock;
  clock.to(1'000'000);
  ASSERT_EQ(linControlStart(control, TRUE), VCI_OK);
  LINMONITORSTATUS ms{};
  ASSERT_EQ(linMonitorGetStatus(monitor, &ms), VCI_OK);
  EXPECT_TRUE(ms.fActivated);
  EXPECT_EQ(ms.sLineStatus.dwStatus, 0u);
  ASSERT_EQ(linControlReset(control), VCI_OK);
  ASSERT_EQ(linControlGetStatus(control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus, LIN_STATUS_ININIT);
  LINMSG m{};
  ASSERT_EQ(linMonitorPeekMessage(monitor, &m), VCI_OK);
  EXPECT_EQ(text_of(m), event_text(1000, LIN_MSGTYPE_INFO, LIN_INFO_START));
  ASSERT_EQ(linMonitorReadMessage(monitor, 100, &m), VCI_OK);
  EXPECT_EQ(text_of(m), event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_RESET));
  EXPECT_EQ(linMonitorPeekMessage(monitor, &m), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(linMonitorClose(monitor), VCI_OK);
  EXPECT_EQ(linControlClose(control), VCI_OK);
  vciDeviceClose(dev);
}

}  // namespace
}  // namespace canemu
