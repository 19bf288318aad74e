// The VCI C API (libvcinpl) on LIN buses with other nodes: an adapter a program makes of its
// own, simulated nodes ([[lin_node]]) where the program is the only real node, and a commander
// with two responders in three processes.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "vci_c_lin_support.hpp"

namespace canemu::testing {
namespace {

TEST(VciCLin, AProgramMakesAnAdapterOfItsOwnOnALinBus) {
  VciDaemon d(kLinAdapters);
  VCIID id{};
  char name[32] = {};
  ASSERT_EQ(canemuCreateDevice("lin0", "mylin", &id, name, sizeof name), VCI_OK);
  EXPECT_STREQ(name, "mylin");
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id, &dev), VCI_OK);
  VCIDEVICECAPS caps{};
  ASSERT_EQ(vciDeviceGetCaps(dev, &caps), VCI_OK);
  EXPECT_EQ(caps.BusCtrlCount, 1);
  EXPECT_EQ(caps.BusCtrlTypes[0], VCI_LIN_CTRL(LIN_CTRL_UNKNOWN));
  HANDLE control = nullptr;
  HANDLE monitor = nullptr;
  ASSERT_EQ(linControlOpen(dev, 0, &control), VCI_OK);
  ASSERT_EQ(linMonitorOpen(dev, 0, FALSE, &monitor), VCI_OK);
  ASSERT_EQ(linMonitorInitialize(monitor, 16, 1), VCI_OK);
  ASSERT_EQ(linMonitorActivate(monitor, TRUE), VCI_OK);
  ASSERT_EQ(linControlInitialize(control, LIN_OPMODE_MASTER, kRate), VCI_OK);
  ASSERT_EQ(linControlStart(control, TRUE), VCI_OK);
  LinAdapter slave("alpha");
  ASSERT_EQ(slave.write(false, lin_data(0x33, {0x99})), VCI_OK);
  const int64_t t0 = step_to(1'000'000);
  LINMSG header = lin_data(0x33, {}, true, true);
  ASSERT_EQ(linControlWriteMessage(control, TRUE, &header), VCI_OK);
  step_to(10'000'000);
  LINMSG m{};
  ASSERT_EQ(linMonitorPeekMessage(monitor, &m), VCI_OK);  // the start
  ASSERT_EQ(linMonitorPeekMessage(monitor, &m), VCI_OK);
  EXPECT_EQ(text_of(m), frame_text(stamp(frame_end(t0, 1)), 0x33, {0x99}, true, false));
  EXPECT_EQ(canControlOpen(dev, 0, &control), VCI_E_INVALIDARG);  // not a CAN controller
  auto c = connect(d.daemon);
  const ipc::StatusReply s = status(c);
  ASSERT_EQ(s.node_count, 7);  // three adapters' two controllers, then mylin:0
  EXPECT_EQ(ipc::name_of(s.nodes[6].name), "mylin:0");
  EXPECT_EQ(s.nodes[6].lin, static_cast<uint8_t>(ipc::WireLinState::online));
  EXPECT_EQ(s.nodes[6].frames_sent, 1U);
  linMonitorClose(monitor);
  linControlClose(control);
  vciDeviceClose(dev);
  EXPECT_EQ(canemuRemoveDevice("mylin"), VCI_OK);
}

// ---- with simulated nodes ([[lin_node]]): the program is the only real node ----

// A commander (bcm) runs a schedule of two slots, 10 ms each: 0x10 (answered by the program)
// and 0x11 (answered by the commander itself).
const char* const kWithCommander =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\n\n"
    "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n"
    "lin = [\"lin0\"]\n\n"
    "[[lin_node]]\nname = \"bcm\"\nbus = \"lin0\"\nschedule = \"normal\"\n\n"
    "[[lin_node.schedules]]\nname = \"normal\"\n"
    "slots = [{ frame = 0x10, delay = \"10ms\" }, { frame = 0x11, delay = \"10ms\" }]\n\n"
    "[[lin_node.response]]\nid = 0x11\ndata = [0x55]\nchecksum = \"classic\"\n";

TEST(VciCLinNodes, AProgramAnswersASimulatedCommandersScheduleAtItsSlotTimes) {
  VciDaemon d(kWithCommander);
  LinAdapter slave("alpha");
  ASSERT_EQ(slave.write(false, lin_data(0x10, {0xA1, 0xA2})), VCI_OK);
  step_to(45'000'000);  // slots at 0, 10, 20, 30 and 40 ms
  const int64_t ms = 1'000'000;
  EXPECT_EQ(slave.texts(),
            (Texts{frame_text(stamp(frame_end(0, 2)), 0x10, {0xA1, 0xA2}, true, true),
                   frame_text(stamp(frame_end(10 * ms, 1)), 0x11, {0x55}, false, false),
                   frame_text(stamp(frame_end(20 * ms, 2)), 0x10, {0xA1, 0xA2}, true, true),
                   frame_text(stamp(frame_end(30 * ms, 1)), 0x11, {0x55}, false, false),
                   frame_text(stamp(frame_end(40 * ms, 2)), 0x10, {0xA1, 0xA2}, true, true)}));
  // canemu status: the simulated commander sent 5 headers and 2 responses of its own.
  auto c = connect(d.daemon);
  const ipc::StatusReply s = status(c);
  ASSERT_EQ(s.node_count, 3);  // alpha:0, alpha:1 (LIN), bcm
  EXPECT_EQ(ipc::name_of(s.nodes[2].name), "bcm");
  EXPECT_EQ(s.nodes[2].bus, 1);
  EXPECT_EQ(s.nodes[2].lin, static_cast<uint8_t>(ipc::WireLinState::online));
  EXPECT_EQ(s.nodes[2].frames_sent, 7U);
  EXPECT_EQ(s.nodes[2].frames_received, 5U);
  EXPECT_EQ(ipc::name_of(s.nodes[1].name), "alpha:1");
  EXPECT_EQ(s.nodes[1].frames_sent, 3U);  // its responses
  EXPECT_EQ(s.nodes[1].frames_received, 2U);
  EXPECT_EQ(s.buses[1].frames, 5U);
  EXPECT_EQ(s.buses[1].error_frames, 0U);
}

// Simulated responders: one answers 0x20 (enhanced), one 0x21 (classic), one is switched off.
const char* const kWithResponders =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\n\n"
    "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n"
    "lin = [\"lin0\"]\n\n"
    "[[lin_node]]\nname = \"doorleft\"\nbus = \"lin0\"\n\n"
    "[[lin_node.response]]\nid = 0x20\ndata = [0x01, 0x02]\n\n"
    "[[lin_node]]\nname = \"doorright\"\nbus = \"lin0\"\n\n"
    "[[lin_node.response]]\nid = 0x21\ndata = [0x03]\nchecksum = \"classic\"\n\n"
    "[[lin_node]]\nname = \"seat\"\nbus = \"lin0\"\npowered = false\n\n"
    "[[lin_node.response]]\nid = 0x22\ndata = [0x04]\n";

TEST(VciCLinNodes, SimulatedRespondersAnswerAProgramsHeaders) {
  VciDaemon d(kWithResponders);
  LinAdapter master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x20, {}, true, true)), VCI_OK);
  const int64_t t1 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x21, {}, true, true)), VCI_OK);
  const int64_t t2 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x22, {}, true, true)), VCI_OK);  // the seat is off
  step_to(20'000'000);
  EXPECT_EQ(master.texts(),
            (Texts{frame_text(stamp(frame_end(t0, 2)), 0x20, {0x01, 0x02}, true, false),
                   frame_text(stamp(frame_end(t1, 1)), 0x21, {0x03}, false, false),
                   event_text(stamp(no_response_at(t2)), LIN_MSGTYPE_ERROR, LIN_ERROR_SLNORE, 0)}));
  auto c = connect(d.daemon);
  const ipc::StatusReply s = status(c);
  ASSERT_EQ(s.node_count, 5);
  EXPECT_EQ(ipc::name_of(s.nodes[4].name), "seat");
  EXPECT_EQ(s.nodes[4].lin, static_cast<uint8_t>(ipc::WireLinState::offline));
  EXPECT_EQ(s.nodes[2].frames_sent, 1U);  // doorleft's response
}

// A commander (this test, on alpha) and two responders in two other processes (vci_c_talk lin
// on beta and gamma, each printing the first three frames or errors it sees), in stepped time.
// Both answer 21h: beta with 11h, gamma with 13h; the wire carries 11h & 13h = 11h, so gamma
// reads back another bit than it sent (a bit error at that character's stop bit) and stops
// (it does not receive that frame), and beta's frame goes through whole. When the programs have
// ended, their controllers are reset: a header for 21h then finds nobody.
TEST(VciCLinProcesses, ACommanderAndTwoRespondersCollideAndEnd) {
  VciDaemon d(kLinAdapters);
  const std::string env = "CANEMU_SOCKET=" + d.daemon.socket() + " ";
  FILE* beta = ::popen((env + VCI_C_TALK_PATH + " lin beta 21 11").c_str(), "r");
  FILE* gamma = ::popen((env + VCI_C_TALK_PATH + " lin gamma 21 13").c_str(), "r");
  ASSERT_NE(beta, nullptr);
  ASSERT_NE(gamma, nullptr);
  auto lines = [](FILE* f) {
    std::vector<std::string> got;
    char line[128];
    while (std::fgets(line, sizeof line, f) != nullptr) {
      got.emplace_back(line);
    }
    return got;
  };
  char line[128] = {};
  ASSERT_NE(std::fgets(line, sizeof line, beta), nullptr);
  EXPECT_STREQ(line, "ready\n");
  ASSERT_NE(std::fgets(line, sizeof line, gamma), nullptr);
  EXPECT_STREQ(line, "ready\n");
  LinAdapter master("alpha", LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS);
  const int64_t t0 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x21, {}, true, true)), VCI_OK);
  const int64_t t1 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x10, {0x55})), VCI_OK);
  const int64_t t2 = step_to(10'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x22, {}, true, true)), VCI_OK);  // nobody has 22h
  step_to(10'000'000);
  auto us = [](int64_t ns) { return std::to_string(stamp(ns)) + " us: "; };
  EXPECT_EQ(lines(beta),
            (Texts{us(frame_end(t0, 1)) + "21#11 (mine)\n", us(frame_end(t1, 1)) + "10#55\n",
                   us(no_response_at(t2)) + "error 4\n"}));
  // gamma, stopped by its bit error, takes no part in the rest of that frame.
  EXPECT_EQ(lines(gamma),
            (Texts{us(after_bits(t0, 44)) + "error 1\n", us(frame_end(t1, 1)) + "10#55\n",
                   us(no_response_at(t2)) + "error 4\n"}));
  EXPECT_EQ(::pclose(beta), 0);
  EXPECT_EQ(::pclose(gamma), 0);
  const int64_t t3 = step_to(1'000'000);
  ASSERT_EQ(master.write(true, lin_data(0x21, {}, true, true)), VCI_OK);
  step_to(10'000'000);
  EXPECT_EQ(master.texts(),
            (Texts{frame_text(stamp(frame_end(t0, 1)), 0x21, {0x11}, true, false),
                   frame_text(stamp(frame_end(t1, 1)), 0x10, {0x55}, true, true),
                   event_text(stamp(no_response_at(t2)), LIN_MSGTYPE_ERROR, LIN_ERROR_SLNORE, 0),
                   event_text(stamp(no_response_at(t3)), LIN_MSGTYPE_ERROR, LIN_ERROR_SLNORE, 0)}));
}

}  // namespace
}  // namespace canemu::testing
