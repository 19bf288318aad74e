// Expected decoder results, shared by the bit-timing decoder tests of each device.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/sim/model_error.hpp"

namespace canemu::model::test_support {

struct Expect {
  uint64_t rate_num;  // exact bit rate = rate_num / rate_den
  uint64_t rate_den;
  uint64_t quantum_ps;
  uint32_t quanta;
  uint32_t sample_point_permille;
  uint32_t sjw;
};

inline void check(const Result<BitTiming>& t, const Expect& e, const std::string& what) {
  ASSERT_TRUE(t) << what << ": " << t.error().message;
  EXPECT_EQ(t->bit_rate(), (BitRate{e.rate_num, e.rate_den})) << what;
  EXPECT_EQ(t->bit_rate().num, e.rate_num) << what << " (fraction reduced)";
  EXPECT_EQ(t->quantum_ps(), e.quantum_ps) << what;
  EXPECT_EQ(t->quanta_per_bit(), e.quanta) << what;
  EXPECT_EQ(t->sample_point_permille(), e.sample_point_permille) << what;
  EXPECT_EQ(t->sjw, e.sjw) << what;
}

}  // namespace canemu::model::test_support
