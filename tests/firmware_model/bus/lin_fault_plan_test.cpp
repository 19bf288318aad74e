// LIN fault rules on a bus: matching by commander, identifier, window, skip and count; each
// effect's outcome at its instant; a responder switched off.
#include "canemu/firmware_model/bus/lin_fault_plan.hpp"

#include <gtest/gtest.h>

#include <map>
#include <vector>

namespace canemu::model::lin {
namespace {

class Node : public LinNode {
 public:
  explicit Node(LinBus& bus) : id(bus.attach(*this)) {}
  std::optional<Response> respond(uint8_t i) override {
    auto it = table.find(i);
    return it == table.end() ? std::nullopt : std::optional<Response>(it->second);
  }
  void on_lin_event(const Event& e) override { seen.push_back(e); }
  uint32_t lin_bitrate() const override { return 19200; }
  LinNodeId id;
  std::map<uint8_t, Response> table;
  std::vector<Event> seen;
};

Response one_byte(uint8_t b) {
  Response r;
  r.size = 1;
  r.data[0] = b;
  return r;
}

class LinFaultPlanTest : public ::testing::Test {
 protected:
  LinFaultPlanTest() {
    bus.set_fault_source(&plan);
    plan.on_hit = [this](std::size_t rule, SimTime at, uint8_t id) {
      hits.push_back({rule, at.ns(), id});
    };
    responder.table[0x10] = one_byte(0x10);
    responder.table[0x11] = one_byte(0x11);
  }
  // One header every 10 ms from `from` (ID 0x10 unless said), run to the end of the last.
  void headers(int n, uint8_t id = 0x10) {
    for (int k = 0; k < n; ++k) {
      ASSERT_TRUE(bus.send_header(commander.id, id));
      t += 10'000'000;
      scheduler.run_until(SimTime::from_ns(t));
    }
  }
  std::vector<ErrorKind> listener_errors() const {
    std::vector<ErrorKind> out;
    for (const Event& e : listener.seen) {
      out.push_back(e.kind == Event::Kind::frame ? static_cast<ErrorKind>(0) : e.error);
    }
    return out;
  }

  struct Hit {
    std::size_t rule;
    int64_t at;
    uint8_t id;
    bool operator==(const Hit&) const = default;
  };
  SimScheduler scheduler;
  LinBus bus{scheduler, Layout{}};
  LinFaultPlan plan;
  Node commander{bus};
  Node responder{bus};
  Node listener{bus};
  std::vector<Hit> hits;
  int64_t t = 0;
};

constexpr auto kFrame = static_cast<ErrorKind>(0);

TEST_F(LinFaultPlanTest, SkipAndCountChooseTheFramesHit) {
  LinFaultRule r;
  r.effect = LinEffect::checksum_error;
  r.id = 0x10;
  r.skip = 1;
  r.count = 2;
  plan.add(r);
  headers(4);
  EXPECT_EQ(listener_errors(),
            (std::vector<ErrorKind>{kFrame, ErrorKind::checksum, ErrorKind::checksum, kFrame}));
  EXPECT_EQ(plan.rule(0).seen, 4u);
  EXPECT_EQ(plan.rule(0).hits, 2u);
  EXPECT_EQ(hits, (std::vector<Hit>{{0, 10'000'000, 0x10}, {0, 20'000'000, 0x10}}));
}

TEST_F(LinFaultPlanTest, IdentifierCommanderAndWindowMustMatch) {
  LinFaultRule r;
  r.effect = LinEffect::no_response;
  r.id = 0x11;
  r.commander = commander.id;
  r.from = SimTime::from_ns(10'000'000);
  r.until = SimTime::from_ns(30'000'000);
  plan.add(r);
  headers(1, 0x11);  // before the window
  headers(1, 0x10);  // another ID
  headers(1, 0x11);  // hit
  headers(1, 0x11);  // after the window
  EXPECT_EQ(listener_errors(),
            (std::vector<ErrorKind>{kFrame, kFrame, ErrorKind::no_response, kFrame}));
}

TEST_F(LinFaultPlanTest, EachEffectGivesItsError) {
  const std::vector<std::pair<LinEffect, ErrorKind>> cases{
      {LinEffect::parity_error, ErrorKind::parity},
      {LinEffect::sync_error, ErrorKind::sync},
      {LinEffect::short_break, ErrorKind::other},
      {LinEffect::header_bit_error, ErrorKind::parity},
      {LinEffect::response_bit_error, ErrorKind::checksum},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    LinFaultRule r;
    r.effect = cases[k].first;
    r.skip = k;
    r.count = 1;
    plan.add(r);
  }
  headers(static_cast<int>(cases.size()));
  std::vector<ErrorKind> expected;
  for (const auto& c : cases) {
    expected.push_back(c.second);
  }
  EXPECT_EQ(listener_errors(), expected);
  // The commander saw its header's bit error; the responder its response's.
  // (The commander hears nothing of a header the listeners could not use.)
  EXPECT_EQ(commander.seen.at(0).error, ErrorKind::bit);
  EXPECT_EQ(responder.seen.at(4).error, ErrorKind::bit);
}

TEST_F(LinFaultPlanTest, AResponderSwitchedOffLeavesTheOtherToAnswer) {
  Node backup{bus};
  backup.table[0x10] = one_byte(0x99);
  LinFaultRule r;
  r.effect = LinEffect::responder_off;
  r.responder = responder.id;
  plan.add(r);
  headers(1);
  ASSERT_EQ(listener.seen.size(), 1u);
  EXPECT_EQ(listener.seen[0].kind, Event::Kind::frame);
  EXPECT_EQ(listener.seen[0].responder, backup.id);
  EXPECT_EQ(listener.seen[0].response.data[0], 0x99);
  plan.disable(0);
  headers(1);  // both answer: 10h AND 99h = 10h on the wire: the first wins every bit
  EXPECT_EQ(listener.seen.at(1).kind, Event::Kind::frame);
  EXPECT_EQ(listener.seen[1].responder, responder.id);
  EXPECT_EQ(backup.seen.at(1).error, ErrorKind::bit);
}

}  // namespace
}  // namespace canemu::model::lin
