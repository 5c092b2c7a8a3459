#include "datagen/dynamic_range.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hdr4d::datagen {
namespace {

Image Gray(const std::vector<float>& luminances) {
  Image image(static_cast<int>(luminances.size()), 1, 3);
  for (int x = 0; x < image.width(); ++x)
    for (int c = 0; c < 3; ++c) image.at(x, 0, c) = luminances[x];
  return image;
}

TEST(DynamicRange, PercentilesOfALogUniformRamp) {
  // 10001 values log-uniform from 1e-3 to 1e3: p0.1 ~ 1e-3 * 1e6^0.001, p99.9 ~ 1e3 / 1e6^0.001.
  std::vector<float> values;
  for (int i = 0; i <= 10000; ++i)
    values.push_back(static_cast<float>(1e-3 * std::pow(1e6, i / 1e4)));
  LuminanceHistogram h;
  h.Add(Gray(values));
  const DynamicRange r = h.Summary();
  const double step = std::pow(1e6, 0.001);
  EXPECT_NEAR(r.p001 / (1e-3 * step), 1.0, 0.012);
  EXPECT_NEAR(r.p999 / (1e3 / step), 1.0, 0.012);
  EXPECT_NEAR(r.ratio / (1e6 / step / step), 1.0, 0.025);
  EXPECT_FLOAT_EQ(r.max, 1e3f);
  EXPECT_NEAR(r.min_positive, 1e-3, 1e-9);
  EXPECT_EQ(r.pixels, 10001);
  EXPECT_EQ(r.zero_fraction, 0.0);
}

TEST(DynamicRange, ZerosAreCountedButLeftOutOfThePercentiles) {
  LuminanceHistogram h;
  h.Add(Gray({0, 0, 0, 2, 2, 2, 2}));
  const DynamicRange r = h.Summary();
  EXPECT_NEAR(r.zero_fraction, 3.0 / 7.0, 1e-12);
  EXPECT_NEAR(r.p001, 2.0, 1e-9);  // clamped to the exact extremes
  EXPECT_NEAR(r.p999, 2.0, 1e-9);
  EXPECT_NEAR(r.ratio, 1.0, 1e-9);
}

TEST(DynamicRange, EmptyOrBlackGivesZeroRatio) {
  LuminanceHistogram h;
  EXPECT_EQ(h.Summary().ratio, 0.0);
  h.Add(Gray({0, 0}));
  EXPECT_EQ(h.Summary().ratio, 0.0);
  EXPECT_EQ(h.Summary().zero_fraction, 1.0);
}

TEST(DynamicRange, MergeEqualsAddingEverything) {
  LuminanceHistogram a, b, all;
  a.Add(Gray({0.01f, 0.5f, 3.0f}));
  b.Add(Gray({100.0f, 0.0f, 0.02f}));
  all.Add(Gray({0.01f, 0.5f, 3.0f, 100.0f, 0.0f, 0.02f}));
  a.Merge(b);
  EXPECT_EQ(a.Summary().p001, all.Summary().p001);
  EXPECT_EQ(a.Summary().p999, all.Summary().p999);
  EXPECT_EQ(a.Summary().max, 100.0);
  EXPECT_NEAR(a.Summary().min_positive, 0.01, 1e-6);
}

TEST(DynamicRange, UsesRec709Luminance) {
  Image green(1, 1, 3);
  green.at(0, 0, 1) = 1.0f;
  LuminanceHistogram h;
  h.Add(green);
  EXPECT_NEAR(h.Summary().max, 0.7152, 1e-6);
}

}  // namespace
}  // namespace hdr4d::datagen
