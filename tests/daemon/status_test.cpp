// What the protocol reports of the world built from the default configuration (can0 and can1
// at 500 kbit/s, ixxat0 with a controller on each) and an ephemeral VCI adapter.
#include "canemu/daemon/status.hpp"

#include <gtest/gtest.h>

#include "canemu/daemon/simulation.hpp"

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

}  // namespace
}  // namespace canemu::daemon
