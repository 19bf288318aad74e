// What the protocol reports of the world built from the default configuration (can0 and can1
// at 500 kbit/s, ixxat0 with a controller on each) and an ephemeral VCI adapter.
#include "canemu/daemon/world/status.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include "../support/many_buses.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "vci/cantype.h"
#include "vci/vcierr.h"

namespace canemu::daemon {
namespace {

std::unique_ptr<Simulation> default_world() {
  return std::move(*Simulation::build(*load_default_config()));
}

TEST(DeviceList, ShowsConfiguredAdaptersThenEphemeralDevicesWithTheirIds) {
  auto sim = default_world();
  sim->scheduler().run_until(model::SimTime::from_ns(1'234'567));
  auto lease = sim->add_vci_device("vci1", 1, 4711);
  auto plain = sim->add_ephemeral("eph1", 0, sim->spare_node(0), 4712);
  auto r = ipc::make_message<ipc::DeviceListReply>();
  fill_device_list(*sim, r);
  EXPECT_EQ(r.generation, 2u);
  EXPECT_EQ(r.total, 3u);
  ASSERT_EQ(r.count, 3u);
  const ipc::DeviceEntry& a = r.devices[0];
  EXPECT_EQ(ipc::name_of(a.name), "ixxat0");
  EXPECT_EQ(a.model, static_cast<uint8_t>(ipc::WireDeviceModel::ixxat_usb_to_can));
  EXPECT_EQ(a.controller_count, 3u);  // two CAN controllers, then the LIN one
  EXPECT_EQ(ipc::name_of(a.buses[0]), "can0");
  EXPECT_EQ(ipc::name_of(a.buses[1]), "can1");
  EXPECT_EQ(ipc::name_of(a.buses[2]), "lin0");
  EXPECT_EQ(a.controller_fd[1], static_cast<uint8_t>(ipc::WireControllerKind::can));
  EXPECT_EQ(a.controller_fd[2], static_cast<uint8_t>(ipc::WireControllerKind::lin));
  EXPECT_EQ(a.vci_id, 1u);
  EXPECT_EQ(a.epoch_ns, 0);
  EXPECT_EQ(a.ephemeral, 0u);
  EXPECT_EQ(ipc::name_of(a.hardware_id), "HW625043");
  const ipc::DeviceEntry& v = r.devices[1];
  EXPECT_EQ(ipc::name_of(v.name), "vci1");
  EXPECT_EQ(v.model, static_cast<uint8_t>(ipc::WireDeviceModel::ixxat_usb_to_can));
  EXPECT_EQ(v.ephemeral, 1u);
  EXPECT_EQ(v.owner_pid, 4711u);
  EXPECT_EQ(ipc::name_of(v.buses[0]), "can1");
  EXPECT_EQ(v.vci_id, 2u);
  EXPECT_EQ(v.epoch_ns, 1'234'000);  // powered on at the last whole microsecond
  EXPECT_EQ(ipc::name_of(v.hardware_id), "HW892140");
  const ipc::DeviceEntry& e = r.devices[2];
  EXPECT_EQ(ipc::name_of(e.name), "eph1");
  EXPECT_EQ(e.model, static_cast<uint8_t>(ipc::WireDeviceModel::ephemeral));
  EXPECT_EQ(e.vci_id, 0u);
  EXPECT_EQ(ipc::name_of(e.hardware_id), "");
}

TEST(Status, ListsTheBusesThenEveryDevicesNodes) {
  auto sim = default_world();
  auto lease = sim->add_ephemeral("eph1", 1, sim->spare_node(1), 1);
  sim->scheduler().run_until(model::SimTime::from_ns(5'000'000));
  auto r = ipc::make_message<ipc::StatusReply>();
  fill_status(*sim, r);
  EXPECT_EQ(r.sim_time_ns, 5'000'000);
  ASSERT_EQ(r.bus_count, 3u);
  EXPECT_EQ(ipc::name_of(r.buses[0].name), "can0");
  EXPECT_EQ(r.buses[1].bitrate, 500'000u);
  EXPECT_EQ(r.buses[1].kind, static_cast<uint8_t>(BusKind::can));
  EXPECT_EQ(r.buses[0].load_permille, 0u);
  EXPECT_EQ(ipc::name_of(r.buses[2].name), "lin0");
  EXPECT_EQ(r.buses[2].kind, static_cast<uint8_t>(BusKind::lin));
  EXPECT_EQ(r.buses[2].bitrate, 19'200u);
  EXPECT_EQ(r.buses[2].frames, 0u);
  ASSERT_EQ(r.node_count, 4u);
  EXPECT_EQ(ipc::name_of(r.nodes[0].name), "ixxat0:0");
  EXPECT_EQ(r.nodes[0].lin, static_cast<uint8_t>(ipc::WireLinState::none));
  EXPECT_EQ(ipc::name_of(r.nodes[1].name), "ixxat0:1");
  EXPECT_EQ(r.nodes[1].bus, 1u);
  EXPECT_EQ(ipc::name_of(r.nodes[2].name), "ixxat0:2");  // the LIN controller, offline
  EXPECT_EQ(r.nodes[2].bus, 2u);
  EXPECT_EQ(r.nodes[2].lin, static_cast<uint8_t>(ipc::WireLinState::offline));
  EXPECT_EQ(ipc::name_of(r.nodes[3].name), "eph1:0");
  EXPECT_EQ(r.nodes[3].bus, 1u);
  EXPECT_EQ(r.nodes[3].state, static_cast<uint8_t>(model::ErrorState::active));
  EXPECT_EQ(r.nodes[3].tec, 0u);
}

// A configured adapter's controller no program started is in its init (reset) mode; its line
// initialized and started, as a VCI program's canControlInitialize and canControlStart do, it
// takes part in traffic.
TEST(Status, SaysWhichControllersAreInTheirInitMode) {
  auto sim = default_world();
  auto r = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>());
  fill_status(*sim, *r);
  ASSERT_EQ(r->node_count, 3u);
  const auto init = static_cast<uint8_t>(ipc::WireNodeMode::init);
  const auto running = static_cast<uint8_t>(ipc::WireNodeMode::running);
  EXPECT_EQ(r->nodes[0].mode, init);
  EXPECT_EQ(r->nodes[1].mode, init);
  model::ixxat::CanLine& line = *sim->devices().configured()[0].controllers[0].line;
  model::ixxat::LineInit settings;
  settings.btr0 = CAN_BT0_500KB;
  settings.btr1 = CAN_BT1_500KB;
  ASSERT_EQ(line.init_line(settings), VCI_OK);
  ASSERT_EQ(line.start_line(), VCI_OK);
  fill_status(*sim, *r);
  EXPECT_EQ(r->nodes[0].mode, running);
  EXPECT_EQ(r->nodes[1].mode, init);
}

std::unique_ptr<Simulation> many_buses_world(std::size_t buses, std::size_t controllers) {
  auto config = parse_config(testing::many_buses_config(buses, controllers), "many.toml");
  EXPECT_TRUE(config) << (config ? "" : config.error().front());
  return std::move(*Simulation::build(*config));
}

// The page from (first_bus, first_node) on: its buses and nodes must be exactly those of a
// world with `buses` buses and `controllers` controllers (many_buses_config) from there on.
void expect_page(const Simulation& sim, std::size_t buses, std::size_t controllers,
                 std::size_t first_bus, std::size_t first_node, std::size_t bus_count,
                 std::size_t node_count) {
  auto r = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>());
  fill_status(sim, *r, first_bus, first_node);
  EXPECT_EQ(r->bus_total, buses);
  EXPECT_EQ(r->node_total, controllers);
  EXPECT_EQ(r->first_bus, first_bus);
  EXPECT_EQ(r->first_node, first_node);
  ASSERT_EQ(r->bus_count, bus_count);
  ASSERT_EQ(r->node_count, node_count);
  for (std::size_t i = 0; i < bus_count; ++i) {
    EXPECT_EQ(ipc::name_of(r->buses[i].name), fmt::format("bus{}", first_bus + i));
    EXPECT_EQ(r->buses[i].bitrate, 1'000'000u);
  }
  for (std::size_t i = 0; i < node_count; ++i) {
    const std::size_t k = first_node + i;
    EXPECT_EQ(ipc::name_of(r->nodes[i].name), testing::many_buses_node(k));
    EXPECT_EQ(r->nodes[i].bus, k % buses);  // among all buses, not the page's
  }
}

TEST(StatusPages, ExactlyAPageFitsTheFirstReplyAndTheNextOneIsEmpty) {
  const std::size_t buses = ipc::kStatusPageBuses;
  const std::size_t nodes = ipc::kStatusPageNodes;
  auto sim = many_buses_world(buses, nodes);
  expect_page(*sim, buses, nodes, 0, 0, buses, nodes);
  expect_page(*sim, buses, nodes, buses, nodes, 0, 0);
}

TEST(StatusPages, OneMoreBusAndNodeComeOnTheSecondPage) {
  const std::size_t buses = ipc::kStatusPageBuses + 1;
  const std::size_t nodes = ipc::kStatusPageNodes + 1;
  auto sim = many_buses_world(buses, nodes);
  expect_page(*sim, buses, nodes, 0, 0, buses - 1, nodes - 1);
  expect_page(*sim, buses, nodes, buses - 1, nodes - 1, 1, 1);
  // Buses and nodes page on their own: the rest of the nodes with no bus.
  expect_page(*sim, buses, nodes, buses, 5, 0, nodes - 5);
}

TEST(StatusPages, SixtyFourBusesAndTwoHundredFiftySixNodesInTwoPagesEach) {
  auto sim = many_buses_world(64, 256);
  expect_page(*sim, 64, 256, 0, 0, 32, 192);
  expect_page(*sim, 64, 256, 32, 192, 32, 64);
  expect_page(*sim, 64, 256, 64, 256, 0, 0);
  expect_page(*sim, 64, 256, 1000, 1000, 0, 0);
}

TEST(DevicePages, AdaptersBeyondAPageComeOnTheNextWithTheSameGeneration) {
  auto sim = many_buses_world(64, 256);  // 64 adapters: exactly a page
  auto before = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>());
  fill_status(*sim, *before, 0, 0);
  auto lease = sim->add_ephemeral("eph1", 5, sim->spare_node(5), 4712);
  auto first = std::make_unique<ipc::DeviceListReply>(ipc::make_message<ipc::DeviceListReply>());
  fill_device_list(*sim, *first);
  EXPECT_EQ(first->total, 65u);
  EXPECT_EQ(first->first, 0u);
  ASSERT_EQ(first->count, ipc::kDevicePage);
  for (std::size_t i = 0; i < ipc::kDevicePage; ++i) {
    EXPECT_EQ(ipc::name_of(first->devices[i].name), fmt::format("dev{}", i));
  }
  auto second = std::make_unique<ipc::DeviceListReply>(ipc::make_message<ipc::DeviceListReply>());
  fill_device_list(*sim, *second, ipc::kDevicePage);
  EXPECT_EQ(second->total, 65u);
  EXPECT_EQ(second->first, ipc::kDevicePage);
  ASSERT_EQ(second->count, 1u);
  EXPECT_EQ(ipc::name_of(second->devices[0].name), "eph1");
  EXPECT_EQ(ipc::name_of(second->devices[0].buses[0]), "bus5");
  EXPECT_EQ(second->generation, first->generation);
  // The ephemeral node is the 257th node, on the second page of the status.
  auto status = std::make_unique<ipc::StatusReply>(ipc::make_message<ipc::StatusReply>());
  fill_status(*sim, *status, 0, 256);
  EXPECT_EQ(status->generation, first->generation);
  EXPECT_NE(status->generation, before->generation);  // pages from before do not fit
  EXPECT_EQ(before->node_total, 256u);
  EXPECT_EQ(status->node_total, 257u);
  ASSERT_EQ(status->node_count, 1u);
  EXPECT_EQ(ipc::name_of(status->nodes[0].name), "eph1:0");
  EXPECT_EQ(status->nodes[0].bus, 5u);
}

}  // namespace
}  // namespace canemu::daemon
