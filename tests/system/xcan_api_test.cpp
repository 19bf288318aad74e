// The X-CAN-2i channel services through libxcan.so against a real canemud: an X-CAN-2i
// interface and an IXXAT adapter (through libvcinpl, a client of its own) on one bus, in stepped
// time. Both libraries are linked into this program: their exported names differ.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>

#include "canmsg_text_support.hpp"
#include "example_program.hpp"
#include "vcinpl.h"
#include "xcan.h"
#include "xcan_test_support.hpp"

namespace canemu::testing {
namespace {

// Runs the canemu command line on the daemon's socket to its end; its exit status.
int run_canemu(const testing::Daemon& d, std::vector<std::string> args) {
  args.insert(args.begin(), {CANEMU_PATH, "--socket", d.socket()});
  std::vector<char*> argv;
  for (std::string& a : args) {
    argv.push_back(a.data());
  }
  argv.push_back(nullptr);
  pid_t pid = -1;
  EXPECT_EQ(::posix_spawn(&pid, CANEMU_PATH, nullptr, nullptr, argv.data(), environ), 0);
  int status = -1;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(XcanApi, ModuleAndMddAreCheckedByName) {
  VciDaemon d(kConfig);
  ASSERT_EQ(canemu_xcan_connect(d.daemon.socket().c_str()), ERR_OK);
  MAX_HANDLE module = 0;
  EXPECT_EQ(canemu_open_module("alpha", &module), ERR_XCAN_NO_MODULE);  // an IXXAT adapter
  EXPECT_EQ(canemu_open_module("nothing", &module), ERR_XCAN_NO_MODULE);
  ASSERT_EQ(canemu_open_module("xcan0", &module), ERR_OK);
  MAX_HANDLE mdd = 0;
  EXPECT_EQ(max_load_mdd(module, 1, 0, 0, 0x8039, nullptr, &mdd), ERR_XCAN_NO_MODULE);
  EXPECT_EQ(max_load_mdd(module, 2, 0, 0, 0x803A, nullptr, &mdd), ERR_XCAN_NO_MODULE);
  EXPECT_EQ(max_load_mdd(module + 100, 1, 0, 0, 0x803A, nullptr, &mdd), ERR_XCAN_INVALID_HANDLE);
  ASSERT_EQ(max_load_mdd(module, 1, 0, 0, 0x803A, nullptr, &mdd), ERR_OK);
  // The model judges the CPS: an interface 2 does not exist, a second general-ID channel is busy.
  CPS_XCAN bad = cps(DEVICE_BUS_OUT, 0x100);
  bad.usChannel = 2;
  MAX_HANDLE h = 0;
  EXPECT_EQ(max_open_channel(mdd, &bad, nullptr, &h), ERR_XCAN_INVALID_CPS);
  const CPS_XCAN general = cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE);
  ASSERT_EQ(max_open_channel(mdd, &general, nullptr, &h), ERR_OK);
  MAX_HANDLE again = 0;
  EXPECT_EQ(max_open_channel(mdd, &general, nullptr, &again), ERR_XCAN_CHANNEL_BUSY);
  EXPECT_EQ(max_close_channel(h), ERR_OK);
  EXPECT_EQ(max_close_channel(h), ERR_XCAN_INVALID_HANDLE);
  EXPECT_EQ(max_open_channel(mdd, &general, nullptr, &again), ERR_OK);
  // The bus-control channel reads its bit timing back.
  MAX_HANDLE bus = 0;
  const CPS_XCAN ctrl = cps(DEVICE_CTRL, 0);
  ASSERT_EQ(max_open_channel(mdd, &ctrl, nullptr, &bus), ERR_OK);
  XCAN_BITPARAMS bits = k500k;
  ULONG size = sizeof bits;
  ASSERT_EQ(max_write_channel_block(bus, &size, &bits), ERR_OK);
  XCAN_BITPARAMS back{};
  size = sizeof back;
  ASSERT_EQ(max_read_channel_block(bus, &size, &back), ERR_OK);
  EXPECT_EQ(size, sizeof back);
  EXPECT_EQ(std::memcmp(&back, &k500k, sizeof back), 0);
  canemu_xcan_connect(nullptr);
}

// The VCI's device enumeration shows the IXXAT adapters only: an X-CAN-2i is no VCI device;
// libxcan's enumeration shows the module's two interfaces.
TEST(XcanApi, TheVciListsTheAdaptersAndLibxcanTheModulesInterfaces) {
  VciDaemon d(kConfig);
  HANDLE e = nullptr;
  ASSERT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
  VCIDEVICEINFO info{};
  std::vector<std::string> found;
  while (vciEnumDeviceNext(e, &info) == VCI_OK) {
    found.emplace_back(info.Description);
  }
  vciEnumDeviceClose(e);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_NE(found[0].find("(canemu alpha)"), std::string::npos) << found[0];
  EXPECT_NE(found[1].find("(canemu beta)"), std::string::npos) << found[1];

  ASSERT_EQ(canemu_xcan_connect(d.daemon.socket().c_str()), ERR_OK);
  for (USHORT k = 0; k < 2; ++k) {
    CANEMU_XCAN_INTERFACE iface{};
    ASSERT_EQ(canemu_xcan_enum_interfaces(k, &iface), ERR_OK);
    EXPECT_STREQ(iface.szDevice, "xcan0");
    EXPECT_STREQ(iface.szBus, k == 0 ? "can0" : "can1");
    EXPECT_EQ(iface.usChannel, k);
    EXPECT_EQ(iface.usLowSpeed, 0u);
    EXPECT_EQ(iface.ulBitrate, 500000u);
  }
  CANEMU_XCAN_INTERFACE none{};
  EXPECT_EQ(canemu_xcan_enum_interfaces(2, &none), ERR_XCAN_NO_MODULE);
  canemu_xcan_connect(nullptr);
}

TEST(XcanApi, DataFramesBothWaysWithAnIxxatAdapter) {
  XcanDaemon x;
  Adapter alpha("alpha");
  const MAX_HANDLE send = x.open(cps(DEVICE_BUS_OUT, 0x100), record);
  const MAX_HANDLE receive = x.open(cps(DEVICE_BUS_IN, 0x200), record);
  step_ns(1'000'000);  // both on the bus
  const uint8_t out[3] = {0x01, 0x02, 0x03};
  ULONG size = 3;
  ASSERT_EQ(max_write_channel_block(send, &size, out), ERR_OK);
  step_ns(1'000'000);
  const auto at_alpha = alpha.frames();
  ASSERT_EQ(at_alpha.size(), 1u);
  EXPECT_EQ(candump_text(at_alpha[0]), "100#010203");
  // Written at 1 ms, sent at once on an idle bus.
  EXPECT_EQ(at_alpha[0].dwTime, static_cast<UINT32>(1000 + bits_of(0x100, {1, 2, 3}) * kBitUs2));

  alpha.post(data(0x200, {0xAA, 0xBB}));
  alpha.post(data(0x201, {0xCC}));  // no object: the 82527 does not take it
  step_ns(1'000'000);
  const auto seen = wait_seen(2);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].channel, send);  // the send object's callback: sent, no data
  EXPECT_TRUE(seen[0].bytes.empty());
  EXPECT_EQ(seen[1].channel, receive);
  EXPECT_EQ(seen[1].bytes, (std::vector<uint8_t>{0xAA, 0xBB}));
  ULONG count = 0;
  EXPECT_EQ(max_channel_info(receive, INFO_XCAN_MSG_COUNT, &count), ERR_OK);
  EXPECT_EQ(count, 1u);
  EXPECT_EQ(max_channel_info(send, INFO_XCAN_MSG_COUNT, &count), ERR_OK);
  EXPECT_EQ(count, 1u);
  uint8_t in[8] = {};
  size = sizeof in;
  EXPECT_EQ(max_read_channel_block(receive, &size, in), ERR_OK);
  EXPECT_EQ(size, 2u);
  EXPECT_EQ(in[0], 0xAA);
  EXPECT_EQ(in[1], 0xBB);
  EXPECT_EQ(wait_seen(2).size(), 2u);  // nothing more came
}

TEST(XcanApi, PassiveSendObjectAnswersRemoteFramesWithTheDataOfThatInstant) {
  XcanDaemon x;
  Adapter alpha("alpha");
  const MAX_HANDLE passive = x.open(cps(DEVICE_BUS_OUT, 0x300, XCAN_REMOTE), record);
  uint8_t first[2] = {0x05, 0x06};
  ULONG size = 2;
  ASSERT_EQ(max_write_channel_block(passive, &size, first), ERR_OK);
  step_ns(1'000'000);
  EXPECT_TRUE(alpha.frames().empty());  // a passive object sends only when asked
  alpha.post(data(0x300, {0, 0}, false, true));
  step_ns(1'000'000);
  auto got = alpha.frames();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x300u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.rtr, 0u);
  EXPECT_EQ(got[0].abData[0], 0x05);
  EXPECT_EQ(got[0].abData[1], 0x06);
  // The remote frame (from 1 ms) and the answer right behind it (after the intermission).
  EXPECT_EQ(
      got[0].dwTime,
      static_cast<UINT32>(1000 + (remote_bits(0x300, 2) + 3 + bits_of(0x300, {5, 6})) * kBitUs2));
  uint8_t second[2] = {0x07, 0x08};
  ASSERT_EQ(max_write_channel_block(passive, &size, second), ERR_OK);
  alpha.post(data(0x300, {0, 0}, false, true));
  step_ns(1'000'000);
  got = alpha.frames();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].abData[0], 0x07);
  EXPECT_EQ(got[0].abData[1], 0x08);
  ULONG count = 0;
  EXPECT_EQ(max_channel_info(passive, INFO_XCAN_MSG_COUNT, &count), ERR_OK);
  EXPECT_EQ(count, 2u);
}

// The remote frames come from `canemu send`, a process of its own with an ephemeral node on
// can0, which steps time itself; alpha sees the request and the answer.
TEST(XcanApi, PassiveSendObjectAnswersAnotherProcessWithTheDataOfThatInstant) {
  XcanDaemon x;
  Adapter alpha("alpha");
  const MAX_HANDLE passive = x.open(cps(DEVICE_BUS_OUT, 0x300, XCAN_REMOTE));
  uint8_t first[2] = {0x11, 0x22};
  ULONG size = 2;
  ASSERT_EQ(max_write_channel_block(passive, &size, first), ERR_OK);
  step_ns(1'000'000);
  ASSERT_EQ(run_canemu(x.vci.daemon, {"send", "can0", "300#R2", "--step", "1ms"}), 0);
  auto got = alpha.frames();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].dwMsgId, 0x300u);
  EXPECT_EQ(got[0].uMsgInfo.Bits.rtr, 1u);
  EXPECT_EQ(got[1].dwMsgId, 0x300u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.rtr, 0u);
  EXPECT_EQ(got[1].uMsgInfo.Bits.dlc, 2u);
  EXPECT_EQ(got[1].abData[0], 0x11);
  EXPECT_EQ(got[1].abData[1], 0x22);
  // The answer follows the request after the intermission.
  EXPECT_EQ(got[1].dwTime - got[0].dwTime,
            static_cast<UINT32>((3 + bits_of(0x300, {0x11, 0x22})) * kBitUs2));
  uint8_t second[2] = {0x33, 0x44};
  ASSERT_EQ(max_write_channel_block(passive, &size, second), ERR_OK);
  ASSERT_EQ(run_canemu(x.vci.daemon, {"send", "can0", "300#R2", "--step", "1ms"}), 0);
  got = alpha.frames();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].abData[0], 0x33);
  EXPECT_EQ(got[1].abData[1], 0x44);
}

TEST(XcanApi, ActiveReceiveObjectAsksByRemoteFrameAndGetsTheAnswer) {
  XcanDaemon x;
  Adapter alpha("alpha");
  const MAX_HANDLE active =
      x.open(cps(DEVICE_BUS_IN, 0x400, XCAN_REMOTE | XCAN_NO_INT, 5000), record);
  step_ns(1'000'000);
  ASSERT_EQ(max_channel_control(active, CMD_START), ERR_OK);
  step_ns(1'000'000);
  const auto asked = alpha.frames();
  ASSERT_EQ(asked.size(), 1u);
  // Asked for at 1 ms, with the DLC of the data the object holds: none yet.
  EXPECT_EQ(candump_text(asked[0]), "400#R0");
  EXPECT_EQ(asked[0].dwTime, static_cast<UINT32>(1000 + remote_bits(0x400, 0) * kBitUs2));
  alpha.post(data(0x400, {0x09, 0x0A, 0x0B}));
  step_ns(1'000'000);
  const auto seen = wait_seen(1);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].channel, active);
  EXPECT_EQ(seen[0].bytes, (std::vector<uint8_t>{0x09, 0x0A, 0x0B}));

  // The blocking read: nobody answers within 5 ms.
  std::atomic<bool> done{false};
  ULONG result = ERR_OK;
  std::thread reader([&] {
    uint8_t in[8];
    ULONG n = sizeof in;
    result = max_read_channel_block(active, &n, in);
    done = true;
  });
  // The read is under way once its remote frame is on the bus.
  while (alpha.frames().empty()) {
    step_ns(100'000);
  }
  testing::step_until(done);
  reader.join();
  EXPECT_EQ(result, ERR_XCAN_TIMEOUT);
}

// Alone with one other node, a node at the wrong rate stays error-passive: its frames lose only
// their acknowledgement, which does not count once it is passive. Two adapters that talk at
// the bus's rate (their good frames bring them back to error-active) destroy its frames with
// active error flags until it is off the bus.
TEST(XcanApi, BitRateMismatchGivesErrorCallbacksAndBusOffUntilStopAndStart) {
  XcanDaemon x(k250k, _CP_SYNC_CALLBACK);
  Adapter alpha("alpha");
  Adapter beta("beta");
  const MAX_HANDLE send = x.open(cps(DEVICE_BUS_OUT, 0x100));
  step_ns(1'000'000);
  const uint8_t out[1] = {0x55};
  ULONG size = 1;
  ASSERT_EQ(max_write_channel_block(send, &size, out), ERR_OK);
  ULONG state = 0;
  int steps = 0;
  for (; steps < 500; ++steps) {
    alpha.post(data(0x010, {1}));
    beta.post(data(0x011, {2}));
    step_ns(1'000'000);
    ASSERT_EQ(max_channel_info(x.bus, INFO_DEVICE, &state), ERR_OK);
    if (XCAN_STATUS_FLAGS(state) & XCAN_BUS_OFF) {
      break;
    }
  }
  EXPECT_EQ(steps, 9);  // off the bus in the tenth millisecond
  // Direct callbacks ran on the receive thread before this reply came.
  EXPECT_EQ(XCAN_STATUS_FLAGS(state), XCAN_BUS_OFF | XCAN_BUS_HEAVY);
  std::vector<Seen> seen;
  {
    std::lock_guard lock(g_mutex);
    seen = g_seen;
  }
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].channel, x.bus);
  EXPECT_EQ(XCAN_STATUS_FLAGS(status_of(seen[0])), XCAN_BUS_ON | XCAN_BUS_HEAVY);
  EXPECT_EQ(XCAN_STATUS_FLAGS(status_of(seen[1])), XCAN_BUS_OFF | XCAN_BUS_HEAVY);
  EXPECT_EQ(max_write_channel_block(send, &size, out), ERR_XCAN_NOT_READY);

  // Recovery: stop, the right timing, start; 128 x 11 recessive bits later it is on the bus.
  ASSERT_EQ(max_channel_control(x.bus, CMD_STOP), ERR_OK);
  ULONG bits_size = sizeof k500k;
  ASSERT_EQ(max_write_channel_block(x.bus, &bits_size, &k500k), ERR_OK);
  ASSERT_EQ(max_channel_control(x.bus, CMD_START), ERR_OK);
  step_ns(128 * 11 * 2'000 + 1'000'000);
  ASSERT_EQ(max_channel_info(x.bus, INFO_DEVICE, &state), ERR_OK);
  EXPECT_EQ(XCAN_STATUS_FLAGS(state), XCAN_BUS_ON);
  alpha.drain();
  ASSERT_EQ(max_write_channel_block(send, &size, out), ERR_OK);
  step_ns(1'000'000);
  const auto got = alpha.frames();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].dwMsgId, 0x100u);
  EXPECT_EQ(got[0].abData[0], 0x55);
}

// The general-ID channel asks alpha by remote frame; the answer, like any frame no object
// takes, reaches the acceptance-filter device's callback as an XCAN_MESSAGE.
TEST(XcanApi, GeneralIdRemoteFrameAndTheAnswerThroughTheAcceptanceFilter) {
  XcanDaemon x;
  Adapter alpha("alpha");
  CPS_XCAN filter_cps = cps(DEVICE_CTRL, XCAN_AUTO_ID);
  filter_cps.usIndexFirst = filter_cps.usIndexLast = 0;
  const MAX_HANDLE filter = x.open(filter_cps, record);
  ASSERT_EQ(max_write_channel_ulong(filter, 0), ERR_OK);  // mask 0: every identifier
  const MAX_HANDLE general = x.open(cps(DEVICE_BUS_OUT, XCAN_GENERAL_ID, _CP_EXCLUSIVE));
  step_ns(1'000'000);
  XCAN_MESSAGE ask{};
  ask.ulCanId = 0x321;
  ask.usDataSize = 1;
  ask.usFlags = XCAN_REMOTE;
  ULONG size = sizeof ask;
  ASSERT_EQ(max_write_channel_block(general, &size, &ask), ERR_OK);
  step_ns(1'000'000);
  const auto asked = alpha.frames();
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(candump_text(asked[0]), "321#R1");
  EXPECT_EQ(asked[0].dwTime, static_cast<UINT32>(1000 + remote_bits(0x321, 1) * kBitUs2));
  alpha.post(data(0x321, {0x77}));
  step_ns(1'000'000);
  const auto seen = wait_seen(1);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].channel, filter);
  const XCAN_MESSAGE got = message_of(seen[0]);
  EXPECT_EQ(got.ulCanId, 0x321u);
  EXPECT_EQ(got.usDataSize, 1u);
  EXPECT_EQ(got.usFlags, 0u);
  EXPECT_EQ(got.aucData[0], 0x77);
}

// The example program as a user runs it (stepped time moved by this test): its three frames
// reach alpha, alpha's answer reaches its receive object's callback.
TEST(XcanApi, TheExampleTalksWithAnIxxatAdapter) {
  XcanDaemon x;
  Adapter alpha("alpha");
  ExampleProgram talk;
  ASSERT_NO_FATAL_FAILURE(
      talk.start({XCAN_TALK_PATH, "xcan0", "0", "0x100", "0x200", "3"}, x.vci.daemon.socket()));
  std::vector<CANMSG> frames;
  bool answered = false;
  talk.step_until_exit([&] {
    for (const CANMSG& m : alpha.frames()) {
      frames.push_back(m);
      if (!answered) {
        alpha.post(data(0x200, {0xAB}));
        answered = true;
      }
    }
  });
  ASSERT_TRUE(WIFEXITED(talk.status));
  EXPECT_EQ(WEXITSTATUS(talk.status), 0);
  const std::string text = talk.output();
  ASSERT_EQ(frames.size(), 3u);
  for (UINT8 k = 0; k < 3; ++k) {
    EXPECT_EQ(frames[k].dwMsgId, 0x100u);
    EXPECT_EQ(frames[k].uMsgInfo.Bits.dlc, 4u);
    EXPECT_EQ(frames[k].abData[3], k);
  }
  // The callback prints on the library's thread, the count on the main thread.
  EXPECT_TRUE(text == "channel 5: 1 bytes: AB\n3 frames sent\n" ||
              text == "3 frames sent\nchannel 5: 1 bytes: AB\n")
      << text;
}

}  // namespace
}  // namespace canemu::testing
