// The device registry: names to nodes, VCI object ids and hardware ids, the generation and the
// notifications of ephemeral devices.
#include "canemu/daemon/world/device_registry.hpp"

#include <gtest/gtest.h>

#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"

namespace canemu::daemon {
namespace {

using namespace canemu::model;

// Two buses; "ixxat0" configured with a controller on each, plus two spare nodes on bus 0.
struct Registry {
  SimScheduler scheduler;
  CanBus buses[2]{{scheduler, "can0"}, {scheduler, "can1"}};
  Sja1000Node spare_a{scheduler, buses[0]};
  Sja1000Node spare_b{scheduler, buses[0]};
  DeviceRegistry devices;
  std::vector<std::pair<ipc::NotificationKind, std::string>> told;
  Registry() {
    DeviceConfig d;
    d.name = "ixxat0";
    d.model = DeviceModel::ixxat_usb_to_can;
    d.controllers = {"can0", "can1"};
    std::vector<DeviceRegistry::Controller> controllers;
    for (std::size_t k = 0; k < 2; ++k) {
      DeviceRegistry::Controller c;
      c.name = "ixxat0:" + std::to_string(k);
      c.bus = k;
      c.node = std::make_unique<Sja1000Node>(scheduler, buses[k]);
      c.line = std::make_shared<ixxat::CanLine>(scheduler, *c.node, ixxat::Clocks{}, SimTime{});
      controllers.push_back(std::move(c));
    }
    devices.add_configured(d, std::move(controllers));
    devices.on_change = [this](ipc::NotificationKind kind, const std::string& name) {
      told.emplace_back(kind, name);
    };
  }
  HostedNode& configured_node(std::size_t k) {
    return *devices.configured()[0].controllers[k].node;
  }
};

TEST(HardwareId, IsHwAndSixDigitsFromTheNameTheSameEveryRun) {
  EXPECT_EQ(hardware_id("ixxat0"), "HW625043");
  EXPECT_EQ(hardware_id("vci1"), "HW892140");
  EXPECT_EQ(hardware_id(""), "HW136261");
}

TEST(DeviceRegistry, ResolvesConfiguredControllersAndEphemeralDevicesByName) {
  Registry r;
  r.devices.add_ephemeral("tester", 0, r.spare_a, 42);
  auto c1 = r.devices.find_node("ixxat0:1");
  ASSERT_TRUE(c1);
  EXPECT_EQ(c1->bus, 1u);
  EXPECT_EQ(c1->node, &r.configured_node(1));
  for (const char* name : {"tester", "tester:0"}) {
    auto e = r.devices.find_node(name);
    ASSERT_TRUE(e) << name;
    EXPECT_EQ(e->bus, 0u);
    EXPECT_EQ(e->node, &r.spare_a);
  }
  EXPECT_FALSE(r.devices.find_node("ixxat0"));  // a device, not a node
  EXPECT_FALSE(r.devices.find_node("ixxat0:2"));
  EXPECT_FALSE(r.devices.find_node("tester:1"));
  EXPECT_EQ(r.devices.node_name(1, r.configured_node(1).node()), "ixxat0:1");
  EXPECT_EQ(r.devices.node_name(0, r.spare_a.node()), "tester:0");
  EXPECT_EQ(r.devices.node_name(0, r.spare_b.node()), std::nullopt);
}

TEST(DeviceRegistry, NamesAreTakenByConfiguredAndEphemeralDevicesAlike) {
  Registry r;
  EXPECT_TRUE(r.devices.exists("ixxat0"));
  EXPECT_FALSE(r.devices.exists("ixxat0:0"));
  EXPECT_EQ(r.devices.unique_name("eph"), "eph1");
  r.devices.add_ephemeral("eph1", 0, r.spare_a, 1);
  EXPECT_TRUE(r.devices.exists("eph1"));
  EXPECT_EQ(r.devices.unique_name("eph"), "eph2");
  EXPECT_EQ(r.devices.unique_name("ixxat"), "ixxat1");
}

TEST(DeviceRegistry, VciIdsCountConfiguredDevicesThenVciAdaptersAsTheyComeNeverReused) {
  Registry r;
  EXPECT_EQ(r.devices.vci_id_of("ixxat0"), 1u);
  auto line = std::make_shared<ixxat::CanLine>(r.scheduler, r.spare_a, ixxat::Clocks{}, SimTime{});
  r.devices.add_ephemeral("vci1", 0, r.spare_a, 7, line);
  r.devices.add_ephemeral("eph1", 0, r.spare_b, 7);  // not a VCI adapter: no id
  EXPECT_EQ(r.devices.vci_id_of("vci1"), 2u);
  EXPECT_EQ(r.devices.vci_id_of("eph1"), 0u);
  EXPECT_EQ(r.devices.vci_id_of("nobody"), 0u);
  r.devices.remove_ephemeral("vci1");
  r.devices.add_ephemeral("vci1", 0, r.spare_a, 7, line);
  EXPECT_EQ(r.devices.vci_id_of("vci1"), 3u);
}

TEST(DeviceRegistry, FindsTheFirmwareOfAControllerAndOfANode) {
  Registry r;
  const auto& controllers = r.devices.configured()[0].controllers;
  EXPECT_EQ(r.devices.vci_line("ixxat0", 1), controllers[1].line);
  EXPECT_EQ(r.devices.vci_line("ixxat0", 2), nullptr);
  EXPECT_EQ(r.devices.vci_line_of(&r.configured_node(0)), controllers[0].line);
  auto line = std::make_shared<ixxat::CanLine>(r.scheduler, r.spare_a, ixxat::Clocks{}, SimTime{});
  r.devices.add_ephemeral("vci1", 0, r.spare_a, 7, line);
  r.devices.add_ephemeral("eph1", 0, r.spare_b, 7);
  EXPECT_EQ(r.devices.vci_line("vci1", 0), line);
  EXPECT_EQ(r.devices.vci_line("vci1", 1), nullptr);  // one controller
  EXPECT_EQ(r.devices.vci_line("eph1", 0), nullptr);
  EXPECT_EQ(r.devices.vci_line_of(&r.spare_a), line);
  EXPECT_EQ(r.devices.vci_line_of(&r.spare_b), nullptr);
}

TEST(DeviceRegistry, EveryEphemeralDeviceThatComesOrGoesCountsAndIsTold) {
  Registry r;
  EXPECT_EQ(r.devices.generation(), 0u);  // configured devices are there from the start
  r.devices.add_ephemeral("a", 0, r.spare_a, 1);
  r.devices.add_ephemeral("b", 0, r.spare_b, 1);
  r.devices.remove_ephemeral("a");
  r.devices.announce(ipc::NotificationKind::device_added, "ixxat1");  // from a reload
  EXPECT_EQ(r.devices.generation(), 4u);
  using K = ipc::NotificationKind;
  EXPECT_EQ(r.told, (std::vector<std::pair<K, std::string>>{{K::device_added, "a"},
                                                            {K::device_added, "b"},
                                                            {K::device_removed, "a"},
                                                            {K::device_added, "ixxat1"}}));
  ASSERT_EQ(r.devices.ephemeral().size(), 1u);
  EXPECT_EQ(r.devices.ephemeral()[0].name, "b");
  EXPECT_EQ(r.devices.find_ephemeral("a"), nullptr);
  EXPECT_EQ(r.devices.find_ephemeral("b")->owner_pid, 1u);
}

}  // namespace
}  // namespace canemu::daemon
