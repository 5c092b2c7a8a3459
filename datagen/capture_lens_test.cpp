// The lenses and the pedestal a synthetic capture's cameras add (datagen/capture_lens.h).
#include "datagen/capture_lens.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing.h"

namespace hdr4d::datagen {
namespace {

// A bright Gaussian spot (sigma 2 px) at continuous pixel coordinates (u, v) on a dark background.
Image Spot(int w, int h, double u, double v) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double d2 = std::pow(x + 0.5 - u, 2) + std::pow(y + 0.5 - v, 2);
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(0.01 + std::exp(-d2 / 8.0));
    }
  return img;
}

// The centre of the spot: pixels weighted by their value above the background.
std::array<double, 2> Centroid(const Image& img) {
  double su = 0, sv = 0, sw = 0;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) {
      const double w = std::max(0.0, img.at(x, y, 1) - 0.01);
      su += w * (x + 0.5);
      sv += w * (y + 0.5);
      sw += w;
    }
  return {su / sw, sv / sw};
}

TEST(CaptureLens, DistortionMovesAPointWhereColmapsRadialModelPutsIt) {
  const PinholeIntrinsics k = PinholeIntrinsics::FromFovX(0.9, 160, 120);
  const CaptureLens lens{.k1 = 0.10, .k2 = 0.03};
  const double u = 145, v = 100;  // near a corner, where the lens moves it most
  const double x = (u - k.cx) / k.fx, y = (v - k.cy) / k.fy, r2 = x * x + y * y;
  const double d = 1 + lens.k1 * r2 + lens.k2 * r2 * r2;
  const double ud = k.fx * d * x + k.cx, vd = k.fy * d * y + k.cy;
  ASSERT_GT(std::hypot(ud - u, vd - v), 1.5);  // the test means something
  const std::array<double, 2> got = Centroid(ApplyCaptureLens(Spot(160, 120, u, v), lens, k));
  EXPECT_NEAR(got[0], ud, 0.2);
  EXPECT_NEAR(got[1], vd, 0.2);
  // The identity lens leaves the render as it is.
  const Image spot = Spot(40, 30, 20, 15);
  const Image same = ApplyCaptureLens(spot, CaptureLens{}, PinholeIntrinsics::FromFovX(0.9, 40, 30));
  for (std::size_t i = 0; i < spot.size(); ++i) ASSERT_EQ(same.data()[i], spot.data()[i]);
}

TEST(CaptureLens, VignettingFallsToOneMinusItsStrengthAtTheCorner) {
  const PinholeIntrinsics k = PinholeIntrinsics::FromFovX(0.9, 81, 61);
  const Image flat(81, 61, 3, Encoding::kLinear, 2.0f);
  const Image out = ApplyCaptureLens(flat, CaptureLens{.vignetting = 0.2}, k);
  EXPECT_NEAR(out.at(40, 30, 0), 2.0, 1e-3);  // the centre pixel
  const double corner_r2 = (std::pow(0.5 - k.cx, 2) + std::pow(0.5 - k.cy, 2)) / (k.cx * k.cx + k.cy * k.cy);
  EXPECT_NEAR(out.at(0, 0, 2), 2.0 * (1 - 0.2 * corner_r2), 1e-4);
  EXPECT_LT(out.at(0, 0, 2), 2.0 * 0.82);
}

TEST(CaptureLens, LensesAreDrawnPerCameraInTheirRangesAndOnlyWhereAsked) {
  const auto both = DrawCaptureLenses("both", 7, 4);
  ASSERT_EQ(both.size(), 4u);
  for (const CaptureLens& l : both) {
    EXPECT_GE(l.k1, 0.03);
    EXPECT_LE(l.k1, 0.10);
    EXPECT_GE(l.k2, 0.0);
    EXPECT_LE(l.k2, 0.03);
    EXPECT_GE(l.vignetting, 0.05);
    EXPECT_LE(l.vignetting, 0.25);
  }
  EXPECT_NE(both[0].k1, both[1].k1);
  // A camera's distortion does not depend on whether vignetting is drawn too.
  const auto distortion = DrawCaptureLenses("distortion", 7, 4);
  EXPECT_EQ(distortion[2].k1, both[2].k1);
  EXPECT_EQ(distortion[2].vignetting, 0.0);
  EXPECT_TRUE(DrawCaptureLenses("none", 7, 4)[3].Identity());
  EXPECT_EQ(testing::ErrorOf([] { DrawCaptureLenses("fisheye", 1, 2); }),
            "datagen: --lenses fisheye: use none, distortion, vignetting or both");
}

TEST(CaptureLens, BlackLevelIsAPedestalWithDarkNoiseAndSaturatesAt255) {
  Image display(200, 100, 1, Encoding::kSrgb, 0.0f);
  for (int x = 0; x < 200; ++x) display.at(x, 99, 0) = 1.0f;
  const Image out = ApplyBlackLevel(display, 16, 1.5, 3);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int y = 0; y < 99; ++y)
    for (int x = 0; x < 200; ++x) {
      const double code = out.at(x, y, 0) * 255.0;
      ASSERT_NEAR(code, std::round(code), 1e-3);  // whole codes
      sum += code;
      sum2 += code * code;
      ++n;
    }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 16, 0.1);
  EXPECT_NEAR(sd, std::sqrt(1.5 * 1.5 + 1.0 / 12), 0.1);  // the noise and the rounding
  for (int x = 0; x < 200; ++x) EXPECT_EQ(out.at(x, 99, 0), 1.0f);
  // The same seed gives the same codes.
  const Image again = ApplyBlackLevel(display, 16, 1.5, 3);
  for (std::size_t i = 0; i < out.size(); ++i) ASSERT_EQ(out.data()[i], again.data()[i]);
  EXPECT_NE(testing::ErrorOf([&] { ApplyBlackLevel(display, -1, 0, 1); }), "");
  EXPECT_NE(testing::ErrorOf([&] { ApplyBlackLevel(display, 16, std::nan(""), 1); }), "");
}

}  // namespace
}  // namespace hdr4d::datagen
