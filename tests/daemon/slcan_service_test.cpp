// The SL-CANi in canemud: the device model in the configuration, its EEPROM state file
// (written atomically, read at start-up), its interface as a node (status), and the protocol's
// SL-CANi requests: slots held per client, every sl064_* call answered with its return value
// and diagnosis, service routine calls to the client holding the slot.
#include "canemu/daemon/sorcus/slcan_service.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "daemon_test_support.hpp"
#include "sorcus_service_support.hpp"

namespace canemu::daemon {
namespace {

std::string temp_path(const std::string& name) {
  return "/tmp/canemu-slcan-test-" + std::to_string(::getpid()) + "-" + name;
}

std::string config_with(const std::string& devices) {
  return "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
         "[[bus]]\nname = \"ls\"\nkind = \"can\"\nbitrate = 125000\ntransceiver = "
         "\"low-speed\"\n\n" +
         devices;
}

std::vector<std::string> errors_of(const std::string& devices) {
  auto config = parse_config(config_with(devices), "s.toml");
  return config ? std::vector<std::string>{} : config.error();
}

std::unique_ptr<Simulation> world(const std::string& eeprom = "") {
  std::string d =
      "[[device]]\nname = \"sl0\"\nmodel = \"sorcus-sl-cani\"\ncontrollers = "
      "[\"can0\"]\nslot = 1\n";
  if (!eeprom.empty()) {
    d += "eeprom = \"" + eeprom + "\"\n";
  }
  auto config = parse_config(config_with(d), "s.toml");
  EXPECT_TRUE(config) << (config ? "" : config.error().front());
  auto sim = Simulation::build(*config);
  EXPECT_TRUE(sim) << (sim ? "" : sim.error().front());
  return std::move(*sim);
}

TEST(SlcanConfig, OneHighSpeedClassicBusAndAFreeSlot) {
  const std::string head = "[[device]]\nname = \"s\"\nmodel = \"sorcus-sl-cani\"\n";
  EXPECT_EQ(errors_of(head + "controllers = [\"can0\"]\nslot = 5\n"), std::vector<std::string>{});
  EXPECT_EQ(
      errors_of(head + "controllers = [\"can0\"]\n"),
      std::vector<std::string>{"s.toml:12:1: device[0].slot: missing (an integer is required)"});
  EXPECT_EQ(errors_of(head + "controllers = [\"can0\"]\nslot = 6\n"),
            std::vector<std::string>{"s.toml:16:8: device[0].slot: 6 is outside 0..5"});
  EXPECT_EQ(errors_of(head + "controllers = [\"can0\", \"can0\"]\nslot = 0\n"),
            std::vector<std::string>{
                "s.toml:15:15: device[0].controllers: 2 controllers; an SL-CANi has 1 interface"});
  EXPECT_EQ(errors_of(head + "controllers = [\"ls\"]\nslot = 0\n"),
            std::vector<std::string>{
                "s.toml:15:15: device[0].controllers: \"ls\" is a low-speed bus; the SL-CANi's "
                "transceiver is high-speed (82C250)"});
  EXPECT_EQ(errors_of(head + "controllers = [\"can0\"]\nslot = 0\n" +
                      "[[device]]\nname = \"t\"\nmodel = \"sorcus-sl-cani\"\ncontrollers = "
                      "[\"can0\"]\nslot = 0\n"),
            std::vector<std::string>{
                "s.toml:21:8: device[1].slot: slot 0 is another SL-CANi's (one S-Link per slot)"});
  EXPECT_EQ(errors_of("[[device]]\nname = \"i\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = "
                      "[\"can0\"]\nslot = 0\n"),
            std::vector<std::string>{
                "s.toml:16:8: device[0].slot: only a sorcus-sl-cani device has this key"});
}

TEST(SlcanEepromFile, IsWrittenAtomicallyAndReadBack) {
  const std::string path = temp_path("atomic");
  std::remove(path.c_str());
  model::sorcus::EepromWords w = model::sorcus::slcan_eeprom_defaults();
  EXPECT_EQ(load_eeprom_file(path), w);  // no file: the factory contents
  w[40] = 0xBEEF;
  ASSERT_TRUE(save_eeprom_file(path, w));
  EXPECT_EQ(::access((path + ".tmp").c_str(), F_OK), -1);  // renamed away
  EXPECT_EQ(load_eeprom_file(path), w);
  {
    std::ifstream in(path);
    std::string first, word0;
    std::getline(in, first);
    std::getline(in, word0);
    EXPECT_EQ(first, "# canemu SL-CANi EEPROM: words 0..63, one per line (hex)");
    EXPECT_EQ(word0, "534C");
  }
  {
    std::ofstream out(path);
    out << "# x\n534C\nzz12\n";
  }
  EXPECT_EQ(load_eeprom_file(path).error(),
            path + ":3: \"zz12\" is not an EEPROM word (4 hex digits, one per line)");
  {
    std::ofstream out(path);
    out << "534C\n";
  }
  EXPECT_EQ(load_eeprom_file(path).error(), path + ": 1 EEPROM words, but the SL-CANi has 64");
  std::remove(path.c_str());
}

TEST(SlcanEepromFile, WritesSurviveARestartAndReadOnlyWordsAreRefused) {
  const std::string path = temp_path("restart");
  std::remove(path.c_str());
  {
    auto m = world(path);
    SlcanDevice& d = *m->devices().find_slcan_slot(1);
    EXPECT_EQ(d.state_file(), path);
    ASSERT_TRUE(d.write_eeprom(15, 100));
    ASSERT_TRUE(d.write_eeprom(63, 0x1234));
    EXPECT_EQ(d.write_eeprom(12, 0x20).error(),
              "word 12 is read-only (writable: 13..19 and 32..63)");
    EXPECT_EQ(d.write_eeprom(64, 0).error(), "word 64 does not exist (0..63)");
  }
  auto again = world(path);
  const auto& w = again->devices().find_slcan_slot(1)->module().eeprom();
  EXPECT_EQ(w[15], 100);
  EXPECT_EQ(w[63], 0x1234);
  EXPECT_EQ(w[12], 0x0010);
  std::remove(path.c_str());
}

TEST(SlcanNodes, StatusShowsTheInterfaceOnItsBus) {
  auto m = world();
  auto r = ipc::make_message<ipc::StatusReply>();
  fill_status(*m, r);
  ASSERT_EQ(r.node_count, 1u);
  EXPECT_EQ(ipc::name_of(r.nodes[0].name), "sl0:0");
  EXPECT_EQ(r.nodes[0].bus, 0u);
  EXPECT_TRUE(m->devices().find_node("sl0:0").has_value());
  EXPECT_TRUE(m->devices().exists("sl0"));
}

TEST(SlcanNodes, ABusOffFaultTakesTheSLinkOffAndItCannotBabble) {
  auto m = world();
  daemon_test::apply_scenario(*m, R"([[fault]]
at = "1ms"
node = "sl0:0"
effect = "bus_off"
)");
  model::I82527& chip = m->devices().find_slcan_slot(1)->module().chip();
  m->scheduler().run_until(model::SimTime::from_ns(999'999));
  EXPECT_FALSE(chip.confinement().bus_off());
  m->scheduler().run_until(model::SimTime::from_ns(1'000'000));
  EXPECT_TRUE(chip.confinement().bus_off());
  const auto refused = daemon_test::scenario_refusal(*m, R"([[fault]]
at = "2ms"
node = "sl0:0"
effect = "babble"
id = 0x100
duration = "1ms"
)",
                                                     "b.toml");
  ASSERT_FALSE(refused.empty());
  EXPECT_NE(refused.front().find("sl0:0 is an SL-CANi S-Link"), std::string::npos)
      << refused.front();
}

// The service with every packet it sends kept.
struct Service : daemon_test::KeptPackets<SlcanService> {
  Service() : KeptPackets(world()) {}
  ipc::SlcanReply call(SlcanSession& s, ipc::SlcanOp op, uint8_t slot = 1,
                       void (*fill)(ipc::SlcanRequest&) = nullptr) {
    auto m = ipc::make_message<ipc::SlcanRequest>(9);
    m.op = static_cast<uint16_t>(op);
    m.slot = slot;
    if (fill != nullptr) {
      fill(m);
    }
    handle(s, m);
    ipc::SlcanReply r{};
    EXPECT_EQ(sent.size(), 1u);
    if (sent.size() == 1 && sent[0].size() == sizeof r) {
      std::memcpy(&r, sent[0].data(), sizeof r);
    } else {
      r.header.type = 0;  // an ErrorReply
    }
    return r;
  }
};

TEST(SlcanService, StartupGivesTheFreeSlotsAndOnlyTheirHolderMayUseThem) {
  Service x;
  SlcanSession a;
  SlcanSession b;
  EXPECT_EQ(x.call(a, ipc::SlcanOp::bib_startup).value, 0b10u);
  EXPECT_EQ(x.call(b, ipc::SlcanOp::bib_startup).value, 0u);
  EXPECT_EQ(x.call(b, ipc::SlcanOp::config_module).header.type, 0);  // refused
  EXPECT_EQ(x.call(a, ipc::SlcanOp::config_module, 0).header.type, 0);
  const auto r = x.call(a, ipc::SlcanOp::config_module);
  EXPECT_EQ(r.ret, 0);
  EXPECT_EQ(r.diagnosis, 0);
  const auto o = x.call(a, ipc::SlcanOp::config_msg_object, 1, [](ipc::SlcanRequest& m) {
    m.value = 7;
    m.flags = _SL064_SEND | _SL064_ACTIVE | _SL064_PASSIVE;
  });
  EXPECT_EQ(o.handle, 1);
  const auto dup = x.call(a, ipc::SlcanOp::config_msg_object, 1, [](ipc::SlcanRequest& m) {
    m.value = 7;
    m.flags = _SL064_PASSIVE;
  });
  EXPECT_EQ(dup.ret, SL064_E_DRIVER);
  EXPECT_EQ(dup.diagnosis, SL064_DIAG_DUPLICATE_ID);
  EXPECT_EQ(x.call(a, ipc::SlcanOp::get_diagnosis).value, SL064_DIAG_DUPLICATE_ID);
  EXPECT_EQ(x.call(a, ipc::SlcanOp::get_diagnosis).value, 0u);
  // The client goes: the S-Link is reset and free for the next one.
  x.service.close_all(a);
  EXPECT_EQ(x.sim->devices().find_slcan_slot(1)->module().object_count(), 0u);
  EXPECT_FALSE(x.sim->devices().find_slcan_slot(1)->module().configured());
  EXPECT_EQ(x.call(b, ipc::SlcanOp::bib_startup).value, 0b10u);
}

TEST(SlcanService, TheEepromOfASlotNobodyHoldsIsOpenToAnyClient) {
  Service x;
  SlcanSession cli;
  SlcanSession program;
  EXPECT_EQ(x.call(cli, ipc::SlcanOp::eeprom_read).eeprom[1], 0x0040);  // nobody holds slot 1
  EXPECT_EQ(x.call(program, ipc::SlcanOp::bib_startup).value, 0b10u);
  EXPECT_EQ(x.call(cli, ipc::SlcanOp::eeprom_read).header.type, 0);  // now the program's
  EXPECT_EQ(x.call(cli, ipc::SlcanOp::config_module).header.type, 0);
}

TEST(SlcanService, TheEepromIsReadAndWrittenWordByWord) {
  Service x;
  SlcanSession a;
  x.call(a, ipc::SlcanOp::bib_startup);
  const auto r = x.call(a, ipc::SlcanOp::eeprom_read);
  EXPECT_EQ(r.eeprom[0], 0x534C);
  EXPECT_EQ(r.eeprom[15], 0x09C4);
  const auto w = x.call(a, ipc::SlcanOp::eeprom_write, 1, [](ipc::SlcanRequest& m) {
    m.value = 15;
    m.handle = 100;
  });
  EXPECT_EQ(w.eeprom[15], 100);
  EXPECT_EQ(x.call(a, ipc::SlcanOp::eeprom_write, 1,
                   [](ipc::SlcanRequest& m) {
                     m.value = 1;
                     m.handle = 0x41;
                   })
                .header.type,
            0);  // read-only: an ErrorReply naming the word
}

}  // namespace
}  // namespace canemu::daemon
