#include "canemu/ipc/duration.hpp"

#include <gtest/gtest.h>

namespace canemu::ipc {
namespace {

TEST(ParseDuration, ReadsEachUnitInNanoseconds) {
  EXPECT_EQ(parse_duration("150ns"), 150);
  EXPECT_EQ(parse_duration("20us"), 20'000);
  EXPECT_EQ(parse_duration("10ms"), 10'000'000);
  EXPECT_EQ(parse_duration("2s"), 2'000'000'000);
  EXPECT_EQ(parse_duration("0s"), 0);
  EXPECT_EQ(parse_duration("0"), 0);  // zero needs no unit; any other number does
  EXPECT_EQ(parse_duration("0.0"), 0);
  EXPECT_EQ(parse_duration("5"), std::nullopt);
}

TEST(ParseDuration, ReadsAFractionRoundedToTheNearestNanosecond) {
  EXPECT_EQ(parse_duration("1.5ms"), 1'500'000);
  EXPECT_EQ(parse_duration(".25us"), 250);
  EXPECT_EQ(parse_duration("0.0000000004s"), 0);
  EXPECT_EQ(parse_duration("0.0000000006s"), 1);
}

TEST(ParseDuration, RefusesTextThatIsNotOne) {
  for (const char* text :
       {"", "10", "ms", "10 ms", "10min", "1.2.3s", "-1s", ".s", "1e3ns", "10000000000s"}) {
    EXPECT_EQ(parse_duration(text), std::nullopt) << text;
  }
}

}  // namespace
}  // namespace canemu::ipc
