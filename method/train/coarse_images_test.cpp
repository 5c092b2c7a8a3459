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
  EXPECT_EQ(CoarseFactor(1, 1000, 100, 50), 2);  // 50 is not a multiple of 4
  EXPECT_EQ(CoarseFactor(1, 1000, 99, 100), 1);  // nor is 99 of 2
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

}  // namespace
}  // namespace hdr4d::method
