#include "calibration/hdr_fusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/radiometry/crf.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

// The true inverse response of a gamma-2.2 camera, as recovery would produce it.
CameraResponse GammaResponse(int channels) {
  const GammaCrf crf(2.2);
  CameraResponse r;
  r.method = "known";
  std::array<double, kResponseCodes> x;
  for (int z = 0; z < kResponseCodes; ++z) x[z] = crf.Inverse(z / 255.0);
  r.inverse.assign(channels, x);
  return r;
}

Bracket Shoot(const Image& radiance, double t) {
  const GammaCrf crf(2.2);
  Bracket b;
  b.exposure = t;
  b.name = "t" + std::to_string(t);
  b.image = Image(radiance.width(), radiance.height(), radiance.channels(), Encoding::kSrgb);
  for (std::size_t i = 0; i < radiance.size(); ++i)
    b.image.data()[i] = std::round(crf.Apply(radiance.data()[i] * t) * 255.0) / 255.0f;
  return b;
}

Image Scene(int w, int h) {
  Image radiance(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)  // a horizontal ramp over ~8 stops
        radiance.at(x, y, c) = static_cast<float>(0.02 * std::exp2(8.0 * x / (w - 1)) * (1 + 0.1 * c));
  return radiance;
}

TEST(HdrFusion, StaticSceneMatchesTheRadiance) {
  const Image radiance = Scene(80, 20);
  const std::vector<Bracket> brackets = {Shoot(radiance, 0.125), Shoot(radiance, 1), Shoot(radiance, 8)};
  const FusionResult r = FuseBrackets(brackets, GammaResponse(3));
  EXPECT_LT(r.motion_fraction, 0.01);
  double worst = 0;
  for (std::size_t i = 0; i < radiance.size(); ++i)
    worst = std::max(worst, std::abs(std::log(double(r.hdr.data()[i]) / radiance.data()[i])));
  EXPECT_LT(worst, 0.1);
  EXPECT_GT(r.dynamic_range_stops, 7.0);
}

TEST(HdrFusion, MovingObjectFallsBackToTheBestExposedBracket) {
  const Image radiance = Scene(80, 20);
  std::vector<Bracket> brackets = {Shoot(radiance, 0.125), Shoot(radiance, 1), Shoot(radiance, 8)};
  // A dark object (radiance 0.05) sits at x in [30, 40) only while the long bracket is taken.
  Image moved = radiance;
  for (int y = 0; y < 20; ++y)
    for (int x = 30; x < 40; ++x)
      for (int c = 0; c < 3; ++c) moved.at(x, y, c) = 0.05f;
  brackets[2] = Shoot(moved, 8);
  FusionOptions options;
  const FusionResult with = FuseBrackets(brackets, GammaResponse(3), options);
  options.detect_motion = false;
  const FusionResult without = FuseBrackets(brackets, GammaResponse(3), options);
  auto error_in_object = [&](const Image& hdr) {
    double worst = 0;
    for (int y = 0; y < 20; ++y)
      for (int x = 30; x < 40; ++x)
        worst = std::max(worst, std::abs(std::log(double(hdr.at(x, y, 1)) / radiance.at(x, y, 1))));
    return worst;
  };
  EXPECT_GT(error_in_object(without.hdr), 0.25);  // the ghost is there without detection
  EXPECT_LT(error_in_object(with.hdr), 0.1);      // and gone with it
  EXPECT_GT(with.motion_fraction, 0.1);
  EXPECT_LT(with.motion_fraction, 0.3);
}

TEST(HdrFusion, BadBracketsAreClearErrors) {
  const Image radiance = Scene(16, 8);
  std::vector<Bracket> brackets = {Shoot(radiance, 1), Shoot(Scene(8, 8), 2)};
  EXPECT_NE(testing::ErrorOf([&] { FuseBrackets(brackets, GammaResponse(3)); }).find("differs"),
            std::string::npos);
  brackets = {Shoot(radiance, 1), Shoot(radiance, -2)};
  EXPECT_NE(testing::ErrorOf([&] { FuseBrackets(brackets, GammaResponse(3)); }).find("not a positive"),
            std::string::npos);
}

}  // namespace
}  // namespace hdr4d
