#include "method/train/coarse_images.h"

#include <gtest/gtest.h>

#include <vector>

namespace hdr4d::method {
namespace {

TEST(CoarseImages, FactorFollowsTheScheduleAndTheImageSize) {
  EXPECT_EQ(CoarseFactor(1, 0, 200, 200), 1);  // off
  EXPECT_EQ(CoarseFactor(1, 1000, 200, 200), 4);
  EXPECT_EQ(CoarseFactor(500, 1000, 200, 200), 4);
  EXPECT_EQ(CoarseFactor(501, 1000, 200, 200), 2);
  EXPECT_EQ(CoarseFactor(1000, 1000, 200, 200), 2);
  EXPECT_EQ(CoarseFactor(1001, 1000, 200, 200), 1);
  // Any size: the factor need not divide it (the remainder is left out of the step).
  EXPECT_EQ(CoarseFactor(1, 1000, 135, 240), 4);
  EXPECT_EQ(CoarseFactor(600, 1000, 99, 101), 2);
  EXPECT_EQ(CoarseFactor(1, 1000, 3, 100), 2);  // 3 px: 1/4 would leave none
  EXPECT_EQ(CoarseFactor(1, 1000, 1, 100), 1);
}

TEST(CoarseImages, IntrinsicsOfTheReducedImageKeepEveryRay) {
  const PinholeIntrinsics k{
      .fx = 151.0, .fy = 149.0, .cx = 67.25, .cy = 120.5, .width = 135, .height = 241};
  const PinholeIntrinsics c = CoarseIntrinsics(k, 4);
  EXPECT_EQ(c.width, 33);  // floor(135 / 4): 3 columns left out
  EXPECT_EQ(c.height, 60);
  // A point projects to 1/4 of its full-size image coordinates (pixel centres at i + 0.5, so
  // reduced pixel i covers full pixels [4 i, 4 i + 4)).
  const double x = 0.3, y = -0.2, z = 2.0;
  EXPECT_DOUBLE_EQ(c.fx * x / z + c.cx, (k.fx * x / z + k.cx) / 4);
  EXPECT_DOUBLE_EQ(c.fy * y / z + c.cy, (k.fy * y / z + k.cy) / 4);
  EXPECT_EQ(c.Problem(), "");
  const PinholeIntrinsics same = CoarseIntrinsics(k, 1);
  EXPECT_EQ(same.width, 135);
  EXPECT_EQ(same.fx, k.fx);
}

TEST(CoarseImages, BoxReduceAveragesEachBlockInPlace) {
  const int w = 6, h = 4, c = 2;
  std::vector<float> image(w * h * c);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k) image[(y * w + x) * c + k] = float(100 * k + 10 * y + x);
  std::vector<float> reduced = image;
  BoxReduceInPlace(&reduced, w, h, c, 2);
  ASSERT_EQ(reduced.size(), std::size_t(3 * 2 * c));
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      for (int k = 0; k < c; ++k) {
        // The mean of 10 y' + x' over the block: 10 (2 y + 0.5) + 2 x + 0.5.
        EXPECT_FLOAT_EQ(reduced[(y * 3 + x) * c + k], 100 * k + 10 * (2 * y + 0.5f) + 2 * x + 0.5f);
      }
  std::vector<float> same = image;
  BoxReduceInPlace(&same, w, h, c, 1);
  EXPECT_EQ(same, image);
}

// A size the factor does not divide: the blocks cover the top-left floor(W / f) f x floor(H / f) f
// pixels, each averaged as above, and the last columns and rows are not read.
TEST(CoarseImages, BoxReduceLeavesOutTheRemainderOfAnySize) {
  const int w = 7, h = 5, c = 1;
  std::vector<float> image(w * h * c);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) image[y * w + x] = float(10 * y + x);
  // The left-out column 6 and row 4 hold values no block may average in.
  for (int y = 0; y < h; ++y) image[y * w + 6] = 1e6f;
  for (int x = 0; x < w; ++x) image[4 * w + x] = 1e6f;
  std::vector<float> reduced = image;
  BoxReduceInPlace(&reduced, w, h, c, 2);
  ASSERT_EQ(reduced.size(), std::size_t(3 * 2));
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      EXPECT_FLOAT_EQ(reduced[y * 3 + x], 10 * (2 * y + 0.5f) + 2 * x + 0.5f);
  std::vector<float> quarter = image;
  BoxReduceInPlace(&quarter, w, h, c, 4);  // one block: rows 0-3, columns 0-3
  ASSERT_EQ(quarter.size(), std::size_t(1));
  EXPECT_FLOAT_EQ(quarter[0], 10 * 1.5f + 1.5f);
}

}  // namespace
}  // namespace hdr4d::method
