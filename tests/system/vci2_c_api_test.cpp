// The VCI "2" C API (libvcinpl2: CANMSG2, CANBTP) against a real canemud in stepped time: CAN
// FD adapters, bit timing as CANBTP, filters and self reception on v2 channels.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
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
using testing::device_named;
using testing::drain;
using testing::end_of;
using testing::FdAdapter;
using testing::kData;
using testing::kFd;
using testing::kFdAdapters;
using testing::kMode;
using testing::kNominal;
using testing::msg;
using testing::step_ns;
using testing::VciDaemon;

HANDLE channel_on(HANDLE dev, UINT32 filter_size, UINT8 filter_mode, bool activate = true) {
  HANDLE ch = nullptr;
  EXPECT_EQ(canChannelOpen(dev, 0, FALSE, &ch), VCI_OK);
  EXPECT_EQ(canChannelInitialize(ch, 256, 1, 64, 1, filter_size, filter_mode), VCI_OK);
  if (activate) {
    EXPECT_EQ(canChannelActivate(ch, TRUE), VCI_OK);
  }
  return ch;
}

TEST(Vci2CApi, FdFramesWithTheRateSwitchArriveAtTheirExactEnd) {
  VciDaemon d(kFdAdapters);
  FdAdapter alpha("alpha");
  FdAdapter beta("beta");
  std::vector<uint8_t> twelve{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  alpha.post(msg(0x123, twelve, true, true));
  step_ns(2'000'000);
  const auto got = drain(beta.channel);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x123u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.edl, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.fdr, 1u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.esi, 0u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.dlc, 9u);  // 12 bytes
  EXPECT_EQ(std::memcmp(got[0].abData, twelve.data(), twelve.size()), 0);
  EXPECT_EQ(got[0].dwTime, end_of(0, *model::Frame::fd_frame(0x123, twelve, false, true)));
}

TEST(Vci2CApi, CapabilitiesAndLineStatusDescribeTheFdController) {
  VciDaemon d(kFdAdapters);
  FdAdapter alpha("alpha", false);
  CANCAPABILITIES2 caps{};
  ASSERT_EQ(canControlGetCaps(alpha.control, &caps), VCI_OK);
  EXPECT_EQ(caps.wCtrlType, CAN_CTRL_IFICFD);
  EXPECT_EQ(caps.wBusCoupling, CAN_BUSC_HIGHSPEED);
  EXPECT_EQ(caps.dwFeatures & (CAN_FEATURE_EXTDATA | CAN_FEATURE_FASTDATA),
            static_cast<UINT32>(CAN_FEATURE_EXTDATA | CAN_FEATURE_FASTDATA));
  EXPECT_EQ(caps.dwCanClkFreq, 80'000'000u);
  EXPECT_EQ(caps.dwTscClkFreq, 1'000'000u);
  EXPECT_EQ(caps.dwTscDivisor, 1u);
  CANLINESTATUS2 s{};
  ASSERT_EQ(canControlGetStatus(alpha.control, &s), VCI_OK);
  EXPECT_EQ(s.bOpMode, kMode);
  EXPECT_EQ(s.bExMode, kFd);
  EXPECT_EQ(s.sBtpSdr.dwBPS, 500000u);
  EXPECT_EQ(s.sBtpFdr.dwBPS, 2000000u);
  EXPECT_EQ(s.dwStatus, static_cast<UINT32>(CAN_STATUS_ININIT));
  // The classic adapter through the same interface: no FD modes.
  const testing::ControlUnit gamma("gamma");
  ASSERT_EQ(canControlGetCaps(gamma.control, &caps), VCI_OK);
  EXPECT_EQ(caps.wCtrlType, CAN_CTRL_SJA1000);
  EXPECT_EQ(caps.dwFeatures & CAN_FEATURE_EXTDATA, 0u);
  CANBTP n = kNominal;
  CANBTP f = kData;
  EXPECT_EQ(canControlInitialize(gamma.control, kMode, kFd, CAN_FILTER_INCL, CAN_FILTER_INCL, 2048,
                                 2048, &n, &f),
            VCI_E_INVALIDARG);
  CANBTP classic = btp(500000, 14, 2);  // 16 quanta of 125 ns: BTR0 0x00, BTR1 0x1C
  ASSERT_EQ(testing::init_classic(gamma.control, classic), VCI_OK);
}

TEST(Vci2CApi, TheVersionComesInOneCallAndTheGeneralFunctionsAreThere) {
  UINT32 major = 0;
  UINT32 minor = 99;
  UINT32 revision = 99;
  UINT32 build = 0;
  ASSERT_EQ(vciGetVersion(&major, &minor, &revision, &build), VCI_OK);
  testing::expect_vci_4_0_0(major, minor, revision, build, CANEMU_PROJECT_VERSION);
  EXPECT_EQ(vciGetVersion(&major, &minor, nullptr, &build), VCI_E_INVALIDARG);
  // What vcinpl_general.h declares is in this library too.
  VCIID id{};
  ASSERT_EQ(vciCreateLuid(&id), VCI_OK);
  wchar_t text[17];
  ASSERT_EQ(vciLuidToCharW(id, text, 17), VCI_OK);
  VCIID back{};
  ASSERT_EQ(vciCharToLuidW(text, &back), VCI_OK);
  EXPECT_EQ(back.AsInt64, id.AsInt64);
  HANDLE e = nullptr;
  ASSERT_EQ(vciEventCreate(FALSE, TRUE, &e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 10), VCI_E_TIMEOUT);
  EXPECT_EQ(vciEventDelete(e), VCI_OK);
  VciDaemon d(kFdAdapters);
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpenDlg(nullptr, &dev), VCI_OK);  // the first device: alpha
  VCIDEVICEINFO info{};
  ASSERT_EQ(vciDeviceGetInfo(dev, &info), VCI_OK);
  EXPECT_NE(std::string(info.Description).find("(canemu alpha)"), std::string::npos);
  EXPECT_EQ(vciDeviceClose(dev), VCI_OK);
}

TEST(Vci2CApi, AChannelAndACyclicListHandOutTheirLinesControlUnit) {
  VciDaemon d(kFdAdapters);
  FdAdapter alpha("alpha");
  HANDLE beta = device_named("beta");
  HANDLE channel = channel_on(beta, 0, CAN_FILTER_PASS);
  HANDLE control = nullptr;
  EXPECT_EQ(canChannelGetControl(channel, nullptr), VCI_E_INVALIDARG);
  EXPECT_EQ(canChannelGetControl(beta, &control), VCI_E_INVHANDLE);  // a device, not a channel
  EXPECT_EQ(control, nullptr);
  ASSERT_EQ(canChannelGetControl(channel, &control), VCI_OK);
  ASSERT_NE(control, nullptr);
  // It is beta's control unit: held, so nobody else opens it; it starts beta's line.
  HANDLE other = nullptr;
  EXPECT_EQ(canControlOpen(beta, 0, &other), VCI_E_ACCESSDENIED);
  HANDLE list = nullptr;
  ASSERT_EQ(canSchedulerOpen(beta, 0, &list), VCI_OK);
  EXPECT_EQ(canSchedulerGetControl(list, &other), VCI_E_ACCESSDENIED);
  CANBTP n = kNominal;
  CANBTP f = kData;
  ASSERT_EQ(canControlInitialize(control, kMode, kFd, CAN_FILTER_INCL, CAN_FILTER_INCL, 2048, 2048,
                                 &n, &f),
            VCI_OK);
  ASSERT_EQ(canControlStart(control, TRUE), VCI_OK);
  CANLINESTATUS2 s{};
  ASSERT_EQ(canControlGetStatus(control, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus & CAN_STATUS_ININIT, 0u);
  EXPECT_EQ(s.sBtpFdr.dwBPS, 2000000u);
  alpha.post(msg(0x321, {1, 2, 3}, true, true));
  step_ns(2'000'000);
  const auto got = drain(channel);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x321u);
  // Closed like any control unit; then the cyclic list gets it (the line keeps running).
  ASSERT_EQ(canControlClose(control), VCI_OK);
  EXPECT_EQ(canSchedulerGetControl(channel, &other), VCI_E_INVHANDLE);  // a channel, not a list
  EXPECT_EQ(canSchedulerGetControl(list, nullptr), VCI_E_INVALIDARG);
  ASSERT_EQ(canSchedulerGetControl(list, &other), VCI_OK);
  ASSERT_EQ(canControlGetStatus(other, &s), VCI_OK);
  EXPECT_EQ(s.dwStatus & CAN_STATUS_ININIT, 0u);
  EXPECT_EQ(s.sBtpSdr.dwBPS, 500000u);
  EXPECT_EQ(canControlClose(other), VCI_OK);
  EXPECT_EQ(canSchedulerClose(list), VCI_OK);
  EXPECT_EQ(canChannelClose(channel), VCI_OK);
  vciDeviceClose(beta);
}

TEST(Vci2CApi, EachV2ChannelFiltersOnItsOwn) {
  VciDaemon d(kFdAdapters);
  FdAdapter alpha("alpha", false);
  FdAdapter beta("beta");
  HANDLE only = channel_on(alpha.device, 16, CAN_FILTER_INCL, false);
  HANDLE except = channel_on(alpha.device, 16, CAN_FILTER_EXCL, false);
  HANDLE nolist = channel_on(alpha.device, 0, CAN_FILTER_INCL, false);
  // INCL: nothing through the acceptance filter, 0x123 on the list.
  ASSERT_EQ(canChannelSetAccFilter(only, FALSE, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE), VCI_OK);
  ASSERT_EQ(canChannelAddFilterIds(only, FALSE, 0x123 << 1, 0xFFF), VCI_OK);
  // EXCL: the same list blocks 0x123 only.
  ASSERT_EQ(canChannelSetAccFilter(except, FALSE, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE), VCI_OK);
  ASSERT_EQ(canChannelAddFilterIds(except, FALSE, 0x123 << 1, 0xFFF), VCI_OK);
  // No 29-bit list: IDs cannot be added, the acceptance filter still works.
  EXPECT_EQ(canChannelAddFilterIds(nolist, TRUE, 0x1000 << 1, 0x3FFFFFFF), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(canChannelSetAccFilter(nolist, TRUE, 0x1000 << 1, 0x3FFFFFFF), VCI_OK);
  UINT8 mode = 0;
  ASSERT_EQ(canChannelGetFilterMode(except, FALSE, &mode), VCI_OK);
  EXPECT_EQ(mode, CAN_FILTER_EXCL);
  for (HANDLE ch : {only, except, nolist}) {
    ASSERT_EQ(canChannelActivate(ch, TRUE), VCI_OK);
  }
  EXPECT_EQ(canChannelSetFilterMode(only, FALSE, CAN_FILTER_PASS, nullptr), VCI_E_INVALID_STATE);
  ASSERT_EQ(canControlStart(alpha.control, TRUE), VCI_OK);
  beta.post(msg(0x122, {}));
  beta.post(msg(0x123, {}));
  CANMSG2 ext = msg(0x1000, {});
  ext.uMsgInfo.Bits.ext = 1;
  beta.post(ext);
  step_ns(2'000'000);
  auto ids = [](HANDLE ch) {
    std::vector<std::pair<uint32_t, unsigned>> v;
    for (const CANMSG2& m : drain(ch)) {
      v.emplace_back(m.dwMsgId, m.uMsgInfo.Bits.afc);
    }
    return v;
  };
  using V = std::vector<std::pair<uint32_t, unsigned>>;
  // The 29-bit filters were left alone: their acceptance filter is open, which passes 0x1000
  // in INCL mode and blocks it in EXCL mode.
  EXPECT_EQ(ids(only), (V{{0x123, CAN_ACCEPT_FILTER_2}, {0x1000, CAN_ACCEPT_FILTER_1}}));
  EXPECT_EQ(ids(except), (V{{0x122, CAN_ACCEPT_PASSEXCL}}));
  EXPECT_EQ(ids(nolist), (V{{0x122, CAN_ACCEPT_FILTER_1},
                            {0x123, CAN_ACCEPT_FILTER_1},
                            {0x1000, CAN_ACCEPT_FILTER_1}}));
  for (HANDLE ch : {only, except, nolist}) {
    canChannelClose(ch);
  }
}

TEST(Vci2CApi, OwnEchoesPassAnyFilterAndOthersNeedSrra) {
  VciDaemon d(kFdAdapters);
  FdAdapter alpha("alpha");
  FdAdapter beta("beta");
  HANDLE sender = channel_on(alpha.device, 0, CAN_FILTER_LOCK);
  HANDLE plain = channel_on(alpha.device, 0, CAN_FILTER_PASS);
  HANDLE srra = channel_on(alpha.device, 0, CAN_FILTER_PASS | CAN_FILTER_SRRA);
  CANMSG2 m = msg(0x42, {1, 2, 3});
  m.uMsgInfo.Bits.srr = 1;
  ASSERT_EQ(canChannelPostMessage(sender, &m), VCI_OK);
  step_ns(2'000'000);
  const auto own = drain(sender);
  ASSERT_EQ(own.size(), 1u);
  EXPECT_EQ(own[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_TRUE(drain(plain).empty());
  const auto foreign = drain(srra);
  ASSERT_EQ(foreign.size(), 1u);
  EXPECT_EQ(foreign[0].dwMsgId, 0x42u);
  EXPECT_EQ(foreign[0].uMsgInfo.Bits.srr, 0u);
  EXPECT_EQ(foreign[0].dwTime, own[0].dwTime);
  EXPECT_EQ(drain(beta.channel).size(), 1u);
  for (HANDLE ch : {sender, plain, srra}) {
    canChannelClose(ch);
  }
}

TEST(Vci2CApi, TheControlUnitsFilterModeComesFromInitLineAndLockKeepsOnlyNonData) {
  VciDaemon d(kFdAdapters);
  FdAdapter beta("beta");
  HANDLE dev = device_named("alpha");
  HANDLE control = nullptr;
  ASSERT_EQ(canControlOpen(dev, 0, &control), VCI_OK);
  HANDLE ch = channel_on(dev, 0, CAN_FILTER_PASS);
  CANBTP n = kNominal;
  CANBTP f = kData;
  ASSERT_EQ(canControlInitialize(control, kMode, kFd, CAN_FILTER_LOCK, CAN_FILTER_INCL, 2048, 2048,
                                 &n, &f),
            VCI_OK);
  UINT8 mode = 0;
  ASSERT_EQ(canControlGetFilterMode(control, FALSE, &mode), VCI_OK);
  EXPECT_EQ(mode, CAN_FILTER_LOCK);
  ASSERT_EQ(canControlStart(control, TRUE), VCI_OK);
  CANMSG2 m = msg(0x10, {1});
  ASSERT_EQ(canChannelPostMessage(beta.channel, &m), VCI_OK);
  step_ns(1'000'000);
  const auto got = drain(ch, false);
  ASSERT_EQ(got.size(), 1u);  // the INFO START passes, the frame does not
  EXPECT_EQ(got[0].uMsgInfo.Bytes.bType, CAN_MSGTYPE_INFO);
  // Back to INCL; the previous mode comes back.
  ASSERT_EQ(canControlStart(control, FALSE), VCI_OK);
  UINT8 previous = 0;
  ASSERT_EQ(canControlSetFilterMode(control, FALSE, CAN_FILTER_INCL, &previous), VCI_OK);
  EXPECT_EQ(previous, CAN_FILTER_LOCK);
  // ResetLine restores the mode InitLine gave.
  ASSERT_EQ(canControlReset(control), VCI_OK);
  ASSERT_EQ(canControlGetFilterMode(control, FALSE, &mode), VCI_OK);
  EXPECT_EQ(mode, CAN_FILTER_LOCK);
  // With no 11-bit IDs the filter is off whatever its mode.
  ASSERT_EQ(
      canControlInitialize(control, kMode, kFd, CAN_FILTER_LOCK, CAN_FILTER_LOCK, 0, 2048, &n, &f),
      VCI_OK);
  ASSERT_EQ(canControlStart(control, TRUE), VCI_OK);
  ASSERT_EQ(canChannelPostMessage(beta.channel, &m), VCI_OK);
  step_ns(1'000'000);
  const auto passed = drain(ch);
  ASSERT_EQ(passed.size(), 1u);
  EXPECT_EQ(passed[0].dwMsgId, 0x10u);
  canChannelClose(ch);
  canControlClose(control);
  vciDeviceClose(dev);
}

TEST(Vci2CApi, AnErrorPassiveSendersFdFrameCarriesEsi) {
  VciDaemon d(kFdAdapters);
  FdAdapter alpha("alpha");
  alpha.post(msg(0x42, {1, 2, 3}, true, true));
  step_ns(10'000'000);  // alone: ACK errors up to TEC 128, error-passive
  UINT8 state = 0;
  ASSERT_EQ(canemuGetControllerState(alpha.control, &state, nullptr, nullptr, nullptr), VCI_OK);
  ASSERT_EQ(state, CANEMU_STATE_PASSIVE);
  FdAdapter beta("beta");
  step_ns(10'000'000);
  const auto got = drain(beta.channel);
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got[0].dwMsgId, 0x42u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.esi, 1u);  // sent while error-passive
}

// A client that refills a 65,535-message transmit FIFO with messages the line refuses (an INFO
// message is no frame), waiting on the FIFO each time it is full (its waiting flag set), does not
// hold canemud: another client's status requests are answered within 100 ms throughout, and the
// flood is consumed (many times the FIFO's size goes through).
TEST(Vci2CApi, AJunkFloodDoesNotDelayAnotherClientsAnswers) {
  testing::ConfigFile config(kFdAdapters);
  testing::Daemon daemon("realtime", {"--config=" + config.path()});
  ASSERT_EQ(canemuConnect(daemon.socket().c_str()), VCI_OK);
  {
    HANDLE gamma = device_named("gamma");
    HANDLE control = nullptr;
    ASSERT_EQ(canControlOpen(gamma, 0, &control), VCI_OK);
    CANBTP classic = btp(500000, 14, 2);
    ASSERT_EQ(testing::init_classic(control, classic), VCI_OK);
    ASSERT_EQ(canControlStart(control, TRUE), VCI_OK);
    HANDLE channel = nullptr;
    ASSERT_EQ(canChannelOpen(gamma, 0, FALSE, &channel), VCI_OK);
    constexpr UINT32 kFifo = 65535;
    ASSERT_EQ(canChannelInitialize(channel, 16, 1, kFifo, 1, 0, CAN_FILTER_PASS), VCI_OK);
    ASSERT_EQ(canChannelActivate(channel, TRUE), VCI_OK);
    std::atomic<bool> stop{false};
    std::atomic<uint64_t> posted{0};
    std::thread flood([&] {
      CANMSG2 junk{};
      junk.uMsgInfo.Bytes.bType = CAN_MSGTYPE_INFO;
      while (!stop) {
        if (canChannelSendMessage(channel, 10, &junk) == VCI_OK) {
          ++posted;
        }
      }
    });
    auto observer = client::Connection::open(daemon.socket(), "observer");
    ASSERT_TRUE(observer) << observer.error().message;
    using Clock = std::chrono::steady_clock;
    const auto end = Clock::now() + std::chrono::seconds(2);
    Clock::duration slowest{};
    int answers = 0;
    while (Clock::now() < end) {
      const auto asked = Clock::now();
      auto r = observer->call<ipc::StatusRequest, ipc::StatusReply>(
          ipc::make_message<ipc::StatusRequest>());
      ASSERT_TRUE(r) << r.error().message;
      slowest = std::max(slowest, Clock::now() - asked);
      ++answers;
    }
    stop = true;
    flood.join();
    std::printf(
        "junk flood: %llu refused messages posted in 2 s; slowest of %d status answers %lld us\n",
        static_cast<unsigned long long>(posted.load()), answers,
        static_cast<long long>(
            std::chrono::duration_cast<std::chrono::microseconds>(slowest).count()));
    EXPECT_LT(std::chrono::duration_cast<std::chrono::milliseconds>(slowest).count(), 100)
        << answers << " answers";
    EXPECT_GT(posted.load(), 4u * kFifo) << "the flood was not consumed";
    canChannelClose(channel);
    canControlClose(control);
    vciDeviceClose(gamma);
  }
  canemuConnect(nullptr);
}

// libvcinpl2 has the LIN functions of libvcinpl (vcinpl_lin.h): a master's header, a slave's
// answer, a monitor that reads several messages at once (vci_c_api_lin_test.cpp has the rest).
TEST(Vci2C, LinMasterAndSlaveExchangeAFrame) {
  using namespace testing;
  VciDaemon d(kLinAdapters);
  HANDLE devs[2] = {device_named("alpha"), device_named("beta")};
  HANDLE controls[2] = {};
  HANDLE monitors[2] = {};
  for (int i = 0; i < 2; ++i) {
    ASSERT_EQ(linControlOpen(devs[i], kLinNo, &controls[i]), VCI_OK);
    ASSERT_EQ(linMonitorOpen(devs[i], kLinNo, FALSE, &monitors[i]), VCI_OK);
    ASSERT_EQ(linMonitorInitialize(monitors[i], 16, 1), VCI_OK);
    ASSERT_EQ(linMonitorActivate(monitors[i], TRUE), VCI_OK);
    ASSERT_EQ(
        linControlInitialize(controls[i], i == 0 ? LIN_OPMODE_MASTER : LIN_OPMODE_SLAVE, kRate),
        VCI_OK);
    ASSERT_EQ(linControlStart(controls[i], TRUE), VCI_OK);
  }
  LINMSG response = lin_data(0x2A, {0xDE, 0xAD}, true);
  ASSERT_EQ(linControlWriteMessage(controls[1], FALSE, &response), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  LINMSG header = lin_data(0x2A, {}, true, true);
  ASSERT_EQ(linControlWriteMessage(controls[0], TRUE, &header), VCI_OK);
  step_to(10'000'000);
  LINMSG got[4] = {};
  UINT32 done = 0;
  ASSERT_EQ(linMonitorReadMsgMult(monitors[0], 100, got, 4, &done), VCI_OK);
  ASSERT_EQ(done, 2U);  // the start's info message, the frame
  EXPECT_EQ(text_of(got[1]), frame_text(stamp(frame_end(t0, 2)), 0x2A, {0xDE, 0xAD}, true, false));
  ASSERT_EQ(linMonitorPeekMsgMult(monitors[1], got, 4, &done), VCI_OK);
  ASSERT_EQ(done, 2U);
  EXPECT_EQ(text_of(got[1]), frame_text(stamp(frame_end(t0, 2)), 0x2A, {0xDE, 0xAD}, true, true));
  EXPECT_EQ(linMonitorPeekMsgMult(monitors[1], got, 4, &done), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(done, 0U);
  EXPECT_EQ(linMonitorWaitRxEvent(monitors[1], 0), VCI_OK);  // the writes signalled it
  EXPECT_EQ(linMonitorWaitRxEvent(monitors[1], 0), VCI_E_TIMEOUT);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(linMonitorClose(monitors[i]), VCI_OK);
    EXPECT_EQ(linControlClose(controls[i]), VCI_OK);
    vciDeviceClose(devs[i]);
  }
}

}  // namespace
}  // namespace canemu
