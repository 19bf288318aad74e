// The fault plan on its own: matching, probability draws from a rule's seed, bit error rates,
// the report of each hit, and when a bus asks it about frames at all.
#include <gtest/gtest.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "canemu/firmware_model/bus/can_bus.hpp"
#include "canemu/firmware_model/bus/fault_plan.hpp"
#include "test_controller.hpp"

namespace canemu::model {
namespace {

// Rules with a probability draw from their own seeded generator: the same seed hits the same
// frames, another seed others, and the share hit is near the probability.
TEST(FaultPlanProbability, DrawsFromTheSeedAndRepeats) {
  const Frame f = testing::k123;
  const EncodedFrame bits = encode(f);
  auto hits = [&](uint64_t seed) {
    FaultPlan plan;
    FaultRule r;
    r.fault.error = CanErrorType::bit;
    r.probability = 0.25;
    r.seed = seed;
    plan.add(r);
    std::vector<bool> hit;
    for (int i = 0; i < 4000; ++i) {
      hit.push_back(plan.on_frame(FrameContext{SimTime::from_ns(i), 0, f, bits}).error.has_value());
    }
    EXPECT_EQ(plan.rule(0).seen, 4000u);
    EXPECT_EQ(plan.rule(0).hits, static_cast<uint64_t>(std::count(hit.begin(), hit.end(), true)));
    return hit;
  };
  const auto a = hits(7);
  EXPECT_EQ(a, hits(7));
  EXPECT_NE(a, hits(8));
  const auto n = std::count(a.begin(), a.end(), true);
  EXPECT_GT(n, 900);  // 1000 expected; 4 standard deviations is 110
  EXPECT_LT(n, 1100);
}

// A bit error rate: the first bit hit (geometric over the frame's bits) becomes a bit error at
// that bit; frames with no bit hit pass untouched.
TEST(FaultPlanProbability, ABitErrorRateHitsAtTheFirstBitDrawn) {
  const Frame f = testing::k123;
  const EncodedFrame bits = encode(f);
  FaultPlan plan;
  FaultRule r;
  r.bit_error_rate = 0.01;
  r.seed = 11;
  plan.add(r);
  int hit = 0;
  for (int i = 0; i < 4000; ++i) {
    const FrameFault ff = plan.on_frame(FrameContext{SimTime::from_ns(i), 0, f, bits});
    if (ff.error) {
      ++hit;
      EXPECT_EQ(*ff.error, CanErrorType::bit);
      ASSERT_TRUE(ff.bit);
      EXPECT_LT(*ff.bit, bits.length);
    }
  }
  // 1 - 0.99^62 = 46 % of the frames; 4 standard deviations is 126 of 4000.
  EXPECT_GT(hit, 1840 - 130);
  EXPECT_LT(hit, 1840 + 130);
  EXPECT_EQ(plan.rule(0).hits, static_cast<uint64_t>(hit));
}

// Every hit is told, with the rule that hit and the frame; frames no rule hits are not.
TEST(FaultPlan, TellsEveryHitWithItsRuleAndFrame) {
  const EncodedFrame bits = encode(testing::k123);
  FaultPlan plan;
  FaultRule miss;
  miss.match.id = 0x456;
  miss.match.mask = 0x7FF;
  miss.fault.error = CanErrorType::crc;
  plan.add(miss);
  FaultRule hit;
  hit.fault.error = CanErrorType::stuff;
  hit.count = 2;
  plan.add(hit);
  std::vector<std::pair<std::size_t, int64_t>> told;
  plan.on_hit = [&](std::size_t rule, const FrameContext& ctx, const FrameFault& fault) {
    EXPECT_EQ(ctx.frame.id(), 0x123u);
    EXPECT_EQ(fault.error, CanErrorType::stuff);
    EXPECT_EQ(plan.rule(rule).hits, told.size() + 1);  // counted before it is told
    told.emplace_back(rule, ctx.sof.ns());
  };
  for (int64_t t : {10, 20, 30}) {
    plan.on_frame(FrameContext{SimTime::from_ns(t), 0, testing::k123, bits});
  }
  EXPECT_EQ(told, (std::vector<std::pair<std::size_t, int64_t>>{{1, 10}, {1, 20}}));
}

// A plan without rules is not asked about frames; a rule added later hits from the next frame.
TEST(FaultPlan, AsksForFramesOnlyWhileItHasRules) {
  FaultPlan plan;
  EXPECT_FALSE(plan.frames_wanted());
  const std::size_t one = plan.add(FaultRule{});
  const std::size_t two = plan.add(FaultRule{});
  EXPECT_TRUE(plan.frames_wanted());
  plan.remove(one);
  EXPECT_TRUE(plan.frames_wanted());
  plan.remove(two);
  EXPECT_FALSE(plan.frames_wanted());
  plan.add(FaultRule{});
  plan.clear();
  EXPECT_FALSE(plan.frames_wanted());

  testing::BusFixture f;
  testing::TestController a(f.bus), b(f.bus);
  a.send(testing::k123);
  f.run_until(1'000'000);
  ASSERT_EQ(a.sent.size(), 1u);
  EXPECT_TRUE(a.errors.empty());
  f.plan.add(testing::fault_rule(CanErrorType::bit, 1));
  a.send(testing::k123);
  f.run_until(2'000'000);
  EXPECT_EQ(a.errors.size(), 1u);
  EXPECT_EQ(a.sent.size(), 2u);  // its retry went through
}

}  // namespace
}  // namespace canemu::model
