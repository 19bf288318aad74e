// The LIN bus engine in scenarios with exact instants: a header answered, published and
// unanswered; responders colliding; listeners that cannot synchronize; faults; sleep, wake-up
// and inactivity; one request per node.
#include "canemu/firmware_model/bus/lin_bus.hpp"

#include <gtest/gtest.h>

#include <map>
#include <vector>

namespace canemu::model::lin {
namespace {

constexpr uint32_t k19200 = 19200;

int64_t at_bits(uint64_t bits, uint32_t rate = k19200) {
  return bits_duration(bits, rate).ns();
}

Response response(std::vector<uint8_t> data, Checksum kind = Checksum::enhanced) {
  Response r;
  r.size = static_cast<uint8_t>(data.size());
  std::copy(data.begin(), data.end(), r.data.begin());
  r.checksum = kind;
  return r;
}

class Node : public LinNode {
 public:
  Node(LinBus& bus, uint32_t rate = k19200) : rate_(rate), id(bus.attach(*this)) {}
  std::optional<Response> respond(uint8_t i) override {
    auto it = table.find(i);
    return it == table.end() ? std::nullopt : std::optional<Response>(it->second);
  }
  void on_lin_event(const Event& e) override { seen.push_back(e); }
  uint32_t lin_bitrate() const override { return rate_; }

  std::vector<Event> of(Event::Kind kind) const {
    std::vector<Event> out;
    for (const Event& e : seen) {
      if (e.kind == kind) {
        out.push_back(e);
      }
    }
    return out;
  }

  uint32_t rate_;
  LinNodeId id;
  std::map<uint8_t, Response> table;
  std::vector<Event> seen;
};

struct Faults : LinFaultSource {
  FrameFaults faults_for(SimTime, uint8_t, LinNodeId) override { return next; }
  FrameFaults next;
};

class LinBusTest : public ::testing::Test {
 protected:
  void run_to(int64_t ns) { scheduler.run_until(SimTime::from_ns(ns)); }

  SimScheduler scheduler;
  LinBus bus{scheduler, Layout{}};
  Node commander{bus};
  Node responder{bus};
  Node listener{bus};
};

TEST_F(LinBusTest, AHeaderIsAnsweredFromAResponseTable) {
  responder.table[0x10] = response({0x11, 0x22});
  ASSERT_TRUE(bus.send_header(commander.id, 0x10));
  EXPECT_TRUE(bus.busy());
  run_to(at_bits(64) - 1);  // 34 header bits and 3 characters
  EXPECT_TRUE(listener.seen.empty());
  run_to(at_bits(64));
  for (Node* n : {&commander, &responder, &listener}) {
    ASSERT_EQ(n->seen.size(), 1u);
    const Event& e = n->seen[0];
    EXPECT_EQ(e.kind, Event::Kind::frame);
    EXPECT_EQ(e.at.ns(), 3'333'333);
    EXPECT_EQ(e.id, 0x10);
    EXPECT_EQ(e.response.size, 2);
    EXPECT_EQ(e.response.data[0], 0x11);
    EXPECT_EQ(e.response.data[1], 0x22);
    EXPECT_EQ(e.response.checksum, Checksum::enhanced);
    EXPECT_EQ(e.checksum_byte, 0x7C);  // ~(50h + 11h + 22h), PID 50h
    EXPECT_EQ(e.sender, commander.id);
    EXPECT_EQ(e.responder, responder.id);
    EXPECT_EQ(e.bitrate, k19200);
  }
  EXPECT_FALSE(bus.busy());
  EXPECT_EQ(bus.stats().frames, 1u);
  EXPECT_EQ(bus.stats().busy_ns, 3'333'333u);
  // The load over the last second, and in 100 ms bins, as on a CAN bus.
  EXPECT_DOUBLE_EQ(bus.load_percent(SimTime::from_ns(1'000'000'000)), 0.3333333);
  EXPECT_DOUBLE_EQ(bus.load_percent(SimTime::from_ns(1'003'333'333)), 0.0);
  const auto bins = bus.load_history(SimTime::from_ns(200'000'000));
  ASSERT_EQ(bins.size(), 2u);
  EXPECT_EQ(bins[0].busy.ns(), 3'333'333);
  EXPECT_EQ(bins[1].busy.ns(), 0);
}

TEST_F(LinBusTest, ListenersTellTheChecksumKindFromTheChecksum) {
  responder.table[0x11] = response({0x01}, Checksum::classic);
  responder.table[0x3C] = response({0x01}, Checksum::enhanced);  // diagnostic: classic anyway
  bus.send_header(commander.id, 0x11);
  run_to(at_bits(54));
  bus.send_header(commander.id, 0x3C);
  run_to(at_bits(108));
  ASSERT_EQ(listener.seen.size(), 2u);
  EXPECT_EQ(listener.seen[0].response.checksum, Checksum::classic);
  EXPECT_EQ(listener.seen[1].response.checksum, Checksum::classic);
  EXPECT_EQ(listener.seen[1].at.ns(), at_bits(108));
}

TEST_F(LinBusTest, TheCommanderPublishesItsOwnResponse) {
  ASSERT_TRUE(bus.send_frame(commander.id, 0x20, response({1, 2, 3, 4, 5, 6, 7, 8})));
  run_to(at_bits(124));
  ASSERT_EQ(listener.seen.size(), 1u);
  EXPECT_EQ(listener.seen[0].at.ns(), 6'458'333);
  EXPECT_EQ(listener.seen[0].responder, commander.id);
  EXPECT_EQ(commander.seen.at(0).responder, commander.id);
}

TEST_F(LinBusTest, NobodyAnsweringIsANoResponseErrorAfterTheLongestResponse) {
  ASSERT_TRUE(bus.send_header(commander.id, 0x05));
  // 34 header bits + 1.4 x 90 bits of the longest response.
  run_to(at_bits(160) - 1);
  EXPECT_TRUE(commander.seen.empty());
  run_to(at_bits(160));
  for (Node* n : {&commander, &responder, &listener}) {
    ASSERT_EQ(n->seen.size(), 1u);
    EXPECT_EQ(n->seen[0].kind, Event::Kind::error);
    EXPECT_EQ(n->seen[0].error, ErrorKind::no_response);
    EXPECT_EQ(n->seen[0].id, 0x05);
  }
  // With the expected length known (a schedule): 34 + 1.4 x 30 bits for two bytes.
  ASSERT_TRUE(bus.send_header(commander.id, 0x06, 2));
  run_to(at_bits(160) + at_bits(76));
  ASSERT_EQ(listener.seen.size(), 2u);
  EXPECT_EQ(listener.seen[1].at.ns(), at_bits(160) + at_bits(76));
  EXPECT_EQ(bus.stats().errors, 2u);
}

TEST_F(LinBusTest, TwoRespondersWithTheSameResponseDoNotCollide) {
  Node twin{bus};
  responder.table[0x12] = response({0x5A});
  twin.table[0x12] = response({0x5A});
  bus.send_header(commander.id, 0x12);
  run_to(at_bits(54));
  ASSERT_EQ(listener.seen.size(), 1u);
  EXPECT_EQ(listener.seen[0].kind, Event::Kind::frame);
  EXPECT_EQ(listener.seen[0].responder, responder.id);  // the first node that completed
  EXPECT_EQ(twin.seen.at(0).kind, Event::Kind::frame);
  // Both sent every bit: each is a responder of the frame (its own, `sor` in its monitor).
  EXPECT_EQ(listener.seen[0].responders, (std::vector<LinNodeId>{responder.id, twin.id}));
  EXPECT_TRUE(twin.seen[0].responded(twin.id));
  EXPECT_TRUE(responder.seen.at(0).responded(responder.id));
  EXPECT_FALSE(listener.seen[0].responded(listener.id));
}

TEST_F(LinBusTest, CollidingRespondersSeeBitErrorsAndListenersAChecksumError) {
  Node other{bus};
  responder.table[0x13] = response({0x0F});
  other.table[0x13] = response({0xF0});
  bus.send_header(commander.id, 0x13);
  run_to(at_bits(44));  // the first character: both read back 00h and stop
  for (Node* n : {&responder, &other}) {
    ASSERT_EQ(n->seen.size(), 1u);
    EXPECT_EQ(n->seen[0].error, ErrorKind::bit);
    EXPECT_EQ(n->seen[0].at.ns(), at_bits(44));
  }
  ASSERT_EQ(listener.seen.size(), 1u);
  EXPECT_EQ(listener.seen[0].error, ErrorKind::checksum);
  // What the wire carried: the AND of the first characters, then nothing.
  EXPECT_EQ(listener.seen[0].response.size, 0);
  EXPECT_EQ(listener.seen[0].checksum_byte, 0x00);
  EXPECT_EQ(commander.seen.at(0).error, ErrorKind::checksum);
}

TEST_F(LinBusTest, TheResponderThatWinsEveryBitCompletesItsFrame) {
  Node other{bus};
  responder.table[0x14] = response({0x01, 0x02});
  other.table[0x14] = response({0x01, 0x03});
  bus.send_header(commander.id, 0x14);
  run_to(at_bits(64));
  ASSERT_EQ(other.seen.size(), 1u);
  EXPECT_EQ(other.seen[0].error, ErrorKind::bit);
  EXPECT_EQ(other.seen[0].at.ns(), at_bits(54));  // at its second character
  ASSERT_EQ(listener.seen.size(), 1u);
  EXPECT_EQ(listener.seen[0].kind, Event::Kind::frame);
  EXPECT_EQ(listener.seen[0].responder, responder.id);
  EXPECT_EQ(listener.seen[0].response.data[1], 0x02);
}

TEST_F(LinBusTest, AListenerFarFromTheHeadersRateCannotSynchronize) {
  Node slow{bus, 9600};   // 50 % off: a sync error
  Node near{bus, 17000};  // 11.5 % off: synchronizes
  Node autobaud{bus, 0};  // takes the rate from the sync byte
  slow.table[0x15] = response({0x99});
  near.table[0x15] = response({0x42});
  bus.send_header(commander.id, 0x15);
  run_to(at_bits(34));
  ASSERT_EQ(slow.seen.size(), 1u);
  EXPECT_EQ(slow.seen[0].error, ErrorKind::sync);
  EXPECT_EQ(slow.seen[0].at.ns(), at_bits(34));
  run_to(at_bits(54));
  ASSERT_EQ(autobaud.seen.size(), 1u);
  EXPECT_EQ(autobaud.seen[0].response.data[0], 0x42);  // the slow node's response never went
  EXPECT_EQ(autobaud.seen[0].responder, near.id);
  EXPECT_EQ(slow.seen.size(), 1u);
}

TEST_F(LinBusTest, FaultsOnTheHeader) {
  Faults faults;
  bus.set_fault_source(&faults);
  responder.table[0x16] = response({0x01});
  faults.next.parity_error = true;
  bus.send_header(commander.id, 0x16);
  run_to(at_bits(34));
  EXPECT_TRUE(commander.seen.empty());  // it sent what it read back
  ASSERT_EQ(listener.seen.size(), 1u);
  EXPECT_EQ(listener.seen[0].error, ErrorKind::parity);
  EXPECT_EQ(listener.seen[0].id, Event::kNoId);
  EXPECT_EQ(responder.seen.at(0).error, ErrorKind::parity);  // and did not answer

  faults.next = {};
  faults.next.header_bit_error = true;
  bus.send_header(commander.id, 0x16);
  run_to(2 * at_bits(34));
  ASSERT_EQ(commander.seen.size(), 1u);
  EXPECT_EQ(commander.seen[0].error, ErrorKind::bit);
  EXPECT_EQ(listener.seen.at(1).error, ErrorKind::parity);

  faults.next = {};
  faults.next.sync_error = true;
  bus.send_header(commander.id, 0x16);
  run_to(3 * at_bits(34));
  EXPECT_EQ(listener.seen.at(2).error, ErrorKind::sync);

  faults.next = {};
  faults.next.short_break = true;
  bus.send_header(commander.id, 0x16);
  run_to(4 * at_bits(34));
  EXPECT_EQ(listener.seen.at(3).error, ErrorKind::other);
  EXPECT_EQ(bus.stats().errors, 4u);
}

TEST_F(LinBusTest, FaultsOnTheResponse) {
  Faults faults;
  bus.set_fault_source(&faults);
  responder.table[0x17] = response({0x01, 0x02});
  faults.next.no_response = true;
  bus.send_header(commander.id, 0x17);
  run_to(at_bits(160));
  EXPECT_EQ(listener.seen.at(0).error, ErrorKind::no_response);

  faults.next = {};
  faults.next.checksum_error = true;
  bus.send_header(commander.id, 0x17);
  run_to(at_bits(160) + at_bits(64));
  EXPECT_EQ(listener.seen.at(1).error, ErrorKind::checksum);
  EXPECT_EQ(listener.seen[1].at.ns(), at_bits(160) + at_bits(64));
  // The characters as received: the data, and the checksum ~(97h + 01h + 02h) = 65h with its
  // lowest bit flipped.
  EXPECT_EQ(listener.seen[1].response.size, 2);
  EXPECT_EQ(listener.seen[1].response.data[0], 0x01);
  EXPECT_EQ(listener.seen[1].response.data[1], 0x02);
  EXPECT_EQ(listener.seen[1].checksum_byte, 0x64);
  EXPECT_EQ(responder.seen.at(1).error, ErrorKind::checksum);  // it reads back what it sent

  faults.next = {};
  faults.next.response_bit_error = true;
  bus.send_header(commander.id, 0x17);
  const int64_t start = at_bits(160) + at_bits(64);
  run_to(start + at_bits(44));
  EXPECT_EQ(responder.seen.at(2).error, ErrorKind::bit);
  EXPECT_EQ(responder.seen[2].at.ns(), start + at_bits(44));
  EXPECT_EQ(listener.seen.at(2).error, ErrorKind::checksum);
}

TEST_F(LinBusTest, TheGoToSleepCommandAndAWakeUpPulse) {
  ASSERT_TRUE(bus.send_sleep(commander.id));
  run_to(at_bits(124));
  ASSERT_EQ(listener.seen.size(), 2u);
  EXPECT_EQ(listener.seen[0].kind, Event::Kind::frame);
  EXPECT_EQ(listener.seen[0].id, kMasterRequestId);
  EXPECT_EQ(listener.seen[0].response.data[0], 0x00);
  EXPECT_EQ(listener.seen[0].response.checksum, Checksum::classic);
  EXPECT_EQ(listener.seen[1].kind, Event::Kind::sleep);
  EXPECT_EQ(listener.seen[1].at.ns(), at_bits(124));

  const int64_t t = at_bits(124);
  ASSERT_TRUE(bus.send_wakeup(responder.id, microseconds(250)));
  run_to(t + 250'000);
  ASSERT_EQ(listener.seen.size(), 3u);
  EXPECT_EQ(listener.seen[2].kind, Event::Kind::wakeup);
  EXPECT_EQ(listener.seen[2].at.ns(), t + 250'000);
  EXPECT_EQ(listener.seen[2].sender, responder.id);
  EXPECT_EQ(responder.of(Event::Kind::wakeup).size(), 0u);  // not to its sender
  // A pulse shorter than 150 us is not recognized.
  ASSERT_TRUE(bus.send_wakeup(responder.id, microseconds(100)));
  run_to(t + 350'000);
  EXPECT_EQ(listener.seen.size(), 3u);
  EXPECT_EQ(bus.stats().wakeups, 2u);
}

TEST_F(LinBusTest, FourSecondsWithoutActivityAreReportedOnce) {
  responder.table[0x18] = response({0x01});
  bus.send_header(commander.id, 0x18);
  run_to(at_bits(54));
  run_to(at_bits(54) + 4'000'000'000 - 1);
  EXPECT_EQ(listener.seen.size(), 1u);
  run_to(at_bits(54) + 4'000'000'000);
  ASSERT_EQ(listener.seen.size(), 2u);
  EXPECT_EQ(listener.seen[1].error, ErrorKind::inactive);
  run_to(at_bits(54) + 20'000'000'000);
  EXPECT_EQ(listener.seen.size(), 2u);
}

TEST_F(LinBusTest, OneRequestPerNodeAndTheBusServesThemInOrder) {
  responder.table[0x19] = response({0x01});
  ASSERT_TRUE(bus.send_header(commander.id, 0x19));
  EXPECT_TRUE(bus.pending(commander.id));
  EXPECT_FALSE(bus.send_header(commander.id, 0x19));             // its one transmit buffer is taken
  ASSERT_TRUE(bus.send_wakeup(listener.id, microseconds(500)));  // waits for the frame
  run_to(at_bits(54));
  EXPECT_FALSE(bus.pending(commander.id));
  EXPECT_TRUE(bus.pending(listener.id));
  run_to(at_bits(54) + 500'000);
  ASSERT_EQ(commander.of(Event::Kind::wakeup).size(), 1u);
  EXPECT_EQ(commander.of(Event::Kind::wakeup)[0].at.ns(), at_bits(54) + 500'000);
  // A request withdrawn before it started never goes.
  ASSERT_TRUE(bus.send_header(commander.id, 0x19));
  ASSERT_TRUE(bus.send_header(listener.id, 0x19));
  bus.withdraw(listener.id);
  EXPECT_FALSE(bus.pending(listener.id));
  run_to(at_bits(54) + 500'000 + at_bits(200));
  EXPECT_EQ(bus.stats().headers, 2u);
}

TEST_F(LinBusTest, ADetachedNodeIsNeitherAskedNorTold) {
  responder.table[0x1A] = response({0x01});
  bus.send_header(commander.id, 0x1A);
  bus.detach(responder.id);
  run_to(at_bits(160));
  EXPECT_TRUE(responder.seen.empty());
  EXPECT_EQ(listener.seen.at(0).error, ErrorKind::no_response);
}

}  // namespace
}  // namespace canemu::model::lin
