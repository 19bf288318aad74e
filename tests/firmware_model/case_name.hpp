// Parameterised suites over a table of cases: each case carries the `name` its test is listed by
// (`Suite/Fixture.Test/<name>`), so a failure names the row.
#pragma once

#include <gtest/gtest.h>

#include <string>

namespace canemu::model::test_support {

struct CaseName {
  template <class Case>
  std::string operator()(const ::testing::TestParamInfo<Case>& c) const {
    return c.param.name;
  }
};

}  // namespace canemu::model::test_support
