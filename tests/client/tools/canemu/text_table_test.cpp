// canemu's tables: columns as wide as their content, at least their minimum.
#include "text_table.hpp"

#include <gtest/gtest.h>

namespace canemu::cli {
namespace {

using Align = TextTable::Align;

TEST(TextTable, ColumnsGrowToTheirWidestCellAndKeepTheirMinimum) {
  TextTable t({{"NAME", Align::left, 6}, {"N", Align::right, 3}, {"NOTE"}});
  t.add({"a", "1", "first"});
  t.add({"a-long-name", "12345", ""});
  EXPECT_EQ(t.text(),
            "NAME            N NOTE\n"
            "a               1 first\n"
            "a-long-name 12345\n");
}

TEST(TextTable, IndentGapsAndMissingCells) {
  TextTable t({{"time"}, {"TEC", Align::right, 5}, {"state", Align::left, 0, 2}, {"cause"}}, "  ");
  t.add({"0.5", "130", "error-passive", "counters written"});
  t.add({"1.0"});
  EXPECT_EQ(t.text(),
            "  time   TEC  state         cause\n"
            "  0.5    130  error-passive counters written\n"
            "  1.0\n");
}

}  // namespace
}  // namespace canemu::cli
