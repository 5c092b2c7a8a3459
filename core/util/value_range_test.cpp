#include "core/util/value_range.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

namespace hdr4d {
namespace {

TEST(ValueRange, DescribesEachKindOfRangeOneWay) {
  EXPECT_EQ(ValueRange::Integer(1).Describe(), "an integer >= 1");
  EXPECT_EQ(ValueRange::Integer(0, std::numeric_limits<std::int64_t>::max()).Describe(),
            "an integer >= 0");
  EXPECT_EQ(ValueRange::Integer(1, 1 << 16).Describe(), "an integer in [1, 65536]");
  EXPECT_EQ(ValueRange::Integer(0, std::int64_t{1} << 40).Describe(),
            "an integer in [0, 1099511627776]");
  EXPECT_EQ(ValueRange::Integer(1, 100'000'000).Describe(), "an integer in [1, 100000000]");
  EXPECT_EQ(ValueRange::Real(0, 1e6).Describe(), "a number in [0, 1e+06]");
  EXPECT_EQ(ValueRange::Real(0, std::numeric_limits<double>::max(), true).Describe(), "a number > 0");
  EXPECT_EQ(ValueRange::Real(1e-30, 1).Bounds(), "in [1e-30, 1]");
  EXPECT_EQ(ValueRange::AnyReal().Describe(), "a number");
}

TEST(ValueRange, ContainsOnlyFiniteValuesWithinItsBounds) {
  const ValueRange weight = ValueRange::Real(0, 1e6);
  EXPECT_TRUE(weight.Contains(0));
  EXPECT_TRUE(weight.Contains(1e6));  // the help's "[0, 1e+06]" includes its ends
  EXPECT_FALSE(weight.Contains(1e6 * (1 + 1e-15)));
  EXPECT_FALSE(weight.Contains(-1e-300));
  EXPECT_FALSE(weight.Contains(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(ValueRange::AnyReal().Contains(std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(ValueRange::Real(0, 1, /*open_min=*/true).Contains(0));
  EXPECT_TRUE(ValueRange::Integer(1).Contains(2147483647));
  EXPECT_FALSE(ValueRange::Integer(1).Contains(2147483648.0));
  EXPECT_FALSE(ValueRange::Integer(0, 10).Contains(2.5));
}

}  // namespace
}  // namespace hdr4d
