// The VCI message filters (VCI C++ guide 5.2.4, docs/vci.md "Filters"): filter values,
// the four modes, acceptance filter and ID list, the afc codes, list capacity and the pair of
// 11-bit and 29-bit filters.
#include "canemu/firmware_model/adapters/ixxat/filter.hpp"

#include <gtest/gtest.h>

namespace canemu::model {
namespace {

using ixxat::filter_value;
using ixxat::FilterPair;
using ixxat::IdFilter;

constexpr uint32_t kStdMask = 0xFFF;       // every bit of an 11-bit filter value
constexpr uint32_t kExtMask = 0x3FFFFFFF;  // every bit of a 29-bit filter value

IdFilter std_filter(uint8_t mode = CAN_FILTER_INCL) {
  return IdFilter(false, ixxat::kStdListCapacity, mode);
}
IdFilter ext_filter(uint32_t capacity, uint8_t mode = CAN_FILTER_INCL) {
  return IdFilter(true, capacity, mode);
}

TEST(VciFilter, AFilterValueIsTheIdentifierShiftedLeftWithRtrInBitZero) {
  EXPECT_EQ(filter_value(0x123, false), 0x246u);
  EXPECT_EQ(filter_value(0x123, true), 0x247u);
  EXPECT_EQ(filter_value(0x7FF, true), 0xFFFu);
  EXPECT_EQ(filter_value(0x1FFFFFFF, true), 0x3FFFFFFFu);
}

TEST(VciFilter, OnlyLockPassInclAndExclAreFilterModes) {
  EXPECT_TRUE(ixxat::valid_filter_mode(CAN_FILTER_LOCK));
  EXPECT_TRUE(ixxat::valid_filter_mode(CAN_FILTER_PASS));
  EXPECT_TRUE(ixxat::valid_filter_mode(CAN_FILTER_INCL));
  EXPECT_TRUE(ixxat::valid_filter_mode(CAN_FILTER_EXCL));
  EXPECT_FALSE(ixxat::valid_filter_mode(CAN_FILTER_VOID));
  EXPECT_FALSE(ixxat::valid_filter_mode(5));
  EXPECT_FALSE(ixxat::valid_filter_mode(CAN_FILTER_PASS | CAN_FILTER_SRRA));
}

TEST(VciFilter, SetModeRefusesAnUnknownModeAndKeepsTheOldOne) {
  IdFilter f = std_filter();
  EXPECT_EQ(f.set_mode(CAN_FILTER_VOID), VCI_E_INVALIDARG);
  EXPECT_EQ(f.set_mode(CAN_FILTER_INCL | CAN_FILTER_SRRA), VCI_E_INVALIDARG);
  EXPECT_EQ(f.mode(), CAN_FILTER_INCL);
  EXPECT_EQ(f.set_mode(CAN_FILTER_EXCL), VCI_OK);
  EXPECT_EQ(f.mode(), CAN_FILTER_EXCL);
}

TEST(VciFilter, TheInitialAcceptanceFilterAcceptsEveryValueWithFilter1) {
  IdFilter s = std_filter();
  IdFilter e = ext_filter(CAN_FILTER_SIZE_EXT);
  EXPECT_FALSE(s.extended());
  EXPECT_TRUE(e.extended());
  for (uint32_t v : {0x000u, 0x001u, 0x246u, 0xFFFu}) {
    EXPECT_EQ(s.accept(v), CAN_ACCEPT_FILTER_1) << v;
  }
  for (uint32_t v : {0x0u, 0x1u, 0x2468ACEu, 0x3FFFFFFFu}) {
    EXPECT_EQ(e.accept(v), CAN_ACCEPT_FILTER_1) << v;
  }
  EXPECT_EQ(s.list_size(), 0u);
  EXPECT_EQ(e.list_size(), 0u);
}

TEST(VciFilter, LockRejectsEveryDataFrameAndPassAcceptsEveryOneWithAcceptAlways) {
  IdFilter lock = std_filter(CAN_FILTER_LOCK);
  ASSERT_EQ(lock.add_ids(filter_value(0x123, false), kStdMask), VCI_OK);
  IdFilter pass = std_filter(CAN_FILTER_PASS);
  pass.set_acceptance(CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE);
  for (uint32_t v : {0x000u, 0x246u, 0x247u, 0xFFFu}) {
    EXPECT_EQ(lock.accept(v), CAN_ACCEPT_REJECT) << v;  // even the listed 0x123
    EXPECT_EQ(pass.accept(v), CAN_ACCEPT_ALWAYS) << v;  // even with the acceptance filter closed
  }
}

// The guide's worked example: code 001 0000 0000 0, mask 111 1111 1100 1.
TEST(VciFilter, TheWorkedExamplePassesDataFrames100To103AndNothingElse) {
  IdFilter f = std_filter();
  f.set_acceptance(0x200, 0xFF9);
  for (uint32_t id = 0x100; id <= 0x103; ++id) {
    EXPECT_EQ(f.accept(filter_value(id, false)), CAN_ACCEPT_FILTER_1) << id;
    EXPECT_EQ(f.accept(filter_value(id, true)), CAN_ACCEPT_REJECT) << id;  // RTR bit relevant
  }
  EXPECT_EQ(f.accept(filter_value(0x104, false)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(f.accept(filter_value(0x0FF, false)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(f.accept(filter_value(0x500, false)), CAN_ACCEPT_REJECT);
  // Exactly 4 of the 4096 filter values pass.
  int passed = 0;
  for (uint32_t v = 0; v < ixxat::kStdListCapacity; ++v) {
    passed += f.accept(v) != CAN_ACCEPT_REJECT ? 1 : 0;
  }
  EXPECT_EQ(passed, 4);
}

TEST(VciFilter, WithTheAcceptanceFilterClosedInclPassesListedValuesWithFilter2) {
  IdFilter f = std_filter();
  f.set_acceptance(CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE);
  ASSERT_EQ(f.add_ids(filter_value(0x123, false), kStdMask), VCI_OK);
  EXPECT_EQ(f.accept(filter_value(0x123, false)), CAN_ACCEPT_FILTER_2);
  EXPECT_EQ(f.accept(filter_value(0x123, true)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(f.accept(filter_value(0x122, false)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(f.accept(filter_value(0x124, false)), CAN_ACCEPT_REJECT);
}

TEST(VciFilter, TheAcceptanceFilterDecidesBeforeTheList) {
  IdFilter f = std_filter();
  f.set_acceptance(filter_value(0x123, false), kStdMask);
  ASSERT_EQ(f.add_ids(filter_value(0x123, false), kStdMask), VCI_OK);
  ASSERT_EQ(f.add_ids(filter_value(0x124, false), kStdMask), VCI_OK);
  EXPECT_EQ(f.accept(filter_value(0x123, false)), CAN_ACCEPT_FILTER_1);  // in both
  EXPECT_EQ(f.accept(filter_value(0x124, false)), CAN_ACCEPT_FILTER_2);
}

TEST(VciFilter, ExclPassesExactlyWhatInclRejectsWithPassExcl) {
  IdFilter incl = std_filter(CAN_FILTER_INCL);
  IdFilter excl = std_filter(CAN_FILTER_EXCL);
  for (IdFilter* f : {&incl, &excl}) {
    f->set_acceptance(0x200, 0xFF9);                                   // 0x100..0x103
    ASSERT_EQ(f->add_ids(filter_value(0x7F0, false), 0xFE1), VCI_OK);  // 0x7F0..0x7FF
    ASSERT_EQ(f->add_ids(filter_value(0x055, true), kStdMask), VCI_OK);
  }
  int passed_incl = 0;
  for (uint32_t v = 0; v < ixxat::kStdListCapacity; ++v) {
    const uint8_t a = incl.accept(v);
    const uint8_t b = excl.accept(v);
    EXPECT_NE(a == CAN_ACCEPT_REJECT, b == CAN_ACCEPT_REJECT) << v;
    if (b != CAN_ACCEPT_REJECT) {
      EXPECT_EQ(b, CAN_ACCEPT_PASSEXCL) << v;
    } else {
      ++passed_incl;
    }
  }
  EXPECT_EQ(passed_incl, 4 + 16 + 1);
  EXPECT_EQ(excl.accept(filter_value(0x7F5, false)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(excl.accept(filter_value(0x7F5, true)), CAN_ACCEPT_PASSEXCL);
  EXPECT_EQ(excl.accept(filter_value(0x055, true)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(excl.accept(filter_value(0x055, false)), CAN_ACCEPT_PASSEXCL);
}

// CODE_ALL / MASK_ALL matches every value, and EXCL blocks what the acceptance filter matches.
TEST(VciFilter, ExclWithTheAcceptanceFilterOpenBlocksEveryDataFrame) {
  IdFilter f = std_filter(CAN_FILTER_EXCL);
  EXPECT_EQ(f.accept(filter_value(0x000, false)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(f.accept(filter_value(0x7FF, true)), CAN_ACCEPT_REJECT);
  f.set_acceptance(CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE);
  EXPECT_EQ(f.accept(filter_value(0x000, false)), CAN_ACCEPT_PASSEXCL);
}

TEST(VciFilter, AddFilterIdsEntersEveryMatchingValueAndRemoveTakesThemOut) {
  IdFilter f = std_filter();
  ASSERT_EQ(f.add_ids(0x200, 0xFF9), VCI_OK);
  EXPECT_EQ(f.list_size(), 4u);
  for (uint32_t id = 0x100; id <= 0x103; ++id) {
    EXPECT_TRUE(f.listed(filter_value(id, false))) << id;
    EXPECT_FALSE(f.listed(filter_value(id, true))) << id;
  }
  EXPECT_FALSE(f.listed(filter_value(0x104, false)));
  // A mask without the RTR bit lists the data and the remote frame.
  ASSERT_EQ(f.add_ids(filter_value(0x321, false), 0xFFE), VCI_OK);
  EXPECT_EQ(f.list_size(), 6u);
  EXPECT_TRUE(f.listed(filter_value(0x321, true)));
  // Adding a value twice keeps one entry.
  ASSERT_EQ(f.add_ids(filter_value(0x101, false), kStdMask), VCI_OK);
  EXPECT_EQ(f.list_size(), 6u);
  ASSERT_EQ(f.remove_ids(0x200, 0xFF9), VCI_OK);
  EXPECT_EQ(f.list_size(), 2u);
  EXPECT_FALSE(f.listed(filter_value(0x101, false)));
  ASSERT_EQ(f.remove_ids(filter_value(0x321, true), kStdMask), VCI_OK);
  EXPECT_EQ(f.list_size(), 1u);
  EXPECT_TRUE(f.listed(filter_value(0x321, false)));
}

TEST(VciFilter, OnlyTheMaskedBitsOfTheCodeCount) {
  IdFilter f = std_filter();
  ASSERT_EQ(f.add_ids(0xFFFF0000u | filter_value(0x123, false), kStdMask), VCI_OK);
  EXPECT_EQ(f.list_size(), 1u);
  EXPECT_TRUE(f.listed(filter_value(0x123, false)));
  // A relevant bit above the filter value's bits matches no value: nothing is added.
  ASSERT_EQ(f.add_ids(0x1000, 0x1000), VCI_OK);
  EXPECT_EQ(f.list_size(), 1u);
}

TEST(VciFilter, TheElevenBitListHasRoomForAll4096Values) {
  IdFilter f(false, 10, CAN_FILTER_INCL);  // the capacity asked for does not limit it
  ASSERT_EQ(f.add_ids(CAN_ACC_CODE_ALL, CAN_ACC_MASK_ALL), VCI_OK);
  EXPECT_EQ(f.list_size(), 4096u);
  EXPECT_TRUE(f.listed(0x000));
  EXPECT_TRUE(f.listed(0xFFF));
  EXPECT_FALSE(f.listed(0x1000));
  ASSERT_EQ(f.remove_ids(0x001, 0x001), VCI_OK);  // every remote frame
  EXPECT_EQ(f.list_size(), 2048u);
}

TEST(VciFilter, AnExtendedPatternThatDoesNotFitWholeAddsNothing) {
  IdFilter f = ext_filter(6);
  const uint32_t base = filter_value(0x1000000, false);
  ASSERT_EQ(f.add_ids(base, kExtMask & ~0x6u), VCI_OK);  // 2 free bits: 4 values
  EXPECT_EQ(f.list_size(), 4u);
  // 8 values of which 4 are listed: 4 new ones do not fit into the 2 free places.
  EXPECT_EQ(f.add_ids(base, kExtMask & ~0xEu), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(f.list_size(), 4u);
  EXPECT_FALSE(f.listed(base | 0x8));
  // 4 values of which 2 are listed: the 2 new ones fit.
  ASSERT_EQ(f.add_ids(base | 0x4, kExtMask & ~0xAu), VCI_OK);
  EXPECT_EQ(f.list_size(), 6u);
  EXPECT_TRUE(f.listed(base | 0xC));
  EXPECT_TRUE(f.listed(base | 0xE));
  EXPECT_EQ(f.add_ids(filter_value(0x5, false), kExtMask), VCI_E_OUTOFMEMORY);
  // Every 29-bit value at once: 2^30 values.
  IdFilter big = ext_filter(ixxat::kMaxExtListCapacity);
  EXPECT_EQ(big.add_ids(CAN_ACC_CODE_ALL, CAN_ACC_MASK_ALL), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(big.list_size(), 0u);
}

TEST(VciFilter, TheExtendedListHoldsAtMost65536Values) {
  IdFilter f = ext_filter(100'000);
  ASSERT_EQ(f.add_ids(0, kExtMask & ~0xFFFFu), VCI_OK);  // 16 free bits: 65536 values
  EXPECT_EQ(f.list_size(), 65536u);
  EXPECT_EQ(f.add_ids(0x10000, kExtMask), VCI_E_OUTOFMEMORY);
  EXPECT_TRUE(f.listed(0xFFFF));
  EXPECT_FALSE(f.listed(0x10000));
}

TEST(VciFilter, ExtendedRemoveTakesOutEveryMatchingValue) {
  IdFilter f = ext_filter(CAN_FILTER_SIZE_EXT);
  ASSERT_EQ(f.add_ids(filter_value(0x1ABCDE00, false), kExtMask & ~0x1FEu), VCI_OK);  // 256
  ASSERT_EQ(f.add_ids(filter_value(0x00000123, true), kExtMask), VCI_OK);
  EXPECT_EQ(f.list_size(), 257u);
  ASSERT_EQ(f.remove_ids(filter_value(0x1ABCDE80, false), kExtMask & ~0xFEu), VCI_OK);  // 128
  EXPECT_EQ(f.list_size(), 129u);
  EXPECT_TRUE(f.listed(filter_value(0x1ABCDE7F, false)));
  EXPECT_FALSE(f.listed(filter_value(0x1ABCDE80, false)));
  EXPECT_TRUE(f.listed(filter_value(0x123, true)));
  // A pattern with a relevant bit no filter value has removes nothing.
  ASSERT_EQ(f.remove_ids(0x40000000, 0x40000000), VCI_OK);
  EXPECT_EQ(f.list_size(), 129u);
}

TEST(VciFilter, ASingle29BitIdWithTheFullMaskMatchesOneIdentifierAndRtrPair) {
  IdFilter f = ext_filter(CAN_FILTER_SIZE_EXT);
  f.set_acceptance(CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE);
  ASSERT_EQ(f.add_ids(filter_value(0x1ABCDEF0, false), kExtMask), VCI_OK);
  EXPECT_EQ(f.list_size(), 1u);
  EXPECT_EQ(f.accept(filter_value(0x1ABCDEF0, false)), CAN_ACCEPT_FILTER_2);
  EXPECT_EQ(f.accept(filter_value(0x1ABCDEF0, true)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(f.accept(filter_value(0x1ABCDEF1, false)), CAN_ACCEPT_REJECT);
  EXPECT_EQ(f.accept(filter_value(0x0ABCDEF0, false)), CAN_ACCEPT_REJECT);
  f.set_acceptance(filter_value(0x1ABCDEF0, true), kExtMask);
  EXPECT_EQ(f.accept(filter_value(0x1ABCDEF0, true)), CAN_ACCEPT_FILTER_1);
}

TEST(VciFilter, WithoutAListIdCallsRunOutOfMemoryButTheAcceptanceFilterWorks) {
  IdFilter e = ext_filter(0);
  IdFilter s(false, 0, CAN_FILTER_INCL);
  EXPECT_EQ(e.add_ids(filter_value(0x123, false), kExtMask), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(e.remove_ids(filter_value(0x123, false), kExtMask), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(s.add_ids(filter_value(0x123, false), kStdMask), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(s.remove_ids(filter_value(0x123, false), kStdMask), VCI_E_OUTOFMEMORY);
  EXPECT_EQ(e.list_size(), 0u);
  EXPECT_EQ(s.list_size(), 0u);
  EXPECT_FALSE(s.listed(filter_value(0x123, false)));
  e.set_acceptance(filter_value(0x1234567, false), kExtMask);
  EXPECT_EQ(e.accept(filter_value(0x1234567, false)), CAN_ACCEPT_FILTER_1);
  EXPECT_EQ(e.accept(filter_value(0x1234568, false)), CAN_ACCEPT_REJECT);
}

TEST(VciFilter, ADisabledFilterPassesEveryFrameWhateverItsMode) {
  IdFilter f(false, 0, CAN_FILTER_LOCK, /*enabled=*/false);
  f.set_acceptance(CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE);
  for (uint32_t v : {0x000u, 0x247u, 0xFFFu}) {
    EXPECT_EQ(f.accept(v), CAN_ACCEPT_ALWAYS) << v;
  }
  ASSERT_EQ(f.set_mode(CAN_FILTER_EXCL), VCI_OK);
  EXPECT_EQ(f.accept(0x246), CAN_ACCEPT_ALWAYS);
}

TEST(VciFilter, ResetRestoresTheModeOpensTheAcceptanceFilterAndEmptiesTheList) {
  IdFilter f = std_filter(CAN_FILTER_LOCK);
  ASSERT_EQ(f.set_mode(CAN_FILTER_INCL), VCI_OK);
  f.set_acceptance(CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE);
  ASSERT_EQ(f.add_ids(filter_value(0x123, false), kStdMask), VCI_OK);
  f.reset(CAN_FILTER_EXCL);
  EXPECT_EQ(f.mode(), CAN_FILTER_EXCL);
  EXPECT_EQ(f.list_size(), 0u);
  ASSERT_EQ(f.set_mode(CAN_FILTER_INCL), VCI_OK);
  EXPECT_EQ(f.accept(filter_value(0x456, true)), CAN_ACCEPT_FILTER_1);
  IdFilter e = ext_filter(16);
  ASSERT_EQ(e.add_ids(filter_value(0x123, false), kExtMask), VCI_OK);
  e.reset(CAN_FILTER_PASS);
  EXPECT_EQ(e.list_size(), 0u);
  EXPECT_EQ(e.mode(), CAN_FILTER_PASS);
}

TEST(VciFilter, ThePairFiltersElevenAndTwentyNineBitFramesIndependently) {
  FilterPair p{std_filter(CAN_FILTER_LOCK), ext_filter(CAN_FILTER_SIZE_EXT)};
  EXPECT_EQ(p.accept(0x123, false, false), CAN_ACCEPT_REJECT);
  EXPECT_EQ(p.accept(0x123, true, false), CAN_ACCEPT_FILTER_1);
  p.select(true).set_acceptance(filter_value(0x123, true), kExtMask);
  EXPECT_EQ(p.accept(0x123, true, true), CAN_ACCEPT_FILTER_1);
  EXPECT_EQ(p.accept(0x123, true, false), CAN_ACCEPT_REJECT);
  ASSERT_EQ(p.select(false).set_mode(CAN_FILTER_PASS), VCI_OK);
  EXPECT_EQ(p.accept(0x123, false, true), CAN_ACCEPT_ALWAYS);
  EXPECT_EQ(&p.select(false), &p.std);
  EXPECT_EQ(&p.select(true), &p.ext);
}

}  // namespace
}  // namespace canemu::model
