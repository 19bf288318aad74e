// Arbitration on its own: the contenders' bit sequences in, who sends, who lost where, who
// collides where.
#include "canemu/firmware_model/bus/arbitration.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "test_controller.hpp"

namespace canemu::model {
namespace {

using testing::frame;

TEST(Arbitration, TheLowestIdentifierWinsAndTheOthersLoseAtTheirFirstRecessiveBit) {
  // 0x0FF = 000 1111 1111 against 0x100 and 0x101 = 001 ...: both lose at ID8, bit 3.
  const EncodedFrame a = encode(frame(0x100, {}));
  const EncodedFrame b = encode(frame(0x0FF, {}));
  const EncodedFrame c = encode(frame(0x101, {}));
  const std::vector<Arbitration::Contender> contenders{{7, &a}, {8, &b}, {9, &c}};
  Arbitration arb;
  arb.resolve(contenders);
  EXPECT_EQ(arb.winner(), 8u);
  EXPECT_EQ(&arb.winning_bits(), &b);
  EXPECT_EQ(arb.senders(), std::vector<NodeId>{8});
  ASSERT_EQ(arb.lost().size(), 2u);
  EXPECT_EQ(arb.lost()[0].node, 7u);
  EXPECT_EQ(arb.lost()[0].bit, 3);
  EXPECT_EQ(arb.lost()[1].node, 9u);
  EXPECT_EQ(arb.lost()[1].bit, 3);
  EXPECT_TRUE(arb.collisions().empty());
}

TEST(Arbitration, IdenticalFramesTieWhateverTheirEncodingsHoldPastTheEnd) {
  // What lies past a frame's end is left undefined by the encoder (a reused encoding keeps an
  // older frame's bits there): it must not pick the winner among identical frames.
  const EncodedFrame a = encode(frame(0x123, {1, 2, 3, 4, 5, 6, 7, 8}));
  ASSERT_GT(a.length, 64u);
  ASSERT_LT(a.length, 128u);
  EncodedFrame low = a;
  EncodedFrame high = a;
  low.level[1] &= ~(~uint64_t{0} >> (a.length - 64));  // dominant after the end
  high.level[1] |= ~uint64_t{0} >> (a.length - 64);    // recessive after the end
  low.level[2] = 0;
  high.level[2] = ~uint64_t{0};
  for (const bool high_first : {true, false}) {
    const std::vector<Arbitration::Contender> contenders{{1, high_first ? &high : &low},
                                                         {2, high_first ? &low : &high}};
    Arbitration arb;
    arb.resolve(contenders);
    EXPECT_EQ(arb.senders(), (std::vector<NodeId>{1, 2})) << high_first;
    EXPECT_EQ(&arb.winning_bits(), contenders[0].bits) << high_first;
    EXPECT_TRUE(arb.lost().empty());
    EXPECT_TRUE(arb.collisions().empty());
  }
}

TEST(Arbitration, AStandardFrameBeatsAnExtendedOneWithTheSameBaseIdentifierAtRtr) {
  // 0x123 = 001 0010 0011 has no stuff bit before its RTR, bit 12, where the extended frame
  // sends its recessive SRR.
  const EncodedFrame ext = encode(frame(0x123u << 18, {}, true));
  const EncodedFrame std11 = encode(frame(0x123, {}));
  const std::vector<Arbitration::Contender> contenders{{0, &ext}, {1, &std11}};
  Arbitration arb;
  arb.resolve(contenders);
  EXPECT_EQ(arb.winner(), 1u);
  ASSERT_EQ(arb.lost().size(), 1u);
  EXPECT_EQ(arb.lost()[0].node, 0u);
  EXPECT_EQ(arb.lost()[0].bit, 12);
}

TEST(Arbitration, IdenticalFramesGoOutTogetherWithTheFirstContenderAsWinner) {
  const EncodedFrame a = encode(testing::k123);
  const EncodedFrame b = encode(testing::k123);
  const std::vector<Arbitration::Contender> contenders{{4, &a}, {2, &b}};
  Arbitration arb;
  arb.resolve(contenders);
  EXPECT_EQ(arb.senders(), (std::vector<NodeId>{4, 2}));
  EXPECT_TRUE(arb.lost().empty());
  EXPECT_TRUE(arb.collisions().empty());
  EXPECT_FALSE(arb.collision_of(2).has_value());
}

TEST(Arbitration, TheSameIdentifierWithOtherContentCollidesAfterTheArbitrationField) {
  // Identifier 0 with DLC 0 and with DLC 1 differ first at DLC0, bit 21 (stuff bits at 5, 11
  // and 17): both send, the DLC 1 frame collides there (it sends recessive).
  const EncodedFrame dlc1 = encode(frame(0x000, {0x00}));
  const EncodedFrame dlc0 = encode(testing::kZero);
  const std::vector<Arbitration::Contender> contenders{{0, &dlc1}, {1, &dlc0}};
  Arbitration arb;
  arb.resolve(contenders);
  EXPECT_EQ(arb.winner(), 1u);
  EXPECT_EQ(arb.senders(), (std::vector<NodeId>{1, 0}));
  EXPECT_TRUE(arb.lost().empty());
  ASSERT_EQ(arb.collisions().size(), 1u);
  EXPECT_EQ(arb.collisions()[0].node, 0u);
  EXPECT_EQ(arb.collisions()[0].bit, 21);
  EXPECT_EQ(arb.collision_of(0), std::optional<uint16_t>(21));
  EXPECT_FALSE(arb.collision_of(1).has_value());
}

TEST(Arbitration, FirstDifferenceLooksOnlyWithinTheShorterFrame) {
  const EncodedFrame zero = encode(testing::kZero);
  EXPECT_FALSE(Arbitration::first_difference(zero, zero).has_value());
  EXPECT_EQ(Arbitration::first_difference(zero, encode(frame(0x100, {}))),
            std::optional<uint16_t>(3));
}

TEST(Arbitration, ResolvingAgainForgetsThePreviousFrame) {
  const EncodedFrame a = encode(frame(0x100, {}));
  const EncodedFrame b = encode(frame(0x0FF, {}));
  Arbitration arb;
  const std::vector<Arbitration::Contender> both{{0, &a}, {1, &b}};
  arb.resolve(both);
  const std::vector<Arbitration::Contender> one{{0, &a}};
  arb.resolve(one);
  EXPECT_EQ(arb.senders(), std::vector<NodeId>{0});
  EXPECT_TRUE(arb.lost().empty());
}

}  // namespace
}  // namespace canemu::model
