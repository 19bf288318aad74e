// The SL-CANi library through libsl64.so against a real canemud, in stepped time: an SL-CANi,
// an X-CAN-2i interface and IXXAT adapters (libvcinpl, libxcan) on one bus; the call order;
// the handle FIFO; repetition until sl064_clear_msg with the counter in canemu status; bus-off
// to the error routine and out by stop/start; the EEPROM across a canemud restart.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <string>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "canemu/firmware_model/bus/can_error.hpp"
#include "canmsg_text_support.hpp"
#include "example_program.hpp"
#include "sl64lib.h"
#include "vci_c_test_support.hpp"
#include "vcinpl.h"
#include "xcan.h"

namespace canemu::testing {
namespace {

// can0 at 500 kbit/s: IXXAT adapters alpha and beta, the X-CAN-2i xcan0 (interface 0), the
// SL-CANi sl0 in slot 1 (channel B); can1 for the X-CAN-2i's interface 1.
const char* const kConfig =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[bus]]\nname = \"can1\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"xcan0\"\nmodel = \"sorcus-x-can-2i\"\ncontrollers = [\"can0\", "
    "\"can1\"]\n\n"
    "[[device]]\nname = \"sl0\"\nmodel = \"sorcus-sl-cani\"\ncontrollers = [\"can0\"]\nslot = 1\n";

constexpr UCHAR kSlot = 1;

// What the service routines got, in order.
struct Call {
  bool error;
  USHORT task;
  ULONG value;  // the handle, or the status
};
std::mutex g_mutex;
std::condition_variable g_cv;
std::vector<Call> g_calls;

void message_service(USHORT task, USHORT, SL064Handle* handle, USHORT, ULONG*) {
  std::lock_guard lock(g_mutex);
  g_calls.push_back(Call{false, task, *handle});
  g_cv.notify_all();
}
void error_service(USHORT task, USHORT, ULONG* status, USHORT, UCHAR*) {
  std::lock_guard lock(g_mutex);
  g_calls.push_back(Call{true, task, *status});
  g_cv.notify_all();
}
std::vector<Call> wait_calls(std::size_t n) {
  std::unique_lock lock(g_mutex);
  g_cv.wait_for(lock, std::chrono::seconds(10), [&] { return g_calls.size() >= n; });
  return g_calls;
}

// The acceptance mask's routine (task 100, function 6) of a bus monitor, as the manual uses it:
// each call reads the ID of its frame with sl064_get_id(slot, 0, ...).
std::vector<ULONG> g_ids;
void monitor_service(USHORT, USHORT, SL064Handle* handle, USHORT, ULONG*) {
  ULONG id = 0xFFFFFFFF;
  const USHORT ret = sl064_get_id(1, *handle, &id);
  std::lock_guard lock(g_mutex);
  g_ids.push_back(ret == 0 ? id : 0xEEEEEEEE);
  g_cv.notify_all();
}

// A call's return value and then the diagnosis.
std::pair<USHORT, USHORT> diag(USHORT ret) {
  return {ret, sl064_get_diagnosis(kSlot)};
}
constexpr std::pair<USHORT, USHORT> kOk{0, 0};
std::pair<USHORT, USHORT> error(USHORT code) {
  return {SL064_E_DRIVER, code};
}

// canemud with `config`, libvcinpl and libsl64 connected, the SL-CANi started and its
// EEPROM set to 500 kbit/s (100 ns, 16, 3, 1); routines: message (100, 4), error (100, 5).
struct Sl64Daemon {
  VciDaemon vci;
  explicit Sl64Daemon(const std::string& config = kConfig, USHORT tq = 100) : vci(config) {
    {
      std::lock_guard lock(g_mutex);
      g_calls.clear();
    }
    EXPECT_EQ(canemu_sl064_connect(vci.daemon.socket().c_str()), 0);
    {
      std::lock_guard lock(g_mutex);
      g_calls.clear();  // a routine of the test before may have been running
    }
    EXPECT_EQ(canemu_sl064_install_message_service(100, 4, message_service), 0);
    EXPECT_EQ(canemu_sl064_install_error_service(100, 5, error_service), 0);
    EXPECT_EQ(sl064_bib_startup(), 0);
    for (const auto& [word, value] :
         std::vector<std::pair<USHORT, USHORT>>{{SL064_EEPROM_TQ, tq},
                                                {SL064_EEPROM_TSEG1, 16},
                                                {SL064_EEPROM_TSEG2, 3},
                                                {SL064_EEPROM_SJW, 1}}) {
      EXPECT_EQ(canemu_sl064_eeprom_write(kSlot, word, value), 0);
    }
  }
  ~Sl64Daemon() { canemu_sl064_connect(nullptr); }
  static SL064Handle object(ULONG id, USHORT flags) {
    SL064MsgType c{id, flags, 100, 4};
    SL064Handle h = 0;
    EXPECT_EQ(diag(sl064_config_msg_object(kSlot, &h, &c)), kOk) << "id " << id;
    return h;
  }
};

TEST(Sl64Api, TheManualsExampleTalksWithAnIxxatAdapterAndAnXcanInterface) {
  Sl64Daemon x;
  ASSERT_EQ(diag(sl064_config_module(kSlot, 100, 5)), kOk);
  // The manual's example: slot 1, ID 7, send active and passive, routine task 100 function 4.
  SL064MsgType msg_config;
  msg_config.id = 7L;
  msg_config.control_flags = _SL064_SEND | _SL064_ACTIVE | _SL064_PASSIVE;
  msg_config.serv_task = 100;
  msg_config.serv_func = 4;
  SL064Handle hMessage1 = 0;
  ASSERT_EQ(sl064_config_msg_object(kSlot, &hMessage1, &msg_config), 0);
  EXPECT_EQ(hMessage1, 1);
  const SL064Handle from_alpha = Sl64Daemon::object(0x200, _SL064_PASSIVE);
  const SL064Handle from_xcan = Sl64Daemon::object(0x300, _SL064_PASSIVE);
  ASSERT_EQ(diag(sl064_start_com(kSlot)), kOk);

  Adapter alpha("alpha");
  ASSERT_EQ(canemu_xcan_connect(x.vci.daemon.socket().c_str()), ERR_OK);
  MAX_HANDLE module = 0;
  MAX_HANDLE mdd = 0;
  ASSERT_EQ(canemu_open_module("xcan0", &module), ERR_OK);
  ASSERT_EQ(max_load_mdd(module, 1, 0, 0, 0x803A, nullptr, &mdd), ERR_OK);
  CPS_XCAN ctrl{};
  ctrl.usDevice = DEVICE_CTRL;
  ctrl.usIndexFirst = ctrl.usIndexLast = XCAN_BUS_CTRL_INDEX;
  MAX_HANDLE bus = 0;
  ASSERT_EQ(max_open_channel(mdd, &ctrl, nullptr, &bus), ERR_OK);
  const XCAN_BITPARAMS k500k = {125, 12, 3, 1, 1, 0, 11};
  ULONG size = sizeof k500k;
  ASSERT_EQ(max_write_channel_block(bus, &size, &k500k), ERR_OK);
  CPS_XCAN in7{};
  in7.usDevice = DEVICE_BUS_IN;
  in7.ulCanID = 7;
  CPS_XCAN out300{};
  out300.usDevice = DEVICE_BUS_OUT;
  out300.ulCanID = 0x300;
  MAX_HANDLE xin = 0;
  MAX_HANDLE xout = 0;
  ASSERT_EQ(max_open_channel(mdd, &in7, nullptr, &xin), ERR_OK);
  ASSERT_EQ(max_open_channel(mdd, &out300, nullptr, &xout), ERR_OK);
  step_ns(1'000'000);

  // SL-CANi -> IXXAT and X-CAN: ID 7 with the data set before.
  UCHAR out[2] = {0x11, 0x22};
  ASSERT_EQ(diag(sl064_set_data(kSlot, hMessage1, out, 2)), kOk);
  ASSERT_EQ(diag(sl064_send_data(kSlot, hMessage1)), kOk);
  step_ns(1'000'000);
  const auto at_alpha = alpha.frames();
  ASSERT_EQ(at_alpha.size(), 1u);
  EXPECT_EQ(at_alpha[0].dwMsgId, 7u);
  EXPECT_EQ(at_alpha[0].abData[1], 0x22);
  EXPECT_EQ(at_alpha[0].dwTime, static_cast<UINT32>(1000 + bits_of(7, {0x11, 0x22}) * kBitUs2));
  uint8_t got[8] = {};
  size = sizeof got;
  ASSERT_EQ(max_read_channel_block(xin, &size, got), ERR_OK);
  EXPECT_EQ(size, 2u);
  EXPECT_EQ(got[0], 0x11);
  // IXXAT -> SL-CANi, X-CAN -> SL-CANi.
  alpha.post(data(0x200, {0xAA}));
  const uint8_t xdata[1] = {0xBB};
  size = 1;
  ASSERT_EQ(max_write_channel_block(xout, &size, xdata), ERR_OK);
  step_ns(1'000'000);
  const auto calls = wait_calls(3);
  ASSERT_EQ(calls.size(), 3u);
  EXPECT_EQ(calls[0].value, hMessage1);  // sent: after the acknowledgement
  EXPECT_EQ(calls[0].task, 100);
  // 200h and 300h started together: the lower identifier first.
  EXPECT_EQ(calls[1].value, from_alpha);
  EXPECT_EQ(calls[2].value, from_xcan);
  UCHAR in[8] = {};
  UCHAR n = 8;
  EXPECT_EQ(diag(sl064_get_data(kSlot, from_alpha, in, &n)), std::make_pair(USHORT{0}, USHORT{1}));
  EXPECT_EQ(n, 1);
  EXPECT_EQ(in[0], 0xAA);
  n = 1;
  EXPECT_EQ(diag(sl064_get_data(kSlot, from_xcan, in, &n)), kOk);
  EXPECT_EQ(in[0], 0xBB);
  // A remote frame from the IXXAT adapter: the passive side answers with the data of now.
  UCHAR now[1] = {0x33};
  ASSERT_EQ(diag(sl064_set_data(kSlot, hMessage1, now, 1)), kOk);
  alpha.post(data(7, {}, false, true));
  step_ns(1'000'000);
  std::vector<CANMSG> answer;  // (alpha also saw the X-CAN's 300h)
  for (const CANMSG& m : alpha.frames()) {
    if (m.uMsgInfo.Bits.rtr == 0 && m.dwMsgId == 7) {
      answer.push_back(m);
    }
  }
  ASSERT_EQ(answer.size(), 1u);
  EXPECT_EQ(answer[0].dwMsgId, 7u);
  EXPECT_EQ(answer[0].abData[0], 0x33);
  EXPECT_EQ(wait_calls(4).size(), 4u);
  ULONG count = 0;
  EXPECT_EQ(diag(sl064_get_msg_count(kSlot, hMessage1, &count)), kOk);
  EXPECT_EQ(count, 2u);
  sl064_set_led(kSlot, 1);
  EXPECT_EQ(sl064_get_dout(kSlot), 1);
  EXPECT_EQ(sl064_get_led(kSlot), 1);
  canemu_xcan_connect(nullptr);
}

TEST(Sl64Api, EveryCallOutOfOrderGives2DhAndBadObjectsTheirCodes) {
  Sl64Daemon x;
  SL064MsgType c{7, _SL064_SEND | _SL064_ACTIVE, 0, 0};
  SL064Handle h = 99;
  ULONG mask = 0;
  EXPECT_EQ(diag(sl064_config_msg_object(kSlot, &h, &c)), error(0x2D));
  EXPECT_EQ(h, 0);
  EXPECT_EQ(diag(sl064_set_acceptance_mask(kSlot, &mask, 0, 0, 0)), error(0x2D));
  EXPECT_EQ(diag(sl064_start_com(kSlot)), error(0x2D));
  EXPECT_EQ(diag(sl064_config_module(kSlot, 0, 0)), kOk);
  EXPECT_EQ(diag(sl064_config_module(kSlot, 0, 0)), error(0x2D));
  h = Sl64Daemon::object(7, _SL064_SEND | _SL064_ACTIVE);
  EXPECT_EQ(diag(sl064_send_data(kSlot, h)), error(0x2D));
  EXPECT_EQ(diag(sl064_config_msg_object(kSlot, &h, &c)), error(0x28));  // the same ID
  for (ULONG id = 0x100; id < 0x10D; ++id) {
    Sl64Daemon::object(id, _SL064_SEND | _SL064_ACTIVE | _SL064_EXCL_BUFFER);
  }
  c.id = 0x10D;
  c.control_flags = _SL064_SEND | _SL064_ACTIVE | _SL064_EXCL_BUFFER;
  EXPECT_EQ(diag(sl064_config_msg_object(kSlot, &h, &c)), error(0x27));  // a 14th exclusive
  EXPECT_EQ(diag(sl064_set_acceptance_mask(kSlot, &mask, 0, 0, 0)), kOk);
  EXPECT_EQ(diag(sl064_set_acceptance_mask(kSlot, &mask, 0, 0, 0)), error(0x2D));
  c.control_flags = _SL064_PASSIVE;
  EXPECT_EQ(diag(sl064_config_msg_object(kSlot, &h, &c)), error(0x2D));
  EXPECT_EQ(diag(sl064_start_com(kSlot)), kOk);
  EXPECT_EQ(diag(sl064_start_com(kSlot)), error(0x2D));
  // A slot without an S-Link does not respond.
  EXPECT_EQ(sl064_config_module(0, 0, 0), SL064_E_DRIVER);
  EXPECT_EQ(sl064_get_diagnosis(0), SL064_DIAG_NO_RESPONSE);
  EXPECT_EQ(sl064_get_diagnosis(0), 0);
  // Read-only EEPROM words stay as they are.
  EXPECT_EQ(canemu_sl064_eeprom_write(kSlot, 12, 0x20), SL064_E_DRIVER);
  USHORT w = 0;
  EXPECT_EQ(canemu_sl064_eeprom_read(kSlot, 12, &w), 0);
  EXPECT_EQ(w, 0x0010);
}

TEST(Sl64Api, AQueuedObjectIsWarning6AndSendsTheDataSetAfterQueuing) {
  Sl64Daemon x;
  Adapter alpha("alpha");
  ASSERT_EQ(diag(sl064_config_module(kSlot, 0, 0)), kOk);
  std::vector<SL064Handle> h;
  for (ULONG id = 0x100; id < 0x10F; ++id) {
    h.push_back(Sl64Daemon::object(id, _SL064_SEND | _SL064_ACTIVE));  // 15: the temporary pool
  }
  ASSERT_EQ(diag(sl064_start_com(kSlot)), kOk);
  step_ns(1'000'000);
  for (std::size_t k = 0; k < 14; ++k) {
    ASSERT_EQ(diag(sl064_send_data(kSlot, h[k])), kOk);
  }
  EXPECT_EQ(diag(sl064_send_data(kSlot, h[14])), std::make_pair(USHORT{0}, USHORT{6}));
  UCHAR later[2] = {0xBB, 0xCC};
  ASSERT_EQ(diag(sl064_set_data(kSlot, h[14], later, 2)), kOk);
  step_ns(5'000'000);
  const auto frames = alpha.frames();
  ASSERT_EQ(frames.size(), 15u);
  // Buffer order: 100h, then 101h (chosen already), then 10Eh from buffer 1.
  EXPECT_EQ(candump_text(frames[2]), "10E#BBCC");
  EXPECT_EQ(wait_calls(15).size(), 15u);  // one message routine call per frame
}

// The SL-CANi's row in canemu status.
ipc::StatusNode node_of(const testing::Daemon& d, const std::string& name) {
  auto c = testing::connect(d);
  const ipc::StatusReply r = testing::status(c);
  for (uint16_t k = 0; k < r.node_count; ++k) {
    if (ipc::name_of(r.nodes[k].name) == name) {
      return r.nodes[k];
    }
  }
  ADD_FAILURE() << "no node " << name;
  return {};
}

TEST(Sl64Api, AnUnacknowledgedFrameRepeatsUntilClearMsg) {
  // The SL-CANi alone on its bus: nobody acknowledges.
  Sl64Daemon x(
      "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
      "[[device]]\nname = \"sl0\"\nmodel = \"sorcus-sl-cani\"\ncontrollers = [\"can0\"]\n"
      "slot = 1\n");
  ASSERT_EQ(diag(sl064_config_module(kSlot, 100, 5)), kOk);
  const SL064Handle h = Sl64Daemon::object(0x55, _SL064_SEND | _SL064_ACTIVE);
  ASSERT_EQ(diag(sl064_start_com(kSlot)), kOk);
  ASSERT_EQ(diag(sl064_send_data(kSlot, h)), kOk);
  step_ns(20'000'000);
  const ipc::StatusNode before = node_of(x.vci.daemon, "sl0:0");
  EXPECT_EQ(before.tec, 128);  // error-passive, and the ACK errors go on
  EXPECT_GT(before.errors, 100u);
  step_ns(1'000'000);
  EXPECT_GT(node_of(x.vci.daemon, "sl0:0").errors, before.errors);
  // The error routine at TEC 96, no message routine: nothing was sent.
  const auto calls = wait_calls(1);
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_TRUE(calls[0].error);
  EXPECT_EQ(calls[0].value, ULONG{SL064_STATUS_HEAVY});
  EXPECT_EQ(diag(sl064_clear_msg(kSlot, h)), kOk);
  step_ns(1'000'000);  // the attempt on the wire ends
  const uint64_t after = node_of(x.vci.daemon, "sl0:0").errors;
  step_ns(10'000'000);
  EXPECT_EQ(node_of(x.vci.daemon, "sl0:0").errors, after);
}

TEST(Sl64Api, BusOffGoesToTheErrorRoutineWithStatus2AndStopStartLeavesIt) {
  Sl64Daemon x(kConfig, 200);  // 250 kbit/s on a 500 kbit/s bus
  Adapter alpha("alpha");
  Adapter beta("beta");
  ASSERT_EQ(diag(sl064_config_module(kSlot, 100, 5)), kOk);
  const SL064Handle h = Sl64Daemon::object(0x100, _SL064_SEND | _SL064_ACTIVE);
  ASSERT_EQ(diag(sl064_start_com(kSlot)), kOk);
  ASSERT_EQ(diag(sl064_send_data(kSlot, h)), kOk);
  // alpha and beta talk: their error flags destroy the SL-CANi's frames.
  for (int k = 0; k < 100; ++k) {
    alpha.post(data(0x200, {1, 2, 3, 4}));
    beta.post(data(0x201, {1}));
  }
  step_ns(60'000'000);
  const auto calls = wait_calls(2);
  ASSERT_EQ(calls.size(), 2u);
  EXPECT_EQ(calls[0].value, ULONG{SL064_STATUS_HEAVY});
  EXPECT_EQ(calls[1].value, ULONG{SL064_STATUS_BUS_OFF});
  EXPECT_EQ(node_of(x.vci.daemon, "sl0:0").state, static_cast<uint8_t>(model::ErrorState::bus_off));
  EXPECT_EQ(diag(sl064_clear_msg(kSlot, h)), kOk);
  EXPECT_EQ(diag(sl064_stop_com(kSlot)), kOk);
  EXPECT_EQ(diag(sl064_start_com(kSlot)), kOk);
  step_ns(20'000'000);
  const ipc::StatusNode after = node_of(x.vci.daemon, "sl0:0");
  EXPECT_EQ(after.state, static_cast<uint8_t>(model::ErrorState::active));
  EXPECT_EQ(after.tec, 0);
  EXPECT_EQ(after.rec, 0);
}

TEST(Sl64Api, EepromWordsSurviveACanemudRestart) {
  char dir[] = "/tmp/canemu-sl64-XXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string state = std::string(dir) + "/sl0.eeprom";
  const std::string config =
      "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
      "[[device]]\nname = \"sl0\"\nmodel = \"sorcus-sl-cani\"\ncontrollers = [\"can0\"]\n"
      "slot = 1\neeprom = \"" +
      state + "\"\n";
  {
    Sl64Daemon x(config);
    EXPECT_EQ(canemu_sl064_eeprom_write(kSlot, 40, 0x1234), 0);
    EXPECT_EQ(canemu_sl064_eeprom_write(kSlot, SL064_EEPROM_ID_FORMAT, 1), 0);
  }
  {
    Sl64Daemon x(config);
    USHORT w = 0;
    EXPECT_EQ(canemu_sl064_eeprom_read(kSlot, 40, &w), 0);
    EXPECT_EQ(w, 0x1234);
    EXPECT_EQ(canemu_sl064_eeprom_read(kSlot, SL064_EEPROM_TQ, &w), 0);
    EXPECT_EQ(w, 100);
    // 29-bit identifiers from word 14.
    ASSERT_EQ(diag(sl064_config_module(kSlot, 0, 0)), kOk);
    Sl64Daemon::object(268435447, _SL064_PASSIVE);
  }
  std::remove(state.c_str());
  ::rmdir(dir);
}

TEST(Sl64Api, Function14GivesAServiceRequestThatEvaluateSrqReads) {
  Sl64Daemon x;
  Adapter alpha("alpha");
  const USHORT task = canemu_sl064_driver_task(kSlot);
  EXPECT_EQ(task, 0x41);
  ASSERT_EQ(diag(sl064_config_module(kSlot, task, SL064_SRQ_SERVICE_FUNC)), kOk);
  SL064MsgType c{0x20, _SL064_PASSIVE, task, SL064_SRQ_SERVICE_FUNC};
  SL064Handle h = 0;
  ASSERT_EQ(diag(sl064_config_msg_object(kSlot, &h, &c)), kOk);
  ASSERT_EQ(diag(sl064_start_com(kSlot)), kOk);
  UCHAR slot = 9;
  SL064Handle got = 9;
  EXPECT_EQ(sl064_evaluate_srq(&slot, &got), 0);
  EXPECT_EQ(got, 0);  // none yet
  alpha.post(data(0x20, {5}));
  step_ns(1'000'000);
  EXPECT_EQ(canemu_sl064_wait_srq(10'000), 0x0180);
  EXPECT_EQ(sl064_evaluate_srq(&slot, &got), 0);
  EXPECT_EQ(slot, kSlot);
  EXPECT_EQ(got, h);
}

TEST(Sl64Api, EachMaskRoutineCallReadsItsOwnFramesIdInStepTime) {
  Sl64Daemon x;
  Adapter alpha("alpha");
  {
    std::lock_guard lock(g_mutex);
    g_ids.clear();
  }
  ASSERT_EQ(canemu_sl064_install_message_service(100, 6, monitor_service), 0);
  ASSERT_EQ(diag(sl064_config_module(kSlot, 100, 5)), kOk);
  Sl64Daemon::object(0x10, _SL064_PASSIVE);
  ULONG mask = 0;  // every unconfigured frame to the routine
  ASSERT_EQ(diag(sl064_set_acceptance_mask(kSlot, &mask, 0, 100, 6)), kOk);
  ASSERT_EQ(diag(sl064_start_com(kSlot)), kOk);
  const std::vector<ULONG> ids = {0x101, 0x202, 0x303, 0x404, 0x505, 0x606, 0x707, 0x7EF};
  for (ULONG id : ids) {
    alpha.post(data(id, {1}));
  }
  step_ns(5'000'000);  // all eight frames in one step, before any routine runs
  std::vector<ULONG> got;
  {
    std::unique_lock lock(g_mutex);
    g_cv.wait_for(lock, std::chrono::seconds(10), [&] { return g_ids.size() >= ids.size(); });
    got = g_ids;
  }
  EXPECT_EQ(got, ids);
  EXPECT_EQ(canemu_sl064_lost_calls(kSlot), 0u);
  ULONG last = 0;  // outside a routine: the last unconfigured frame's
  EXPECT_EQ(diag(sl064_get_id(kSlot, 0, &last)), kOk);
  EXPECT_EQ(last, 0x7EFu);
  EXPECT_EQ(canemu_sl064_install_message_service(100, 6, nullptr), 0);
}

TEST(Sl64Api, TheExampleTalksBetweenTwoSlots) {
  Sl64Daemon x(std::string(kConfig) +
               "\n[[device]]\nname = \"sl1\"\nmodel = \"sorcus-sl-cani\"\ncontrollers = "
               "[\"can0\"]\nslot = 2\n");
  canemu_sl064_connect(nullptr);  // the example's slots must be free
  ExampleProgram talk;
  ASSERT_NO_FATAL_FAILURE(talk.start({SL64_TALK_PATH, "1", "2", "2"}, x.vci.daemon.socket()));
  talk.step_until_exit();
  const std::string text = talk.output();
  const int status = talk.status;
  ASSERT_TRUE(WIFEXITED(status)) << text;
  EXPECT_EQ(WEXITSTATUS(status), 0) << text;
  // Per frame: the sender's routine (after the acknowledgement) and the receiver's, in the
  // order the emulation made them, then the data read.
  EXPECT_EQ(text,
            "service routine 100/4: handle 1\n"
            "service routine 100/4: handle 1\n"
            "slot 2 received ID 7: 2 bytes: C0 00\n"
            "service routine 100/4: handle 1\n"
            "service routine 100/4: handle 1\n"
            "slot 2 received ID 7: 2 bytes: C0 01\n");
}

}  // namespace
}  // namespace canemu::testing
