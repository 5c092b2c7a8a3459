#include "calibration/undistort.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hdr4d {
namespace {

// A smooth pattern of the pinhole camera's normalised coordinates.
double Pattern(double x, double y) { return 0.5 + 0.4 * std::sin(6 * x) * std::cos(5 * y); }

TEST(Undistort, RestoresThePinholeImage) {
  const BundleIntrinsics k{80, 50, 40, -0.2, 0.05};
  const int w = 100, h = 80;
  // The distorted image: pixel (u, v) shows the pinhole point whose distortion lands there
  // (inverted by fixed-point iteration).
  Image distorted(w, h, 1);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const double xd = (u + 0.5 - k.cx) / k.f, yd = (v + 0.5 - k.cy) / k.f;
      double x = xd, y = yd;
      for (int i = 0; i < 50; ++i) {
        const double r2 = x * x + y * y;
        const double d = 1 + k.k1 * r2 + k.k2 * r2 * r2;
        x = xd / d;
        y = yd / d;
      }
      distorted.at(u, v, 0) = static_cast<float>(Pattern(x, y));
    }
  const Image out = Undistort(distorted, k);
  double worst = 0, worst_distorted = 0;
  for (int v = 10; v < h - 10; ++v)
    for (int u = 10; u < w - 10; ++u) {
      const double truth = Pattern((u + 0.5 - k.cx) / k.f, (v + 0.5 - k.cy) / k.f);
      worst = std::max(worst, std::abs(out.at(u, v, 0) - truth));
      worst_distorted = std::max(worst_distorted, std::abs(distorted.at(u, v, 0) - truth));
    }
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(worst_distorted, 0.05);  // the distortion was visible before
}

TEST(Undistort, MaxDistortionAtTheCorner) {
  const BundleIntrinsics k{100, 50, 50, 0.1, 0};
  // Corner at r = sqrt(0.5^2 + 0.5^2) in normalised units: displacement f r^3 k1.
  const double r = std::sqrt(0.5);
  EXPECT_NEAR(MaxDistortionPixels(k, 100, 100), 100 * r * r * r * 0.1, 1e-9);
  EXPECT_EQ(MaxDistortionPixels(BundleIntrinsics{100, 50, 50, 0, 0}, 100, 100), 0);
}

}  // namespace
}  // namespace hdr4d
