// canemud with many buses (256 buses, 256 controllers, written by the test; it starts with the
// most it takes, 1024 buses): `canemu status --json`, the text tables and `canemu metrics` list
// every bus and node, though the status comes in several pages; one more bus than the limit is
// refused naming it.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <string>

#include <fmt/format.h>

#include "../support/many_buses.hpp"
#include "../support/temp_dir.hpp"
#include "canemu/client/channel.hpp"
#include "canemu/client/lists.hpp"
#include "cli_process.hpp"
#include "cli_run_support.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

using testing::connect;
using testing::Daemon;
using testing::many_buses_config;
using testing::many_buses_node;

std::string write_config(const testing::TempDir& dir, const std::string& text) {
  const std::string file = (dir.path / "canemud.toml").string();
  std::ofstream(file) << text;
  return file;
}

client::Channel open(client::Connection& c, const std::string& bus, const std::string& device) {
  client::ChannelOptions o;
  o.bus = bus;
  o.device = device;
  auto ch = client::Channel::open(c, o);
  EXPECT_TRUE(ch) << ch.error().message;
  return std::move(*ch);
}

void step(client::Connection& c, int64_t ns) {
  auto m = ipc::make_message<ipc::TimeStepRequest>();
  m.step_ns = ns;
  auto r = c.call<ipc::TimeStepRequest, ipc::TimeStepReply>(m);
  ASSERT_TRUE(r) << r.error().message;
}

// One node of `canemu status --json`: its keys in the order the JSON has them. A configured
// adapter's controller no program started is in its init mode.
std::string json_node(const std::string& name, const std::string& bus, uint64_t sent,
                      uint64_t received, const std::string& state = "init") {
  return fmt::format(
      "{{\"bus\" : \"{}\",\"errors\" : 0,\"frames_received\" : {},\"frames_sent\" : {},"
      "\"name\" : \"{}\",\"rec\" : 0,\"state\" : \"{}\",\"tec\" : 0}}",
      bus, received, sent, name, state);
}

// Three frames are 0.015 % of the last second: 0.0 %.
std::string json_bus(std::size_t i, uint64_t frames) {
  return fmt::format(
      "{{\"bitrate\" : 1000000,\"data_bitrate\" : 0,\"error_frames\" : 0,\"frames\" : {},"
      "\"kind\" : \"can\",\"load_percent\" : 0.0,\"name\" : \"bus{}\",\"transceiver\" : "
      "\"high-speed\"}}",
      frames, i);
}

// 256 buses and 256 controllers (64 adapters of four, one controller on each bus), a recorder
// on every bus, two ephemeral nodes on the last bus that exchange three frames: eight pages of
// buses, two of nodes, pages of devices and recorders.
TEST(Scale, StatusListsTwoHundredFiftySixBusesAndEveryControllerWithTheirCounts) {
  testing::TempDir dir;
  std::string config = many_buses_config(256, 256);
  for (int b = 0; b < 256; ++b) {  // a recorder on every bus: several pages of recorders
    config += fmt::format("[[recorder]]\nbus = \"bus{}\"\npath = \"{}\"\n", b,
                          (dir.path / fmt::format("bus{}.log", b)).string());
  }
  Daemon d("stepped", {"--config=" + write_config(dir, config)});
  auto c = connect(d);
  auto tx = open(c, "bus255", "tx255");
  auto rx = open(c, "bus255", "rx255");
  for (uint32_t id = 1; id <= 3; ++id) {
    ipc::ChannelMessage m;
    m.id = id;
    m.dlc = 1;
    ASSERT_TRUE(tx.send(m));
  }
  step(c, 1'000'000);

  const std::string j = output_of(d, {"status", "--json"});
  std::string buses = "\"buses\" : [";
  for (std::size_t i = 0; i < 256; ++i) {
    buses += (i == 0 ? "" : ",") + json_bus(i, i == 255 ? 3 : 0);
  }
  buses += "]";
  EXPECT_NE(j.find(buses), std::string::npos) << j;
  std::string nodes = "\"nodes\" : [";
  for (std::size_t k = 0; k < 256; ++k) {
    nodes += json_node(many_buses_node(k), fmt::format("bus{}", k), 0, 0) + ",";
  }
  nodes += json_node("tx255:0", "bus255", 3, 0, "error-active") + "," +
           json_node("rx255:0", "bus255", 0, 3, "error-active") + "]";
  EXPECT_NE(j.find(nodes), std::string::npos) << j;
  // The devices: 64 configured adapters, then the two ephemeral ones.
  EXPECT_NE(j.find("\"model\" : \"ixxat-usb-to-can\",\"name\" : \"dev63\",\"nodes\" : "
                   "[\"dev63:0\",\"dev63:1\",\"dev63:2\",\"dev63:3\"]"),
            std::string::npos)
      << j;
  EXPECT_NE(j.find("\"name\" : \"rx255\",\"nodes\" : [\"rx255:0\"]"), std::string::npos) << j;
  // The recorders: bus255's, on the last page, wrote the three frames.
  const std::size_t recorder = j.find("{\"bus\" : \"bus255\",\"bytes\"");
  ASSERT_NE(recorder, std::string::npos) << j;
  const std::string entry = j.substr(recorder, j.find('}', recorder) - recorder);
  EXPECT_NE(entry.find("\"frames\" : 3,"), std::string::npos) << entry;
  EXPECT_NE(entry.find("bus255.log"), std::string::npos) << entry;
  const std::string log = testing::read_file(dir.path / "bus255.log");
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 3) << log;
  for (const char* line : {" bus255 001#00\n", " bus255 002#00\n", " bus255 003#00\n"}) {
    EXPECT_NE(log.find(line), std::string::npos) << log;
  }

  // The tables: a row for every bus and node.
  const std::string t = output_of(d, {"status"});
  EXPECT_NE(t.find("\nbus255       can       1000000         0    0.0%          3        0\n"),
            std::string::npos)
      << t;
  EXPECT_NE(t.find("\ndev63:3        bus255       init              0    0          0          0"
                   "        0\ntx255:0        bus255       error-active      0    0          3"
                   "          0        0\n"),
            std::string::npos)
      << t;
  std::size_t rows = 0;
  for (std::size_t at = t.find("\ndev"); at != std::string::npos; at = t.find("\ndev", at + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, 256u + 64u);  // a NODE row per controller, a DEVICE row per adapter

  // Metrics of a node on the second page, on a bus of the last page.
  const std::string m = output_of(d, {"metrics"});
  EXPECT_NE(m.find("canemu_node_frames_received_total{node=\"rx255:0\",bus=\"bus255\"} 3\n"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("canemu_bus_frames_total{bus=\"bus255\"} 3\n"), std::string::npos) << m;

  // `canemu dump any` listens on all 256 (16 channels to a connection: 16 connections).
  Cli dump(d, {"dump", "any", "--no-errors", "-n", "1"});
  const std::string err = Cli::read_until(dump.err, "listening on bus255");
  ASSERT_NE(err.find("listening on bus255"), std::string::npos) << err;
  const std::string sent = output_of(d, {"send", "bus255", "123#11", "--step", "1ms"});
  EXPECT_NE(sent.find(" bus255 123#11"), std::string::npos) << sent;
  EXPECT_EQ(Cli::read_all(dump.out), sent);
  EXPECT_EQ(dump.wait(), 0);
}

// Exactly a page (32 buses, 192 nodes) and one more of each: every entry once, in order.
TEST(Scale, FetchStatusReadsExactlyAPageAndOneMore) {
  for (const auto& [buses, controllers] :
       {std::pair<std::size_t, std::size_t>{ipc::kStatusPageBuses, ipc::kStatusPageNodes},
        {ipc::kStatusPageBuses + 1, ipc::kStatusPageNodes + 1}}) {
    testing::TempDir dir;
    Daemon d("stepped", {"--config=" + write_config(dir, many_buses_config(buses, controllers))});
    auto c = connect(d);
    auto s = client::fetch_status(c);
    ASSERT_TRUE(s) << s.error().message;
    ASSERT_EQ(s->buses.size(), buses);
    for (std::size_t i = 0; i < buses; ++i) {
      EXPECT_EQ(ipc::name_of(s->buses[i].name), fmt::format("bus{}", i));
    }
    ASSERT_EQ(s->nodes.size(), controllers);
    for (std::size_t k = 0; k < controllers; ++k) {
      EXPECT_EQ(ipc::name_of(s->nodes[k].name), many_buses_node(k));
      EXPECT_EQ(s->bus_name(s->nodes[k]), fmt::format("bus{}", k % buses));
    }
    auto devices = client::fetch_device_list(c);
    ASSERT_TRUE(devices) << devices.error().message;
    EXPECT_EQ(devices->devices.size(), (controllers + 3) / 4);
    EXPECT_EQ(ipc::name_of(devices->devices.back().name),
              fmt::format("dev{}", (controllers - 1) / 4));
  }
}

// A page that starts beyond the end is empty and still says how many there are.
TEST(Scale, APageBeyondTheEndIsEmpty) {
  testing::TempDir dir;
  Daemon d("stepped", {"--config=" + write_config(dir, many_buses_config(40, 200))});
  auto c = connect(d);
  auto m = ipc::make_message<ipc::StatusRequest>();
  m.first_bus = 40;
  m.first_node = 500;
  auto r = c.call<ipc::StatusRequest, ipc::StatusReply>(m);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->bus_count, 0u);
  EXPECT_EQ(r->node_count, 0u);
  EXPECT_EQ(r->bus_total, 40u);
  EXPECT_EQ(r->node_total, 200u);
  EXPECT_EQ(r->first_bus, 40u);
  EXPECT_EQ(r->first_node, 500u);
  auto dm = ipc::make_message<ipc::DeviceListRequest>();
  dm.first = 50;
  auto dr = c.call<ipc::DeviceListRequest, ipc::DeviceListReply>(dm);
  ASSERT_TRUE(dr) << dr.error().message;
  EXPECT_EQ(dr->count, 0u);
  EXPECT_EQ(dr->total, 50u);
}

// A client list longer than a page: every client once.
TEST(Scale, ClientListReadsEveryPage) {
  testing::TempDir dir;
  Daemon d("stepped",
           {"--config=" + write_config(dir, many_buses_config(1, 0) +
                                                "[security]\nmax_clients_per_user = 100\n")});
  std::vector<client::Connection> clients;
  for (std::size_t i = 0; i < ipc::kClientPage + 1; ++i) {
    clients.push_back(connect(d, fmt::format("c{}", i).c_str()));
  }
  auto list = client::fetch_client_list(clients[0]);
  ASSERT_TRUE(list) << list.error().message;
  ASSERT_EQ(list->size(), ipc::kClientPage + 1);
  std::set<std::string> names;
  for (const ipc::ClientEntry& e : *list) {
    names.insert(ipc::name_of(e.name));
  }
  EXPECT_EQ(names.size(), ipc::kClientPage + 1);
  EXPECT_EQ(names.count("c64"), 1u);
}

// The most buses a configuration takes run (every one in the status); one more bus, or one
// more controller than 256, is refused naming the limit.
TEST(Scale, AThousandTwentyFourBusesRunAndOneMoreBusOrControllerIsRefusedNamingTheLimit) {
  testing::TempDir dir;
  {
    Daemon d("stepped", {"--config=" + write_config(dir, many_buses_config(1024, 4))});
    auto c = connect(d);
    auto s = client::fetch_status(c);
    ASSERT_TRUE(s) << s.error().message;
    ASSERT_EQ(s->buses.size(), 1024u);
    EXPECT_EQ(ipc::name_of(s->buses.back().name), "bus1023");
  }
  testing::CanemudProcess buses(CANEMUD_PATH,
                                {"--config=" + write_config(dir, many_buses_config(1025, 4))});
  EXPECT_FALSE(buses.ready());
  EXPECT_NE(buses.log().find("bus: 1025 buses; at most 1024"), std::string::npos) << buses.log();
  testing::CanemudProcess controllers(
      CANEMUD_PATH, {"--config=" + write_config(dir, many_buses_config(64, 257))});
  EXPECT_FALSE(controllers.ready());
  EXPECT_NE(controllers.log().find("device: 257 controllers in all; at most 256"),
            std::string::npos)
      << controllers.log();
}

}  // namespace
}  // namespace canemu
