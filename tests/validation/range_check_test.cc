// The one helper every Validate() reports a bad value with: field, value,
// range; NaN and infinities are never in range.
#include "common/validation/range_check.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace cornerpose {
namespace {

TEST(CheckRangeTest, InsideAndOnTheBoundsIsOk) {
  EXPECT_TRUE(CheckRange("f", 0.0, 0.0, 1.0).ok());
  EXPECT_TRUE(CheckRange("f", 1.0, 0.0, 1.0).ok());
  EXPECT_TRUE(CheckRange("n", 3, 1, 3).ok());
}

TEST(CheckRangeTest, OutsideNamesFieldValueAndRange) {
  absl::Status s = CheckRange("selection.min_score", 1.5, 0.0, 1.0);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message(), "selection.min_score must be in [0, 1], got 1.5");
  EXPECT_EQ(CheckRange("iterations", 21, 0, 20).message(), "iterations must be in [0, 20], got 21");
  EXPECT_FALSE(CheckRange("f", std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0).ok());
  EXPECT_FALSE(CheckRange("f", std::numeric_limits<double>::infinity(), 0.0,
                          std::numeric_limits<double>::infinity())
                   .ok());
}

TEST(CheckPositiveTest, ZeroIsOutAndTheUpperBoundIsSaidWhenThereIsOne) {
  EXPECT_TRUE(CheckPositive("f", 1e-9).ok());
  EXPECT_EQ(CheckPositive("motion.linear_speed_m_s", 3.0, 1.0).message(),
            "motion.linear_speed_m_s must be > 0 and <= 1, got 3");
  EXPECT_EQ(CheckPositive("fps", 0.0).message(), "fps must be > 0, got 0");
  EXPECT_FALSE(CheckPositive("f", -1.0).ok());
}

TEST(CheckAtLeastTest, BelowIsOut) {
  EXPECT_TRUE(CheckAtLeast("margin", 0.0, 0.0).ok());
  EXPECT_EQ(CheckAtLeast("margin", -0.1, 0.0).message(), "margin must be >= 0, got -0.1");
}

TEST(QuotedNameTest, EscapesAndShortensWhatACallerNamed) {
  EXPECT_EQ(QuotedName("cell_1"), "'cell_1'");
  EXPECT_EQ(QuotedName(std::string("c\xff\nx\0y", 6)), "'c\\xff\\nx\\x00y'");
  const std::string quoted = QuotedName(std::string(10000, 'a'));
  EXPECT_LT(quoted.size(), 100u);
  EXPECT_EQ(quoted, "'" + std::string(64, 'a') + "...' (10000 bytes)");
}

}  // namespace
}  // namespace cornerpose
