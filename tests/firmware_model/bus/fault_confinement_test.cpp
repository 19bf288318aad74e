// ISO 11898-1:2015 12.1.4.2, one rule per test (rule numbers in the names), at counter level.
// The rules that depend on what a node sees on the wire are tested through the bus in
// can_bus_faults_test.cpp.
#include "canemu/firmware_model/bus/fault_confinement.hpp"

#include <gtest/gtest.h>

#include "case_name.hpp"

namespace canemu::model {
namespace {

// Rules 1 to 6: what one error (or one dominant sequence per role) adds to each counter.
struct CounterRule {
  const char* name;
  void (*errors)(FaultConfinement&);
  uint16_t tec;
  uint16_t rec;
};

class FaultConfinementRule : public ::testing::TestWithParam<CounterRule> {};

TEST_P(FaultConfinementRule, AddsToTheCountersItNames) {
  FaultConfinement fc;
  GetParam().errors(fc);
  EXPECT_EQ(fc.tec(), GetParam().tec);
  EXPECT_EQ(fc.rec(), GetParam().rec);
}

INSTANTIATE_TEST_SUITE_P(
    FaultConfinement, FaultConfinementRule,
    ::testing::Values(CounterRule{"Rule1ReceiverErrorAddsOne",
                                  [](FaultConfinement& fc) { fc.receiver_detected_error(); }, 0, 1},
                      CounterRule{"Rules2And5SevereReceiverErrorAddsEight",
                                  [](FaultConfinement& fc) { fc.receiver_severe_error(); }, 0, 8},
                      CounterRule{"Rules3And4TransmitterErrorAddsEight",
                                  [](FaultConfinement& fc) { fc.transmitter_error(); }, 8, 0},
                      CounterRule{"Rule6DominantSequencesCountForTheRole",
                                  [](FaultConfinement& fc) {
                                    fc.dominant_sequence(ErrorRole::transmitter);
                                    fc.dominant_sequence(ErrorRole::receiver);
                                  },
                                  8, 8}),
    test_support::CaseName{});
;

TEST(FaultConfinement, TheReceiveCounterStopsAtTheControllersWidth) {
  FaultConfinement fc(255);
  fc.set_counters(0, 250);
  fc.receiver_severe_error();
  EXPECT_EQ(fc.rec(), 255);
  fc.receiver_detected_error();
  fc.dominant_sequence(ErrorRole::receiver);
  EXPECT_EQ(fc.rec(), 255);
  fc.set_counters(0, 300);  // a direct write is no wider than the counter
  EXPECT_EQ(fc.rec(), 255);
  fc.reset();  // the width survives a reset
  fc.set_counters(0, 254);
  fc.receiver_severe_error();
  EXPECT_EQ(fc.rec(), 255);
  // Without a width of its own, the counter only stops at 65535.
  FaultConfinement wide;
  wide.set_counters(0, 65530);
  wide.receiver_severe_error();
  EXPECT_EQ(wide.rec(), 65535);
}

// Rules 7 and 8: each good frame, from given counters, and the state that follows.
struct SuccessRule {
  const char* name;
  uint16_t tec;  // counters before
  uint16_t rec;
  ErrorState before;
  void (*success)(FaultConfinement&);
  int frames;
  uint16_t want_tec;
  uint16_t want_rec;
  ErrorState after;
};

void transmitted(FaultConfinement& fc) {
  fc.transmit_succeeded();
}
void received(FaultConfinement& fc) {
  fc.receive_succeeded();
}

class FaultConfinementSuccess : public ::testing::TestWithParam<SuccessRule> {};

TEST_P(FaultConfinementSuccess, CountsDownAndSetsTheState) {
  const SuccessRule& c = GetParam();
  FaultConfinement fc;
  fc.set_counters(c.tec, c.rec);
  EXPECT_EQ(fc.state(), c.before);
  for (int i = 0; i < c.frames; ++i) {
    c.success(fc);
  }
  EXPECT_EQ(fc.tec(), c.want_tec);
  EXPECT_EQ(fc.rec(), c.want_rec);
  EXPECT_EQ(fc.state(), c.after);
  EXPECT_EQ(fc.error_passive(), c.after == ErrorState::passive);
}

constexpr ErrorState kActive = ErrorState::active;
constexpr ErrorState kWarning = ErrorState::warning;
constexpr ErrorState kPassive = ErrorState::passive;

INSTANTIATE_TEST_SUITE_P(
    FaultConfinement, FaultConfinementSuccess,
    ::testing::Values(SuccessRule{"Rule7SuccessfulTransmissionSubtractsOne", 2, 0, kActive,
                                  transmitted, 1, 1, 0, kActive},
                      SuccessRule{"Rule7StopsAtZero", 2, 0, kActive, transmitted, 3, 0, 0, kActive},
                      SuccessRule{"Rule8SuccessfulReceptionSubtractsOne", 0, 5, kActive, received,
                                  1, 0, 4, kActive},
                      SuccessRule{"Rule8ReturnsAPassiveReceiverTo127", 0, 200, kPassive, received,
                                  1, 0, 127, kWarning},
                      SuccessRule{"Rule8StopsAtZero", 0, 0, kActive, received, 1, 0, 0, kActive},
                      SuccessRule{"ErrorPassiveReturnsToActiveWhenBothCountersAreAtMost127", 128, 0,
                                  kPassive, transmitted, 1, 127, 0, kWarning}),
    test_support::CaseName{});
;

TEST(FaultConfinement, StatesFollowTheThresholds) {
  FaultConfinement fc;
  EXPECT_EQ(fc.state(), ErrorState::active);
  struct Row {
    uint16_t tec;
    uint16_t rec;
    ErrorState state;
  };
  for (const Row& row : {Row{95, 95, kActive}, Row{96, 0, kWarning}, Row{0, 96, kWarning},
                         Row{127, 127, kWarning}, Row{128, 0, kPassive}, Row{0, 128, kPassive},
                         Row{255, 0, kPassive}, Row{256, 0, ErrorState::bus_off}}) {
    fc.set_counters(row.tec, row.rec);
    EXPECT_EQ(fc.state(), row.state) << row.tec << "/" << row.rec;
    EXPECT_EQ(fc.error_passive(), row.state == kPassive) << row.tec << "/" << row.rec;
  }
}

TEST(FaultConfinement, WarningLimitIsProgrammable) {
  FaultConfinement fc;
  fc.set_warning_limit(50);
  fc.set_counters(50, 0);
  EXPECT_EQ(fc.state(), ErrorState::warning);
}

TEST(FaultConfinement, TransmitCounterAbove255IsBusOffAndFreezesCounting) {
  FaultConfinement fc;
  for (int i = 0; i < 31; ++i) {
    fc.transmitter_error();
  }
  EXPECT_EQ(fc.tec(), 248);
  EXPECT_FALSE(fc.bus_off());
  fc.transmitter_error();
  EXPECT_TRUE(fc.bus_off());
  EXPECT_EQ(fc.state(), ErrorState::bus_off);
  fc.receiver_detected_error();
  fc.transmitter_error();
  EXPECT_EQ(fc.tec(), 256);
  EXPECT_EQ(fc.rec(), 0);
}

// passive_or_off_changes() changes whenever error_passive() or bus_off() may have (the bus keeps
// a frame's roles while it does not): each way in and out of the passive and bus-off states.
TEST(FaultConfinement, TheChangeNumberMovesWithEveryWayInOrOutOfPassiveAndBusOff) {
  FaultConfinement fc(255);
  auto changed = [&fc, last = fc.passive_or_off_changes()]() mutable {
    const bool moved = fc.passive_or_off_changes() != last;
    last = fc.passive_or_off_changes();
    return moved;
  };
  fc.set_counters(128, 0);  // a write
  EXPECT_TRUE(fc.error_passive());
  EXPECT_TRUE(changed());
  fc.transmit_succeeded();  // 128 -> 127: active again
  EXPECT_FALSE(fc.error_passive());
  EXPECT_TRUE(changed());
  fc.transmit_succeeded();  // 127 -> 126: no state crossed
  EXPECT_FALSE(changed());
  fc.set_counters(0, 200);
  EXPECT_TRUE(changed());
  fc.receive_succeeded();  // 200 -> 127: active again
  EXPECT_FALSE(fc.error_passive());
  EXPECT_TRUE(changed());
  fc.receive_succeeded();  // 127 -> 126
  EXPECT_FALSE(changed());
  fc.receiver_detected_error();  // a counted error
  EXPECT_TRUE(changed());
  for (int i = 0; i < 32; ++i) {
    fc.transmitter_error();
  }
  EXPECT_TRUE(fc.bus_off());
  EXPECT_TRUE(changed());
  fc.begin_recovery();
  EXPECT_TRUE(fc.recessive_sequences(kBusOffRecoverySequences));  // recovered: reset
  EXPECT_FALSE(fc.bus_off());
  EXPECT_TRUE(changed());
  FaultConfinement other(255);
  other.set_counters(300, 0);
  fc = other;  // an assignment, even from a copy whose own number happens to match
  EXPECT_TRUE(fc.bus_off());
  EXPECT_TRUE(changed());
  fc.reset();
  EXPECT_TRUE(changed());
}

TEST(FaultConfinement, RecoveryNeeds128SequencesAfterItBegins) {
  FaultConfinement fc;
  fc.set_counters(256, 3);
  EXPECT_FALSE(fc.recessive_sequences(200));  // not counting before recovery begins
  fc.begin_recovery();
  EXPECT_TRUE(fc.recovering());
  EXPECT_FALSE(fc.recessive_sequences(127));
  EXPECT_EQ(fc.recovery_sequences_left(), 1u);
  EXPECT_TRUE(fc.recessive_sequences(1));
  EXPECT_FALSE(fc.bus_off());
  EXPECT_EQ(fc.tec(), 0);
  EXPECT_EQ(fc.rec(), 0);
  EXPECT_EQ(fc.state(), ErrorState::active);
}

}  // namespace
}  // namespace canemu::model
