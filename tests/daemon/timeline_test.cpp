// canemu timeline's answers: the counter history of an ephemeral device's node stays readable
// after the device went (a python-can program that ended), bounded per bus, until a device of
// the same name comes.
#include "canemu/daemon/world/timeline.hpp"

#include <gtest/gtest.h>

#include <string>

namespace canemu::daemon {
namespace {

Config default_config() {
  return *load_default_config();
}

// Writes the counters of node `name` (as SJA1000 TXERR/RXERR or a fault scenario would): one
// change in its timeline.
void write_counters(Simulation& sim, const std::string& name, uint16_t tec) {
  const auto node = sim.devices().find_node(name);
  ASSERT_TRUE(node);
  node->controller->confinement().set_counters(tec, 1);
  sim.bus(node->bus).counters_changed(node->id);
}

TimelineAnswer ask(const Simulation& sim, const std::string& bus, const std::string& node) {
  auto m = ipc::make_message<ipc::TimelineRequest>();
  ipc::copy_name(m.bus, bus);
  ipc::copy_name(m.node, node);
  return answer_timeline(sim, m, 1);
}

// The node's reply; a failure naming the error otherwise.
const ipc::TimelineReply* reply(const TimelineAnswer& a) {
  if (const auto* e = std::get_if<TimelineError>(&a)) {
    ADD_FAILURE() << e->text;
    return nullptr;
  }
  return std::get<std::unique_ptr<ipc::TimelineReply>>(a).get();
}

TEST(GoneNodes, AnEphemeralNodesHistoryIsReadableAfterItsDeviceWent) {
  auto sim = std::move(*Simulation::build(default_config()));
  {
    auto lease = sim->add_vci_device("vci1", 0, 3);
    write_counters(*sim, "vci1:0", 200);
    const TimelineAnswer a = ask(*sim, "can0", "vci1:0");
    const ipc::TimelineReply* r = reply(a);
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->gone, 0);
    sim->scheduler().run_until(model::SimTime::from_ns(7'000));
  }
  EXPECT_FALSE(sim->devices().exists("vci1"));
  for (const char* name : {"vci1:0", "vci1"}) {
    const TimelineAnswer a = ask(*sim, "can0", name);
    const ipc::TimelineReply* r = reply(a);
    ASSERT_NE(r, nullptr) << name;
    EXPECT_EQ(ipc::name_of(r->node), name);
    EXPECT_EQ(r->gone, 1);
    EXPECT_EQ(r->gone_at_ns, 7'000);
    ASSERT_EQ(r->total, 1u);
    ASSERT_EQ(r->count, 1u);
    EXPECT_EQ(r->samples[0].tec, 200);
    EXPECT_EQ(r->samples[0].rec, 1);
  }
  // The bus names it among its gone nodes.
  auto load = ipc::make_message<ipc::TimelineRequest>();
  ipc::copy_name(load.bus, "can0");
  const TimelineAnswer bus = answer_timeline(*sim, load, 1);
  const auto& history = std::get<std::unique_ptr<ipc::LoadHistoryReply>>(bus);
  ASSERT_EQ(history->gone_count, 1u);
  EXPECT_EQ(ipc::name_of(history->gone[0]), "vci1:0");
  // On another bus it is not.
  const TimelineAnswer elsewhere = ask(*sim, "can1", "vci1:0");
  const auto* e = std::get_if<TimelineError>(&elsewhere);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->text, "node \"vci1:0\" is not on bus \"can1\"");
}

TEST(GoneNodes, ABusKeepsItsNewestGoneNodesAndTheNextDeviceOfTheNameReplacesOne) {
  auto sim = std::move(*Simulation::build(default_config()));
  constexpr std::size_t kMore = Simulation::kGoneNodesPerBus + 1;
  {
    std::vector<Simulation::DeviceLease> leases;
    for (std::size_t k = 1; k <= kMore; ++k) {
      const std::string name = "vci" + std::to_string(k);
      leases.push_back(sim->add_vci_device(name, 0, 3));
      write_counters(*sim, name + ":0", static_cast<uint16_t>(k));
    }
    // A node of another bus does not count against can0's.
    leases.push_back(sim->add_vci_device("other", 1, 3));
    write_counters(*sim, "other:0", 77);
  }  // they go in the order they came
  const TimelineAnswer first = ask(*sim, "can0", "vci1:0");
  const auto* oldest = std::get_if<TimelineError>(&first);
  ASSERT_NE(oldest, nullptr);
  EXPECT_EQ(oldest->code, ipc::ErrorCode::bad_argument);
  for (std::size_t k = 2; k <= kMore; ++k) {
    const TimelineAnswer a = ask(*sim, "can0", "vci" + std::to_string(k) + ":0");
    const ipc::TimelineReply* r = reply(a);
    ASSERT_NE(r, nullptr);
    ASSERT_EQ(r->count, 1u);
    EXPECT_EQ(r->samples[0].tec, k);
  }
  auto load = ipc::make_message<ipc::TimelineRequest>();
  ipc::copy_name(load.bus, "can0");
  const TimelineAnswer bus = answer_timeline(*sim, load, 1);
  const auto& history = std::get<std::unique_ptr<ipc::LoadHistoryReply>>(bus);
  ASSERT_EQ(history->gone_count, Simulation::kGoneNodesPerBus);
  for (std::size_t k = 0; k < Simulation::kGoneNodesPerBus; ++k) {
    EXPECT_EQ(ipc::name_of(history->gone[k]), "vci" + std::to_string(k + 2) + ":0");
  }
  const TimelineAnswer a = ask(*sim, "can1", "other:0");
  const ipc::TimelineReply* other = reply(a);
  ASSERT_NE(other, nullptr);
  EXPECT_EQ(other->samples[0].tec, 77);
  // A device of a kept name: its own history from nothing (on a node of the pool, maybe the
  // very node the old one had).
  auto lease = sim->add_vci_device("vci5", 0, 3);
  const TimelineAnswer b = ask(*sim, "can0", "vci5:0");
  const ipc::TimelineReply* fresh = reply(b);
  ASSERT_NE(fresh, nullptr);
  EXPECT_EQ(fresh->total, 0u);
  EXPECT_EQ(fresh->forgotten, 0u);
  EXPECT_EQ(fresh->gone, 0);
  const TimelineAnswer again = answer_timeline(*sim, load, 1);
  EXPECT_EQ(std::get<std::unique_ptr<ipc::LoadHistoryReply>>(again)->gone_count,
            Simulation::kGoneNodesPerBus - 1);
}

}  // namespace
}  // namespace canemu::daemon
