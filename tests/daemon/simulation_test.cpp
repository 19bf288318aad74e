// The world and its reload: what may change while canemud runs is applied, the rest is
// reported and stays; ephemeral devices come and go with their leases.
#include "canemu/daemon/world/simulation.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace canemu::daemon {
namespace {

// What reloading `fresh` refuses, when it applies nothing.
std::vector<std::string> refused_whole(Simulation& sim, const Config& fresh) {
  const ReloadReport r = sim.reload(fresh);
  EXPECT_TRUE(r.applied.empty());
  return r.refused;
}

Config default_config() {
  return *load_default_config();
}

TEST(SimulationReload, AddsNewBusesAndDevicesAndTellsOfTheDevice) {
  auto sim = std::move(*Simulation::build(default_config()));
  std::vector<std::string> told;
  sim->devices().on_change = [&](ipc::NotificationKind, const std::string& name) {
    told.push_back(name);
  };
  Config fresh = default_config();
  BusConfig can2;
  can2.name = "can2";
  can2.bitrate = 250'000;
  fresh.buses.push_back(can2);
  DeviceConfig d;
  d.name = "ixxat1";
  d.controllers = {"can2"};
  fresh.devices.push_back(d);
  const ReloadReport r = sim->reload(fresh);
  EXPECT_EQ(r.applied, (std::vector<std::string>{"bus can2: added (can at 250000 bit/s)",
                                                 "device ixxat1: added"}));
  EXPECT_TRUE(r.refused.empty());
  EXPECT_EQ(sim->bus_count(), 4u);
  EXPECT_EQ(sim->bus_index("can2"), 3u);
  EXPECT_EQ(sim->scenarios().bus_count(), 4u);
  EXPECT_EQ(sim->devices().vci_id_of("ixxat1"), 2u);
  ASSERT_TRUE(sim->devices().find_node("ixxat1:0"));
  EXPECT_EQ(sim->devices().find_node("ixxat1:0")->bus, 3u);
  EXPECT_EQ(told, (std::vector<std::string>{"ixxat1"}));
  EXPECT_EQ(sim->devices().generation(), 1u);
}

TEST(SimulationReload, AppliesTheLoopsBatchWindowAndSpinAtOnce) {
  auto sim = std::move(*Simulation::build(default_config()));
  Config fresh = default_config();
  fresh.simulation.batch_us = 20;
  fresh.simulation.batch_max_us = 20;
  fresh.simulation.spin_us = 0;
  const ReloadReport r = sim->reload(fresh);
  EXPECT_EQ(r.applied,
            (std::vector<std::string>{"simulation: batch_us 20, batch_max_us 20, spin_us 0"}));
  EXPECT_TRUE(r.refused.empty());
  EXPECT_EQ(sim->config().simulation.batch_max_us, 20u);
}

TEST(SimulationReload, SetsOrRemovesTheCpuLatencyBound) {
  auto sim = std::move(*Simulation::build(default_config()));
  Config fresh = default_config();
  fresh.simulation.cpu_latency_us = 0;
  EXPECT_EQ(sim->reload(fresh).applied, (std::vector<std::string>{"simulation: cpu_latency_us 0"}));
  EXPECT_EQ(sim->config().simulation.cpu_latency_us, std::optional<uint32_t>(0));
  EXPECT_TRUE(sim->reload(fresh).applied.empty());  // unchanged: nothing to say
  fresh.simulation.cpu_latency_us.reset();
  EXPECT_EQ(sim->reload(fresh).applied,
            (std::vector<std::string>{"simulation: cpu_latency_us removed"}));
  EXPECT_FALSE(sim->config().simulation.cpu_latency_us);
}

TEST(SimulationReload, ReportsWhatOnlyARestartChangesAndKeepsIt) {
  auto sim = std::move(*Simulation::build(default_config()));
  Config fresh = default_config();
  fresh.simulation.seed = 9;
  fresh.simulation.time.mode = TimeMode::stepped;
  fresh.buses[0].bitrate = 125'000;
  fresh.devices.clear();
  EXPECT_EQ(refused_whole(*sim, fresh),
            (std::vector<std::string>{
                "simulation.time: stays realtime (a restart changes it)",
                "simulation.seed: stays 1 (a restart changes it)",
                "bus can0: keeps its settings (can at 500000 bit/s; a restart changes them)",
                "device ixxat0: still there (devices are removed by a restart)"}));
  EXPECT_EQ(sim->config().buses[0].bitrate, 500'000u);
  EXPECT_TRUE(sim->devices().exists("ixxat0"));
}

TEST(SimulationReload, ADeviceNamedLikeAnEphemeralOneIsNotAdded) {
  auto sim = std::move(*Simulation::build(default_config()));
  auto lease = sim->add_vci_device("vci1", 0, 1);
  Config fresh = default_config();
  DeviceConfig d;
  d.name = "vci1";
  d.controllers = {"can0"};
  fresh.devices.push_back(d);
  const ReloadReport r = sim->reload(fresh);
  EXPECT_EQ(r.refused,
            (std::vector<std::string>{"device vci1: an ephemeral device has that name"}));
  EXPECT_EQ(sim->config().devices.size(), 1u);
}

TEST(SimulationDevices, AnEphemeralDeviceLastsAsLongAsItsLeaseAndItsNodeIsSpareAgain) {
  auto sim = std::move(*Simulation::build(default_config()));
  model::HostedNode& node = sim->spare_node(0);
  {
    Simulation::DeviceLease lease = sim->add_ephemeral("eph1", 0, node, 3);
    EXPECT_TRUE(sim->devices().exists("eph1"));
    Simulation::DeviceLease moved = std::move(lease);
    EXPECT_TRUE(sim->devices().exists("eph1"));  // the moved-from lease ends nothing
  }
  EXPECT_FALSE(sim->devices().exists("eph1"));
  EXPECT_EQ(sim->devices().generation(), 2u);
  EXPECT_EQ(&sim->spare_node(0), &node);
}

TEST(SimulationDevices, AVciDeviceOnACanBusRunsAnSja1000WithItsFirmware) {
  auto sim = std::move(*Simulation::build(default_config()));
  auto lease = sim->add_vci_device("vci1", 1, 3);
  auto line = sim->devices().vci_line("vci1", 0);
  ASSERT_NE(line, nullptr);
  EXPECT_FALSE(line->fd_controller());
  EXPECT_EQ(sim->devices().find_node("vci1")->bus, 1u);
}

}  // namespace
TEST(SimulationReload, BusesOfOtherDaemonsNeedDistributedFromTheStart) {
  auto sim = std::move(*Simulation::build(default_config()));
  Config fresh = default_config();
  fresh.distributed.enabled = true;
  fresh.distributed.name = "here";
  BusConfig remote;
  remote.name = "far";
  remote.owner = "rig-a";
  fresh.buses.push_back(remote);
  fresh.buses[0].owner = "rig-a";
  EXPECT_EQ(refused_whole(*sim, fresh),
            (std::vector<std::string>{
                "distributed: stays as it was (a restart changes it)",
                "bus can0: keeps its settings (can at 500000 bit/s; a restart changes them)",
                "bus far: not added (daemon rig-a simulates it, and [distributed] needs a "
                "restart)"}));
  EXPECT_EQ(sim->bus_count(), 3u);
  EXPECT_TRUE(sim->config().buses[0].owner.empty());
  EXPECT_EQ(sim->remote(), nullptr);
}

}  // namespace canemu::daemon
