// ISO 11898-1:2015 12.1.4.2, one rule per test (rule numbers in the names), at counter level.
// The rules that depend on what a node sees on the wire are tested through the bus in
// can_bus_faults_test.cpp.
#include "canemu/firmware_model/bus/fault_confinement.hpp"

#include <gtest/gtest.h>

namespace canemu::model {
namespace {

TEST(FaultConfinement, Rule1ReceiverErrorAddsOne) {
  FaultConfinement fc;
  fc.receiver_detected_error();
  EXPECT_EQ(fc.rec(), 1);
  EXPECT_EQ(fc.tec(), 0);
}

TEST(FaultConfinement, Rules2And5SevereReceiverErrorAddsEight) {
  FaultConfinement fc;
  fc.receiver_severe_error();
  EXPECT_EQ(fc.rec(), 8);
}

TEST(FaultConfinement, Rules3And4TransmitterErrorAddsEight) {
  FaultConfinement fc;
  fc.transmitter_error();
  EXPECT_EQ(fc.tec(), 8);
  EXPECT_EQ(fc.rec(), 0);
}

TEST(FaultConfinement, Rule6DominantSequencesCountForTheRole) {
  FaultConfinement fc;
  fc.dominant_sequence(ErrorRole::transmitter);
  fc.dominant_sequence(ErrorRole::receiver);
  EXPECT_EQ(fc.tec(), 8);
  EXPECT_EQ(fc.rec(), 8);
}

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

TEST(FaultConfinement, Rule7SuccessfulTransmissionSubtractsOneDownToZero) {
  FaultConfinement fc;
  fc.set_counters(2, 0);
  fc.transmit_succeeded();
  EXPECT_EQ(fc.tec(), 1);
  fc.transmit_succeeded();
  fc.transmit_succeeded();
  EXPECT_EQ(fc.tec(), 0);
}

TEST(FaultConfinement, Rule8SuccessfulReceptionSubtractsOneOrReturnsTo127) {
  FaultConfinement fc;
  fc.set_counters(0, 5);
  fc.receive_succeeded();
  EXPECT_EQ(fc.rec(), 4);
  fc.set_counters(0, 200);
  EXPECT_EQ(fc.state(), ErrorState::passive);
  fc.receive_succeeded();
  EXPECT_EQ(fc.rec(), 127);
  EXPECT_EQ(fc.state(), ErrorState::warning);
  fc.set_counters(0, 0);
  fc.receive_succeeded();
  EXPECT_EQ(fc.rec(), 0);
}

TEST(FaultConfinement, StatesFollowTheThresholds) {
  FaultConfinement fc;
  EXPECT_EQ(fc.state(), ErrorState::active);
  fc.set_counters(95, 95);
  EXPECT_EQ(fc.state(), ErrorState::active);
  fc.set_counters(96, 0);
  EXPECT_EQ(fc.state(), ErrorState::warning);
  fc.set_counters(0, 96);
  EXPECT_EQ(fc.state(), ErrorState::warning);
  fc.set_counters(127, 127);
  EXPECT_EQ(fc.state(), ErrorState::warning);
  fc.set_counters(128, 0);
  EXPECT_EQ(fc.state(), ErrorState::passive);
  EXPECT_TRUE(fc.error_passive());
  fc.set_counters(0, 128);
  EXPECT_EQ(fc.state(), ErrorState::passive);
  fc.set_counters(255, 0);
  EXPECT_EQ(fc.state(), ErrorState::passive);
  fc.set_counters(256, 0);
  EXPECT_EQ(fc.state(), ErrorState::bus_off);
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

TEST(FaultConfinement, ErrorPassiveReturnsToActiveWhenBothCountersAreAtMost127) {
  FaultConfinement fc;
  fc.set_counters(128, 0);
  fc.transmit_succeeded();
  EXPECT_FALSE(fc.error_passive());
  EXPECT_EQ(fc.state(), ErrorState::warning);
}

}  // namespace
}  // namespace canemu::model
