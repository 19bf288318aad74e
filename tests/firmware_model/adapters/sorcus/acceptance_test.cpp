// Buffer 15's automatic acceptance filter: the manual's two examples (digest §1.5) and the
// "all bits equal" rule where a chained XNOR would differ.
#include "canemu/firmware_model/adapters/sorcus/acceptance.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace canemu::model::sorcus {
namespace {

std::vector<uint32_t> passing(const AcceptanceFilter& f) {
  std::vector<uint32_t> out;
  for (uint32_t id = 0; id <= 0x7FF; ++id) {
    if (f.passes(id)) {
      out.push_back(id);
    }
  }
  return out;
}

TEST(XcanAcceptance, Example1PassesOnlyThreeAndSeven) {
  const std::vector<uint32_t> ids{0x03, 0x07};
  const AcceptanceFilter f = automatic_filter(ids, false);
  EXPECT_EQ(f.acc, 0x7FBu);
  EXPECT_EQ(f.idm, 0x003u);
  EXPECT_EQ(passing(f), (std::vector<uint32_t>{0x03, 0x07}));
}

TEST(XcanAcceptance, Example2PassesZeroToSevenAndTwentyToTwentySeven) {
  const std::vector<uint32_t> ids{0x20, 0x07};
  const AcceptanceFilter f = automatic_filter(ids, false);
  EXPECT_EQ(f.acc, 0x7D8u);
  EXPECT_EQ(f.idm, 0x000u);
  std::vector<uint32_t> expected;
  for (uint32_t id = 0x00; id <= 0x07; ++id) {
    expected.push_back(id);
  }
  for (uint32_t id = 0x20; id <= 0x27; ++id) {
    expected.push_back(id);
  }
  EXPECT_EQ(passing(f), expected);  // the two wanted IDs and «weitere 14 unerwünschte IDs»
}

TEST(XcanAcceptance, ThreeIdsAgreeingOnAZeroBitCompareItUnlikeAChainedXnor) {
  // Bit 3 is 0 in all three IDs: "all bits equal" compares it; (0 XNOR 0) XNOR 0 = 0 would not.
  const std::vector<uint32_t> ids{0x01, 0x02, 0x04};
  const AcceptanceFilter f = automatic_filter(ids, false);
  EXPECT_EQ(f.acc, 0x7F8u);
  EXPECT_EQ(f.idm, 0x000u);
  EXPECT_FALSE(f.passes(0x08));
  EXPECT_TRUE(f.passes(0x07));
}

TEST(XcanAcceptance, OneIdComparesEveryBitOfItsWidth) {
  const std::vector<uint32_t> ids{0x12345678};
  const AcceptanceFilter f = automatic_filter(ids, true);
  EXPECT_EQ(f.acc, 0x1FFFFFFFu);
  EXPECT_EQ(f.idm, 0x12345678u);
  EXPECT_TRUE(f.passes(0x12345678));
  EXPECT_FALSE(f.passes(0x12345679));
}

}  // namespace
}  // namespace canemu::model::sorcus
