// The X-CAN-2i in canemud: the device model in the configuration, its interfaces as nodes
// (status, faults), and the protocol's X-CAN requests checked field by field, with blocking
// services answered at their simulated instant.
#include "canemu/daemon/sorcus/xcan_service.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "daemon_test_support.hpp"
#include "sorcus_service_support.hpp"

namespace canemu::daemon {
namespace {

using model::sorcus::XcanVariant;

// can0 high-speed, can1 low-speed (both 125 kbit/s): an X-CAN-2i/M on them.
const char* const kConfig =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 125000\n\n"
    "[[bus]]\nname = \"can1\"\nkind = \"can\"\nbitrate = 125000\ntransceiver = \"low-speed\"\n\n"
    "[[device]]\nname = \"xcan0\"\nmodel = \"sorcus-x-can-2i\"\ncontrollers = [\"can0\", "
    "\"can1\"]\n";

std::unique_ptr<Simulation> world(const std::string& text = kConfig) {
  auto config = parse_config(text, "x.toml");
  EXPECT_TRUE(config) << (config ? "" : config.error().front());
  return std::move(*Simulation::build(*config));
}

std::vector<std::string> errors_of(const std::string& devices) {
  const std::string text =
      "[[bus]]\nname = \"hs\"\nkind = \"can\"\nbitrate = 125000\n\n"
      "[[bus]]\nname = \"ls\"\nkind = \"can\"\nbitrate = 125000\ntransceiver = \"low-speed\"\n\n"
      "[[bus]]\nname = \"fd\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n\n" +
      devices;
  auto config = parse_config(text, "x.toml");
  return config ? std::vector<std::string>{} : config.error();
}

TEST(XcanConfig, TheVariantFollowsTheTransceiversOfTheTwoBuses) {
  auto m = world();
  ASSERT_EQ(m->devices().xcan().size(), 1u);
  EXPECT_EQ(m->devices().find_xcan("xcan0")->module().variant(), XcanVariant::m);
  EXPECT_TRUE(m->devices().exists("xcan0"));
  auto h = world(
      "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 125000\n\n"
      "[[device]]\nname = \"x\"\nmodel = \"sorcus-x-can-2i\"\ncontrollers = [\"can0\", "
      "\"can0\"]\n");
  EXPECT_EQ(h->devices().find_xcan("x")->module().variant(), XcanVariant::h);
  // In the device list with its model and buses, without a VCI object id (the VCI's device
  // enumeration leaves it out).
  auto r = ipc::make_message<ipc::DeviceListReply>();
  fill_device_list(*h, r);
  EXPECT_EQ(r.total, 1u);
  ASSERT_EQ(r.count, 1u);
  EXPECT_EQ(ipc::name_of(r.devices[0].name), "x");
  EXPECT_EQ(r.devices[0].model, static_cast<uint8_t>(ipc::WireDeviceModel::sorcus_x_can_2i));
  EXPECT_EQ(r.devices[0].controller_count, 2u);
  EXPECT_EQ(ipc::name_of(r.devices[0].buses[0]), "can0");
  EXPECT_EQ(ipc::name_of(r.devices[0].buses[1]), "can0");
  EXPECT_EQ(r.devices[0].vci_id, 0u);
  EXPECT_EQ(r.devices[0].ephemeral, 0u);
}

TEST(XcanConfig, TwoClassicBusesInAnOrderAVariantHas) {
  const std::string head = "[[device]]\nname = \"x\"\nmodel = \"sorcus-x-can-2i\"\n";
  EXPECT_EQ(errors_of(head + "controllers = [\"hs\", \"ls\"]\n"), std::vector<std::string>{});
  EXPECT_EQ(errors_of(head + "controllers = [\"ls\", \"ls\"]\n"), std::vector<std::string>{});
  EXPECT_EQ(
      errors_of(head + "controllers = [\"hs\"]\n"),
      std::vector<std::string>{
          "x.toml:21:15: device[0].controllers: 1 controllers; an X-CAN-2i has 2 interfaces"});
  EXPECT_EQ(errors_of(head + "controllers = [\"ls\", \"hs\"]\n"),
            std::vector<std::string>{
                "x.toml:21:15: device[0].controllers: interface 0 low-speed and interface 1 "
                "high-speed: no X-CAN-2i variant has that (/M has interface 0 high-speed)"});
  EXPECT_EQ(errors_of(head + "controllers = [\"hs\", \"fd\"]\n"),
            std::vector<std::string>{"x.toml:21:15: device[0].controllers: \"fd\" is a CAN FD bus; "
                                     "the 82527 is a classic CAN controller"});
}

// mdd_version gates what the manual marks «ab MDD Version 3.C» (docs/sorcus.md); 3.C unless set.
TEST(XcanConfig, TheMddVersionIsTheManualsNumberAndOnlyAModuleHasOne) {
  EXPECT_EQ(world()->devices().find_xcan("xcan0")->module().mdd_version(), model::sorcus::kMdd3C);
  auto old = world(std::string(kConfig) + "mdd_version = \"3.B\"\n");
  EXPECT_EQ(old->devices().find_xcan("xcan0")->module().mdd_version(),
            (model::sorcus::MddVersion{3, 'B'}));
  const std::string head =
      "[[device]]\nname = \"x\"\nmodel = \"sorcus-x-can-2i\"\ncontrollers = [\"hs\", \"hs\"]\n";
  EXPECT_EQ(
      errors_of(head + "mdd_version = \"3C\"\n"),
      std::vector<std::string>{"x.toml:22:15: device[0].mdd_version: \"3C\": a version as the "
                               "manual writes it, a digit, a dot and a capital letter "
                               "(\"3.C\")"});
  EXPECT_EQ(errors_of("[[device]]\nname = \"i\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = "
                      "[\"hs\"]\nmdd_version = \"3.C\"\n"),
            std::vector<std::string>{"x.toml:22:15: device[0].mdd_version: only an X-CAN-2i "
                                     "(sorcus-x-can-2i) has an MDD"});
}

// buffer_load_time: how long loading a buffer takes (docs/sorcus.md, checklist 6); 0 unless set.
TEST(XcanConfig, TheBufferLoadTimeIsADurationUpToAMillisecond) {
  EXPECT_EQ(world()->devices().find_xcan("xcan0")->module().buffer_load_time(), 0);
  auto slow = world(std::string(kConfig) + "buffer_load_time = \"5us\"\n");
  EXPECT_EQ(slow->devices().find_xcan("xcan0")->module().buffer_load_time(), 5'000);
  const std::string head =
      "[[device]]\nname = \"x\"\nmodel = \"sorcus-x-can-2i\"\ncontrollers = [\"hs\", \"hs\"]\n";
  EXPECT_EQ(errors_of(head + "buffer_load_time = \"2ms\"\n"),
            std::vector<std::string>{"x.toml:22:20: device[0].buffer_load_time: \"2ms\": a "
                                     "duration from \"0us\" to \"1ms\" (\"5us\")"});
  EXPECT_EQ(errors_of("[[device]]\nname = \"i\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = "
                      "[\"hs\"]\nbuffer_load_time = \"5us\"\n"),
            std::vector<std::string>{"x.toml:22:20: device[0].buffer_load_time: only an X-CAN-2i "
                                     "(sorcus-x-can-2i) loads buffers"});
}

TEST(XcanNodes, StatusShowsBothInterfacesOnTheirBuses) {
  auto m = world();
  auto r = ipc::make_message<ipc::StatusReply>();
  fill_status(*m, r);
  ASSERT_EQ(r.node_count, 2u);
  EXPECT_EQ(ipc::name_of(r.nodes[0].name), "xcan0:0");
  EXPECT_EQ(r.nodes[0].bus, 0u);
  EXPECT_EQ(ipc::name_of(r.nodes[1].name), "xcan0:1");
  EXPECT_EQ(r.nodes[1].bus, 1u);
  EXPECT_EQ(m->devices().node_name(1, m->devices().find_xcan("xcan0")->module().chip(1).node()),
            "xcan0:1");
}

TEST(XcanNodes, ALineErrorReachesTheModulesTransceiverFromItsInstantToItsEnd) {
  auto m = world();
  daemon_test::apply_scenario(*m, R"([[fault]]
at = "2ms"
until = "5ms"
node = "xcan0:1"
effect = "line_error"
)");
  model::sorcus::XcanModule& x = m->devices().find_xcan("xcan0")->module();
  m->scheduler().run_until(model::SimTime::from_ns(1'999'999));
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.bus_state(1)) & XCAN_LINE_ERROR, 0u);
  m->scheduler().run_until(model::SimTime::from_ns(2'000'000));
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.bus_state(1)) & XCAN_LINE_ERROR, XCAN_LINE_ERROR);
  m->scheduler().run_until(model::SimTime::from_ns(4'999'999));
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.bus_state(1)) & XCAN_LINE_ERROR, XCAN_LINE_ERROR);
  m->scheduler().run_until(model::SimTime::from_ns(5'000'000));
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.bus_state(1)) & XCAN_LINE_ERROR, 0u);
}

TEST(XcanNodes, ABusOffFaultTakesTheInterfaceOffAtItsInstant) {
  auto m = world();
  model::sorcus::XcanModule& x = m->devices().find_xcan("xcan0")->module();
  CPS_XCAN send{};
  send.usDevice = DEVICE_BUS_OUT;
  send.ulCanID = 0x100;
  ASSERT_TRUE(x.open_channel(send, false));  // the bus is on from the first object
  daemon_test::apply_scenario(*m, R"([[fault]]
at = "1ms"
node = "xcan0:0"
effect = "bus_off"
)");
  m->scheduler().run_until(model::SimTime::from_ns(999'999));
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.bus_state(0)), XCAN_BUS_ON);
  m->scheduler().run_until(model::SimTime::from_ns(1'000'000));
  EXPECT_EQ(XCAN_STATUS_FLAGS(x.bus_state(0)) & XCAN_BUS_OFF, XCAN_BUS_OFF);
  EXPECT_TRUE(x.chip(0).confinement().bus_off());
}

TEST(XcanNodes, AnInterfaceCannotBabble) {
  auto m = world();
  const auto refused = daemon_test::scenario_refusal(*m, R"([[fault]]
at = "0s"
node = "xcan0:0"
effect = "babble"
id = 0x100
duration = "1ms"
)");
  ASSERT_FALSE(refused.empty());
  EXPECT_NE(refused.front().find("xcan0:0 is an X-CAN-2i interface"), std::string::npos)
      << refused.front();
}

// The service with every packet it sends kept.
struct Service : daemon_test::KeptPackets<XcanService> {
  Service() : KeptPackets(world()) {}
  ipc::XcanReply call(XcanSession& s, const ipc::XcanRequest& m) {
    handle(s, m);
    EXPECT_EQ(sent.size(), 1u);
    return reply(0);
  }
  ipc::XcanReply reply(std::size_t k) const { return packet<ipc::XcanReply>(k); }
  // The ErrorReply code of the one packet sent.
  uint32_t refused(XcanSession& s, const ipc::XcanRequest& m) {
    handle(s, m);
    EXPECT_EQ(sent.size(), 1u);
    return packet<ipc::ErrorReply>(0).code;
  }
};

ipc::XcanRequest request(ipc::XcanOp op, uint32_t channel = 0) {
  auto m = ipc::make_message<ipc::XcanRequest>(7);
  m.op = static_cast<uint16_t>(op);
  m.channel = channel;
  return m;
}

ipc::XcanRequest open(const CPS_XCAN& cps, uint16_t flags = 0) {
  auto m = request(ipc::XcanOp::open);
  ipc::copy_name(m.device, "xcan0");
  std::memcpy(m.cps, &cps, sizeof cps);
  m.flags = flags;
  return m;
}

constexpr uint32_t kBad = static_cast<uint32_t>(ipc::ErrorCode::bad_argument);

TEST(XcanService, EveryFieldIsCheckedAgainstItsOwner) {
  Service x;
  XcanSession s;
  EXPECT_EQ(x.refused(s, request(static_cast<ipc::XcanOp>(0))), kBad);
  EXPECT_EQ(x.refused(s, request(static_cast<ipc::XcanOp>(11))), kBad);
  auto flagged = request(ipc::XcanOp::info, 1);
  flagged.flags = ipc::kXcanCallback;  // only for open
  EXPECT_EQ(x.refused(s, flagged), kBad);
  auto reserved = request(ipc::XcanOp::info, 1);
  reserved.reserved = 1;
  EXPECT_EQ(x.refused(s, reserved), kBad);
  auto unterminated = request(ipc::XcanOp::module_check);
  std::memset(unterminated.device, 'x', sizeof unterminated.device);
  EXPECT_EQ(x.refused(s, unterminated), kBad);
  auto nobody = request(ipc::XcanOp::module_check);
  ipc::copy_name(nobody.device, "nobody");
  EXPECT_EQ(x.refused(s, nobody), static_cast<uint32_t>(ipc::ErrorCode::no_such_bus));
  auto check = request(ipc::XcanOp::module_check);
  ipc::copy_name(check.device, "xcan0");
  EXPECT_EQ(x.call(s, check).value, static_cast<uint32_t>(XcanVariant::m));

  // A channel of nobody's, and one of another session's, are no channel.
  EXPECT_EQ(x.call(s, request(ipc::XcanOp::info, 1)).error, ERR_XCAN_INVALID_HANDLE);
  CPS_XCAN send{};
  send.usDevice = DEVICE_BUS_OUT;
  send.ulCanID = 0x100;
  const ipc::XcanReply opened = x.call(s, open(send));
  EXPECT_EQ(opened.error, ERR_OK);
  EXPECT_EQ(opened.channel, 1u);
  XcanSession other;
  EXPECT_EQ(x.call(other, request(ipc::XcanOp::info, 1)).error, ERR_XCAN_INVALID_HANDLE);
  // The model judges the CPS and the values.
  CPS_XCAN bad = send;
  bad.usDevice = 9;
  EXPECT_EQ(x.call(s, open(bad)).error, ERR_XCAN_INVALID_CPS);
  auto big = request(ipc::XcanOp::write_block, 1);
  big.size = 17;
  EXPECT_EQ(x.call(s, big).error, ERR_XCAN_DATA_SIZE);
  auto nine = request(ipc::XcanOp::write_block, 1);
  nine.size = 9;
  EXPECT_EQ(x.call(s, nine).error, ERR_XCAN_DATA_SIZE);
  auto wide = request(ipc::XcanOp::control, 1);
  wide.value = 0x10001;  // CMD_START in the low half: still refused
  EXPECT_EQ(x.refused(s, wide), kBad);
  auto info = request(ipc::XcanOp::info, 1);
  info.value = INFO_XCAN_MSG_COUNT;
  EXPECT_EQ(x.call(s, info).error, ERR_OK);
  x.service.close_all(s);
  EXPECT_EQ(x.call(s, info).error, ERR_XCAN_INVALID_HANDLE);
}

TEST(XcanService, ABlockingSendIsAnsweredAtItsTimeoutAndCloseEndsTheWaitFirst) {
  Service x;
  XcanSession s;
  CPS_XCAN ctrl{};
  ctrl.usDevice = DEVICE_CTRL;
  ctrl.usIndexFirst = ctrl.usIndexLast = XCAN_BUS_CTRL_INDEX;
  ASSERT_EQ(x.call(s, open(ctrl)).error, ERR_OK);
  CPS_XCAN send{};
  send.usDevice = DEVICE_BUS_OUT;
  send.usFlags = XCAN_NO_INT;
  send.usTimeout = 1000;
  send.ulCanID = 0x100;
  const uint32_t h = x.call(s, open(send)).channel;
  x.sim->scheduler().run_until(model::SimTime::from_ns(1'000'000));
  // Nobody acknowledges on can0: the send waits 1000 us and gives up.
  auto write = request(ipc::XcanOp::write_block, h);
  write.header.request_id = 9;
  write.size = 1;
  x.sent.clear();
  x.service.handle(s, write, x.send);
  EXPECT_TRUE(x.sent.empty());
  x.sim->scheduler().run_until(model::SimTime::from_ns(1'999'999));
  EXPECT_TRUE(s.outbox.empty());
  x.sim->scheduler().run_until(model::SimTime::from_ns(2'000'000));
  ASSERT_EQ(s.outbox.size(), 1u);
  ipc::XcanReply r{};
  std::memcpy(&r, s.outbox.front().data(), sizeof r);
  EXPECT_EQ(r.header.request_id, 9u);
  EXPECT_EQ(r.error, ERR_XCAN_TIMEOUT);
  EXPECT_EQ(r.sim_time_ns, 2'000'000);
  s.outbox.clear();

  // Closed while a send waits: the send is answered first, then the close.
  write.header.request_id = 10;
  x.service.handle(s, write, x.send);
  auto close = request(ipc::XcanOp::close, h);
  close.header.request_id = 11;
  x.sent.clear();
  x.service.handle(s, close, x.send);
  ASSERT_EQ(x.sent.size(), 2u);
  EXPECT_EQ(x.reply(0).header.request_id, 10u);
  EXPECT_EQ(x.reply(0).error, ERR_XCAN_INVALID_HANDLE);
  EXPECT_EQ(x.reply(1).header.request_id, 11u);
  EXPECT_EQ(x.reply(1).error, ERR_OK);
  x.sim->scheduler().run_until(model::SimTime::from_ns(10'000'000));
  EXPECT_TRUE(s.outbox.empty());
}

TEST(XcanService, ASessionThatGoesReleasesItsChannelsForOthers) {
  Service x;
  XcanSession first;
  XcanSession second;
  CPS_XCAN general{};
  general.usDevice = DEVICE_BUS_OUT;
  general.usFlags = _CP_EXCLUSIVE;
  general.ulCanID = XCAN_GENERAL_ID;
  general.usFlags = _CP_EXCLUSIVE | XCAN_NO_INT;
  general.usTimeout = 1000;
  const uint32_t h = x.call(first, open(general)).channel;
  EXPECT_EQ(x.call(second, open(general)).error, ERR_XCAN_CHANNEL_BUSY);
  // The first client goes while its send waits (nobody acknowledges): nothing is answered to
  // anybody, now or at the timeout.
  auto write = request(ipc::XcanOp::write_block, h);
  XCAN_MESSAGE message{};
  message.ulCanId = 0x123;
  std::memcpy(write.data, &message, sizeof message);
  write.size = sizeof message;
  x.sent.clear();
  x.service.handle(first, write, x.send);
  EXPECT_TRUE(x.sent.empty());
  x.service.close_all(first);
  EXPECT_TRUE(first.channels.empty());
  EXPECT_TRUE(first.outbox.empty());
  x.sim->scheduler().run_until(model::SimTime::from_ns(5'000'000));
  EXPECT_TRUE(first.outbox.empty());
  EXPECT_TRUE(second.outbox.empty());
  EXPECT_EQ(x.call(second, open(general)).error, ERR_OK);
}

}  // namespace
}  // namespace canemu::daemon
